//! `plume bench` for an effect with groups and events: what events cost. The effect is scaled
//! to about N slots (every group's capacity and the spawning groups' bursts and rates by the
//! same factor), run to its steady state, and its steps timed; then the same groups with the
//! same live particles and no events (each filled by one burst that never dies) are timed in
//! the same run. The difference is the events' cost: the parents' records, the ordering of
//! their firings, the children's spawns. Each stream's ordering is also timed alone.

use plume_compiler::emitter::Amount;
use plume_compiler::graph::{compile_graph, group_effects, CompiledGraph, CompiledGroup};
use plume_compiler::schema::{EffectSpec, Emitter, Shape, Vec3, Velocity};
use plume_compiler::{compile_effect, CompileError};

use crate::bench::profile::{profiled, DispatchTime};
use crate::bench::timer::{median_after_warmup, PassTimer, TimingSource};
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
// The running effect; `Effect` here is the file's schema.
use crate::sim::effect::Effect as RunningEffect;

/// What was measured.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphBench {
    /// Adapter description.
    pub adapter: String,
    /// The factor every capacity, burst and rate was scaled by.
    pub scale: f64,
    /// Steps run before timing.
    pub warm_steps: u64,
    /// Steps per timed pass.
    pub steps: u32,
    /// Per group: name, capacity and live particles after the timed steps.
    pub groups: Vec<(String, u32, u64)>,
    /// Seconds per step of the effect with its events.
    pub seconds_per_step: f64,
    /// Seconds per step of the same groups with the same live particles and no events.
    pub plain_seconds_per_step: f64,
    /// Firings per step during the timed steps (records put in order and turned into children).
    pub firings_per_step: f64,
    /// Children requested per step (spawned or dropped).
    pub children_per_step: f64,
    /// Seconds of each stream's ordering of its firings alone (the last step's), in stream
    /// order.
    pub order_seconds: Vec<f64>,
    /// Timestamps or wall clock.
    pub timing: TimingSource,
    /// With `profile`: each dispatch's time a step with events, then without
    /// ([`DispatchTime`]: `s0.` is event stream 0, `g1.` group 1).
    pub dispatches: (Vec<DispatchTime>, Vec<DispatchTime>),
}

impl GraphBench {
    /// Seconds per step the events add.
    pub fn event_seconds_per_step(&self) -> f64 {
        self.seconds_per_step - self.plain_seconds_per_step
    }

    /// Firings handled per second of the events' added time.
    pub fn firings_per_second(&self) -> f64 {
        self.firings_per_step / self.event_seconds_per_step().max(1e-12)
    }
}

fn invalid(e: CompileError) -> RuntimeError {
    RuntimeError::Output(format!("the benchmark's copy of the effect: {e}"))
}

/// `effect` with every group's capacity, and the bursts and rates of the groups that spawn on
/// their own, multiplied by `scale`.
pub fn scaled(effect: &EffectSpec, scale: f64) -> EffectSpec {
    let cap = |c: u32| ((f64::from(c) * scale).round() as u32).max(1);
    let params = &effect.params;
    let emit = |emitters: &mut Vec<Emitter>| {
        for e in emitters {
            e.burst = Amount::Value((f64::from(e.burst.value(params)) * scale).round() as u32);
            e.rate = Amount::Value(e.rate.value(params) * scale);
        }
    };
    let mut e = effect.clone();
    e.capacity = cap(e.capacity);
    emit(&mut e.emitters);
    for g in &mut e.groups {
        g.capacity = cap(g.capacity);
        emit(&mut g.emitters);
    }
    e
}

/// Times `steps` steps `repeats` times (after one untimed batch) and returns the median
/// seconds per step.
fn per_step(
    sim: &mut RunningEffect,
    timer: &PassTimer<'_>,
    steps: u32,
    repeats: u32,
) -> Result<f64, RuntimeError> {
    Ok(median_after_warmup(repeats, || sim.time_steps(timer, steps))? / f64::from(steps))
}

/// Events requested per fed group so far (spawned and dropped: a fed group spawns only from
/// its events).
fn requested(sim: &RunningEffect, fed: &[bool]) -> Result<Vec<u64>, RuntimeError> {
    (0..fed.len())
        .map(|g| {
            let t = sim.group_totals(g)?;
            Ok(if fed[g] { t.spawned + t.dropped } else { 0 })
        })
        .collect()
}

