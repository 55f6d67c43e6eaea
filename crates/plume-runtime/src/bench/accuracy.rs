//! Speed against accuracy: every integrator at several step sizes, its position error at the
//! end of a fixed duration against a reference, its time per step, and the observed order.
//!
//! The reference is the closed form where one exists (the Exact integrator in f64: exact at any
//! step) and otherwise the CPU reference's RK4 in f64 at 1/64 of the smallest step. Only the
//! particles spawned at step 0 are followed, since they start identically at every step size;
//! rate emitters are turned into a burst of rate × 0.1 s (at least 1) for the measurement.
//! Particles alive at the end in both runs are compared.

use std::collections::HashMap;
use std::time::Instant;

use glam::DVec3;
use plume_compiler::emitter::Amount;
use plume_compiler::passes::integrator::exact_blocker;
use plume_compiler::reference::ReferenceSim;
use plume_compiler::{compile_effect, CompileError, EffectSpec, Integrator};

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sim::effect::Effect as RunningEffect;

/// What to measure.
#[derive(Clone, Debug)]
pub struct AccuracyPlan {
    /// Integrators to measure (Exact is skipped where it is not allowed).
    pub integrators: Vec<Integrator>,
    /// Step sizes (s); each must divide `duration` into a whole number of steps.
    pub dts: Vec<f64>,
    /// Simulated time (s) at which errors are measured.
    pub duration: f64,
}

/// One integrator at one step size.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyRow {
    /// The integrator.
    pub integrator: Integrator,
    /// The step (s).
    pub dt: f64,
    /// Steps run.
    pub steps: u64,
    /// Largest position error over the compared particles (m).
    pub max_error: f64,
    /// Root mean square position error (m).
    pub rms_error: f64,
    /// Wall time per step (s) of the engine that ran it.
    pub seconds_per_step: f64,
    /// Observed order against the next larger step of the same integrator:
    /// log2(e(h') / e(h)) / log2(h' / h), from max errors.
    pub order: Option<f64>,
    /// Particles compared.
    pub compared: usize,
}

/// What the errors are measured against.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceKind {
    /// The closed form (Exact in f64).
    ClosedForm,
    /// RK4 in f64 at this step.
    Rk4(f64),
}

/// Where the integrators run.
pub enum Engine<'g> {
    /// The GPU (f32).
    Gpu(&'g Gpu),
    /// The CPU reference (f64): the integrator's own error without f32 rounding.
    Cpu,
}

/// Makes the measured copy of an effect: bursts only (see the module docs).
pub fn measured_effect(effect: &EffectSpec) -> EffectSpec {
    let mut e = effect.clone();
    let params = e.params.clone();
    for em in &mut e.emitters {
        let (burst, rate) = (em.burst.value(&params), em.rate.value(&params));
        em.burst = Amount::Value(match burst == 0 && rate > 0.0 {
            true => ((rate * 0.1).round() as u32).max(1),
            false => burst,
        });
        em.rate = Amount::Value(0.0);
        (em.start, em.duration, em.every, em.cycles) = (0.0, None, None, None);
    }
    let total: u64 = e
        .emitters
        .iter()
        .map(|em| u64::from(em.burst.value(&params)))
        .sum();
    e.capacity = e.capacity.max(total.min(u64::from(u32::MAX)) as u32);
    e
}

fn compile(
    effect: &EffectSpec,
    integrator: Integrator,
    dt: f64,
) -> Result<plume_compiler::CompiledEffect, RuntimeError> {
    let mut e = effect.clone();
    e.integrator = integrator;
    e.dt = dt;
    // The sweep compares stepping integrators, so Exact steps too: a stateless effect would
    // compute the closed form once, whatever dt (tests/stateless.rs measures that).
    e.state = plume_compiler::schema::State::Stateful;
    // The sweep measures each integrator as it is, at steps the budget was not stated for:
    // the budget (checked on its own first) neither chooses nor calibrates here.
    e.accuracy = None;
    compile_effect(&e, "").map_err(|err| match err {
        CompileError::Invalid(d) => RuntimeError::Output(format!("{integrator:?} at dt {dt}: {d}")),
        CompileError::Internal(i) => RuntimeError::Output(i.to_string()),
    })
}