/// Benchmarks `effect` (a graph) scaled to about `particles` slots: `warm_steps` untimed, then
/// batches of `steps` timed; with `profile`, one batch more of each with every dispatch timed.
pub fn bench_graph(
    gpu: &Gpu,
    effect: &EffectSpec,
    particles: u32,
    warm_steps: u64,
    steps: u32,
    profile: bool,
) -> Result<GraphBench, RuntimeError> {
    let total: u64 = u64::from(effect.capacity)
        + effect
            .groups
            .iter()
            .map(|g| u64::from(g.capacity))
            .sum::<u64>();
    let scale = f64::from(particles) / total as f64;
    let big = scaled(effect, scale);
    let graph = compile_graph(&big, "").map_err(invalid)?;
    let names: Vec<String> = graph.groups.iter().map(|g| g.name.clone()).collect();
    // Children per firing, per group fed by events (the mean where several events feed it).
    let mut per_firing = vec![(0u64, 0u64); names.len()];
    for s in &graph.streams {
        per_firing[s.child].0 += u64::from(s.count);
        per_firing[s.child].1 += 1;
    }
    let fed: Vec<bool> = per_firing.iter().map(|p| p.1 > 0).collect();
    let timer = PassTimer::new(gpu);
    let mut sim = RunningEffect::from_graph(gpu, graph)?;
    sim.run(warm_steps, |_| {})?;
    let repeats = 3;
    let before = requested(&sim, &fed)?;
    let seconds_per_step = per_step(&mut sim, &timer, steps, repeats)?;
    let after = requested(&sim, &fed)?;
    // One untimed batch and `repeats` timed ones ran.
    let timed_steps = f64::from(steps) * f64::from(repeats + 1);
    let (mut children, mut firings) = (0.0, 0.0);
    for g in (0..names.len()).filter(|&g| fed[g]) {
        let n = (after[g] - before[g]) as f64;
        children += n;
        firings += n / (per_firing[g].0 as f64 / per_firing[g].1 as f64);
    }
    let order_seconds = sim.time_orders(&timer, repeats)?;
    let with_events = match profile {
        true => profiled(gpu, steps, |n| sim.time_steps(&timer, n))?,
        false => Vec::new(),
    };
    let mut groups = Vec::new();
    for (g, name) in names.iter().enumerate() {
        let cap = sim.group_compiled(g)?.ir.capacity;
        groups.push((name.clone(), cap, sim.group_totals(g)?.alive));
    }
    // The same groups, the same live particles, no events.
    let plain = plain_graph(&big, &groups)?;
    let mut plain_sim = RunningEffect::from_graph(gpu, plain)?;
    plain_sim.run(1, |_| {})?;
    let plain_seconds_per_step = per_step(&mut plain_sim, &timer, steps, repeats)?;
    let without = match profile {
        true => profiled(gpu, steps, |n| plain_sim.time_steps(&timer, n))?,
        false => Vec::new(),
    };
    for (g, (name, _, alive)) in groups.iter().enumerate() {
        let left = plain_sim.group_totals(g)?.alive;
        if left != *alive {
            return Err(RuntimeError::Output(format!(
                "the event-free copy of group {name} kept {left} of its {alive} particles alive (a kill volume reached them)"
            )));
        }
    }
    Ok(GraphBench {
        adapter: gpu.describe(),
        scale,
        warm_steps,
        steps,
        groups,
        seconds_per_step,
        plain_seconds_per_step,
        firings_per_step: firings / timed_steps,
        children_per_step: children / timed_steps,
        order_seconds,
        timing: timer.source(),
        dispatches: (with_events, without),
    })
}

/// Where the event-free copies' particles sit: a kilometre up, so that in the few seconds
/// timed they reach no collider or kill volume near the scene (the update runs the same
/// collision and kill tests on them, which all miss).
const PLAIN_CENTRE: Vec3 = Vec3(0.0, 1000.0, 0.0);

/// The event-free copies' lifetime (s): a day.
const PLAIN_LIFETIME: f64 = 86_400.0;

/// One plain group per group of `big`: its forces, integrator, colliders, kills and look, with
/// `alive` particles from one burst that outlives the run, and no events. (A group fed by
/// events may also store its particles' spawn step or tint, which the copy does not: that is
/// part of what events cost.)
fn plain_graph(
    big: &EffectSpec,
    groups: &[(String, u32, u64)],
) -> Result<CompiledGraph, RuntimeError> {
    let mut out = Vec::new();
    for (e, (name, cap, alive)) in group_effects(big).into_iter().zip(groups) {
        let mut plain = e;
        plain.events.clear();
        plain.groups.clear();
        plain.capacity = *cap;
        plain.emitters = vec![Emitter {
            burst: Amount::Value((*alive).min(u64::from(*cap)) as u32),
            ..Emitter::idle(
                Shape::Sphere {
                    center: PLAIN_CENTRE,
                    radius: 3.0,
                    surface: false,
                },
                Velocity::Constant(Vec3(0.0, 0.0, 0.0)),
                // Mortal (as the groups' particles are, so the same death test runs), but not
                // within the run.
                Some(plume_compiler::schema::Range(
                    PLAIN_LIFETIME,
                    PLAIN_LIFETIME,
                )),
            )
        }];
        // Stateful as the original (events made it so).
        plain.state = plume_compiler::schema::State::Stateful;
        let effect = compile_effect(&plain, "").map_err(invalid)?;
        out.push(CompiledGroup {
            name: name.clone(),
            effect,
        });
    }
    Ok(CompiledGraph {
        groups: out,
        streams: Vec::new(),
        warnings: Default::default(),
    })
}