fn steps_for(duration: f64, dt: f64) -> Result<u64, RuntimeError> {
    let n = (duration / dt).round();
    if n < 1.0 || ((n * dt - duration).abs() > 1e-9 * duration) {
        return Err(RuntimeError::Output(format!(
            "dt {dt} does not divide the duration {duration} s into whole steps"
        )));
    }
    Ok(n as u64)
}

/// The reference positions at `duration`, by id, and what they are.
pub fn reference(
    effect: &EffectSpec,
    plan: &AccuracyPlan,
) -> Result<(HashMap<u32, DVec3>, ReferenceKind), RuntimeError> {
    let finest = plan.dts.iter().copied().fold(f64::INFINITY, f64::min);
    let probe = compile(effect, Integrator::Auto, finest)?;
    let (integrator, dt, kind) = if exact_blocker(&probe.ir, &[]).is_none() {
        (Integrator::Exact, finest, ReferenceKind::ClosedForm)
    } else {
        (
            Integrator::Rk4,
            finest / 64.0,
            ReferenceKind::Rk4(finest / 64.0),
        )
    };
    let c = compile(effect, integrator, dt)?;
    let mut sim = ReferenceSim::new(&c.ir);
    if let Some(burst) = effect.sample_burst {
        sim.burst(burst).map_err(RuntimeError::Output)?;
    }
    sim.run(steps_for(plan.duration, dt)?);
    Ok((
        sim.records()
            .into_iter()
            .map(|r| (r.id, r.position))
            .collect(),
        kind,
    ))
}

/// The largest and the root-mean-square of `errors` (0 and 0 when empty).
fn max_and_rms(errors: &[f64]) -> (f64, f64) {
    let max = errors.iter().copied().fold(0.0, f64::max);
    let rms = if errors.is_empty() {
        0.0
    } else {
        (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
    };
    (max, rms)
}

/// Runs `steps` of `c` on `engine`, after firing `sample_burst` (a group fed by events alone:
/// `EffectSpec::sample_burst`); returns the live particles and the wall time of the steps.
fn timed_run(
    engine: &Engine,
    c: plume_compiler::CompiledEffect,
    steps: u64,
    sample_burst: Option<plume_compiler::bursts::Burst>,
) -> Result<(Vec<plume_compiler::reference::ParticleRecord>, f64), RuntimeError> {
    Ok(match engine {
        Engine::Gpu(gpu) => {
            // Warm up: drivers compile shaders on first dispatch; keep that out of the timing.
            RunningEffect::new(gpu, c.clone())?.run(1, |_| {})?;
            let mut sim = RunningEffect::new(gpu, c)?;
            if let Some(burst) = sample_burst {
                sim.burst(0, burst)?;
            }
            let start = Instant::now();
            sim.run(steps, |_| {})?;
            let s = start.elapsed().as_secs_f64();
            (sim.records()?, s)
        }
        Engine::Cpu => {
            let mut sim = ReferenceSim::new(&c.ir);
            if let Some(burst) = sample_burst {
                sim.burst(burst).map_err(RuntimeError::Output)?;
            }
            let start = Instant::now();
            sim.run(steps);
            let s = start.elapsed().as_secs_f64();
            (sim.records(), s)
        }
    })
}

/// Runs the plan; `progress(done, total)` after each run.
pub fn measure(
    engine: &Engine,
    effect: &EffectSpec,
    plan: &AccuracyPlan,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<AccuracyRow>, ReferenceKind), RuntimeError> {
    let effect = measured_effect(effect);
    let (truth, kind) = reference(&effect, plan)?;
    let mut dts = plan.dts.clone();
    dts.sort_by(|a, b| b.total_cmp(a));
    let total = plan.integrators.len() * dts.len();
    let mut rows = Vec::new();
    let mut done = 0;
    for &integrator in &plan.integrators {
        let mut previous: Option<(f64, f64)> = None;
        for &dt in &dts {
            done += 1;
            let c = match compile(&effect, integrator, dt) {
                Ok(c) => c,
                // Exact is not allowed for this effect: skip it rather than fail the report.
                Err(_) if integrator == Integrator::Exact => continue,
                Err(e) => return Err(e),
            };
            let steps = steps_for(plan.duration, dt)?;
            let (records, seconds) = timed_run(engine, c, steps, effect.sample_burst)?;
            let errors: Vec<f64> = records
                .iter()
                .filter_map(|r| truth.get(&r.id).map(|t| (r.position - *t).length()))
                .collect();
            let (max_error, rms_error) = max_and_rms(&errors);
            let order = previous.and_then(|(h_prev, e_prev)| {
                (e_prev > 0.0 && max_error > 0.0)
                    .then(|| (e_prev / max_error).log2() / (h_prev / dt).log2())
            });
            previous = Some((dt, max_error));
            rows.push(AccuracyRow {
                integrator,
                dt,
                steps,
                max_error,
                rms_error,
                seconds_per_step: seconds / steps as f64,
                order,
                compared: errors.len(),
            });
            progress(done, total);
        }
    }
    Ok((rows, kind))
}

/// Indices of the rows on the Pareto front: no other row is both faster and more accurate.
pub fn pareto_front(rows: &[AccuracyRow]) -> Vec<usize> {
    (0..rows.len())
        .filter(|&i| {
            !rows.iter().enumerate().any(|(j, r)| {
                j != i
                    && r.seconds_per_step <= rows[i].seconds_per_step
                    && r.max_error <= rows[i].max_error
                    && (r.seconds_per_step < rows[i].seconds_per_step
                        || r.max_error < rows[i].max_error)
            })
        })
        .collect()
}

/// One row of the baked-field sweep: the baked run's position error against the same effect
/// with every force evaluated per particle.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldRow {
    /// Nodes per axis (the same on every axis).
    pub resolution: u32,
    /// The sampling filter.
    pub filter: plume_compiler::field::Filter,
    /// Largest position error over the compared particles (m).
    pub max_error: f64,
    /// RMS position error (m).
    pub rms_error: f64,
    /// Wall time per step (s), bake included.
    pub seconds_per_step: f64,
}

/// The baked-field sweep: for each resolution (n³ nodes over the file's field bounds) and
/// filter, run the effect with the field baked (every step when a force changes with time)
/// and compare the positions after `duration` with the run where every force is evaluated.
/// Returns the rows and the evaluated run's wall time per step.
pub fn field_sweep(
    engine: &Engine,
    effect: &EffectSpec,
    resolutions: &[u32],
    duration: f64,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<FieldRow>, f64), RuntimeError> {
    use plume_compiler::field::{Field, Filter, Refresh};
    let effect = measured_effect(effect);
    let Field::Baked { min, max, .. } = effect.field.clone() else {
        return Err(RuntimeError::Output(
            "the sweep needs the grid's bounds: give the effect a field: Baked(resolution: ..., min: ..., max: ...)".into(),
        ));
    };
    let time_dependent = effect
        .forces
        .iter()
        .any(|f| matches!(f, plume_compiler::forces::Force::Wind(w) if w.noise != 0.0));
    let refresh = if time_dependent {
        Refresh::EveryStep
    } else {
        Refresh::Once
    };
    let steps = steps_for(duration, effect.dt)?;
    let run = |e: &EffectSpec| -> Result<(Vec<(u32, DVec3)>, f64), RuntimeError> {
        let c = compile_effect(e, "").map_err(|err| RuntimeError::Output(err.to_string()))?;
        let (records, seconds) = timed_run(engine, c, steps, effect.sample_burst)?;
        Ok((
            records.iter().map(|r| (r.id, r.position)).collect(),
            seconds / steps as f64,
        ))
    };
    let mut evaluated = effect.clone();
    evaluated.field = Field::Evaluated;
    let (truth, evaluated_seconds) = run(&evaluated)?;
    let truth: HashMap<u32, DVec3> = truth.into_iter().collect();
    let total = resolutions.len() * 2;
    let mut rows = Vec::new();
    for &resolution in resolutions {
        for filter in [Filter::Nearest, Filter::Trilinear] {
            let mut baked = effect.clone();
            baked.field = Field::Baked {
                resolution: (resolution, resolution, resolution),
                min,
                max,
                filter,
                refresh,
            };
            let (positions, seconds_per_step) = run(&baked)?;
            let errors: Vec<f64> = positions
                .iter()
                .filter_map(|(id, x)| truth.get(id).map(|t| (*x - *t).length()))
                .collect();
            let (max_error, rms_error) = max_and_rms(&errors);
            rows.push(FieldRow {
                resolution,
                filter,
                max_error,
                rms_error,
                seconds_per_step,
            });
            progress(rows.len(), total);
        }
    }
    Ok((rows, evaluated_seconds))
}
