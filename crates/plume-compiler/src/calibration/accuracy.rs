//! The accuracy pass (`features::accuracy`): with a budget, `integrator: Auto` becomes the
//! cheapest scheme (integrator and substeps, counted in force evaluations a step) whose f64
//! error over sample particles stays within half the budget (the other half is left to f32's
//! rounding on the GPU). Exact wherever a closed form exists: it is exact at any step. An
//! integrator the file names is kept, and its error estimated for the note.
//!
//! With the scheme chosen, the same sample runs once more with its motion (velocity, or Verlet's
//! displacement) rounded to 16-bit floats after every step, as a half-motion layout stores it;
//! where that error too stays within the f64 share, the layout stores the motion in halves
//! (8 bytes a particle instead of 12: `base::layout::Layout::half_motion`).
//!
//! The error model: each integrator's error falls as h^p. The search runs the sample at the
//! file's substeps s and at 2s, takes the observed order p from the two errors, predicts the
//! substeps that bring the error under the target, runs that, and corrects the prediction by
//! the same model until it holds (or the substeps pass `MAX_SUBSTEPS`). Every error is measured
//! against the converged RK4 truth (`reference::calibrate::truth`), plus the truth's own
//! uncertainty.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::time::Instant;

use crate::base::check::Checker;
use crate::base::diagnostics::Diagnostic;
use crate::base::path::ValuePath;
use crate::base::values::Integrator;
use crate::calibration::cache as calibration_cache;
use crate::features::accuracy::{AccuracyIr, Choice, Measure, Scheme, Screen};
use crate::ir::EffectIr;
use crate::reference::calibrate::{self, Metric, MAX_SUBSTEPS};

/// The share of the budget the f64 error may take: the rest is f32's.
const F64_SHARE: f64 = 0.5;

/// The integrators the search compares (Euler costs what SemiImplicitEuler costs and is less
/// accurate on every force here, so it is never the cheapest).
const CANDIDATES: [Integrator; 4] = [
    Integrator::SemiImplicitEuler,
    Integrator::Verlet,
    Integrator::Midpoint,
    Integrator::Rk4,
];

/// What a calibration decided, kept by the effect's content ([`choose`]'s cache).
#[derive(Clone)]
struct Decided {
    accuracy: Option<AccuracyIr>,
    integrator: Integrator,
    substeps: u32,
    integrator_reason: String,
    warning: Option<(Diagnostic, String)>,
}

/// The most calibrations kept in memory (a host compiling many files starts again past it).
const CACHED_MOST: usize = 256;

/// Calibrations decided in this process, by the hash of the IR they were made for, its seed
/// aside.
fn decided() -> &'static std::sync::Mutex<HashMap<u64, Decided>> {
    static DECIDED: std::sync::OnceLock<std::sync::Mutex<HashMap<u64, Decided>>> =
        std::sync::OnceLock::new();
    DECIDED.get_or_init(Default::default)
}

/// The key a calibration of `ir` is remembered by: the content the compile driver hashed
/// (`AccuracyIr::content`: the effect lowered with its seed at 0, since the seed only changes
/// which sample particles a calibration draws) and whether the closed form applies.
fn content_key(ir: &EffectIr, exact_possible: bool) -> Option<u64> {
    let content = ir.accuracy.as_ref()?.content?;
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (content, exact_possible).hash(&mut h);
    Some(h.finish())
}

/// Chooses how to meet `ir.accuracy`, when there is one (before the integrator pass, which then
/// finds a concrete integrator or Exact). `exact_possible`: whether the closed form applies.
/// Returns a warning (with its lookup path) when the file's own scheme misses the budget; an
/// error when no scheme meets it. A choice made once is kept by the effect's content, its seed
/// aside: compiling the same effect again, or a variant with another seed (a Bevy instance's),
/// takes it from memory instead of calibrating again (docs/performance.md, "The compiler's own
/// speed").
pub(crate) fn choose(
    ir: &mut EffectIr,
    exact_possible: bool,
) -> Result<Option<(Diagnostic, String)>, Checker> {
    if ir.accuracy.is_none() {
        return Ok(None);
    }
    let Some(key) = content_key(ir, exact_possible) else {
        return calibrate_choice(ir, exact_possible);
    };
    let known = decided()
        .lock()
        .ok()
        .and_then(|d| d.get(&key).cloned())
        .or_else(|| from_disk(ir, key));
    if let Some(d) = known {
        ir.accuracy = d.accuracy.map(|a| AccuracyIr {
            remembered: true,
            ..a
        });
        ir.integrator = d.integrator;
        ir.substeps = d.substeps;
        ir.integrator_reason = d.integrator_reason;
        return Ok(d.warning);
    }
    let warning = calibrate_choice(ir, exact_possible)?;
    let made = Decided {
        accuracy: ir.accuracy.clone(),
        integrator: ir.integrator,
        substeps: ir.substeps,
        integrator_reason: ir.integrator_reason.clone(),
        warning: warning.clone(),
    };
    calibration_cache::store(
        key,
        &calibration_cache::Stored {
            choice: made.accuracy.as_ref().and_then(|a| a.choice.clone()),
            half_motion: made.accuracy.as_ref().is_some_and(|a| a.half_motion),
            half_estimate: made.accuracy.as_ref().and_then(|a| a.half_estimate),
            integrator: made.integrator,
            substeps: made.substeps,
            integrator_reason: made.integrator_reason.clone(),
            warning: made
                .warning
                .as_ref()
                .map(|(d, lookup)| (d.path.clone(), d.message.clone(), lookup.clone())),
        },
    );
    remember(key, made);
    Ok(warning)
}

/// Keeps `made` in memory for `key`.
fn remember(key: u64, made: Decided) {
    if let Ok(mut d) = decided().lock() {
        if d.len() >= CACHED_MOST {
            d.clear();
        }
        d.insert(key, made);
    }
}

/// The choice stored on disk for `key` (see [`calibration_cache`]), applied to `ir`'s budget,
/// and kept in memory too.
fn from_disk(ir: &EffectIr, key: u64) -> Option<Decided> {
    let stored = calibration_cache::load(key)?;
    let accuracy = ir.accuracy.clone().map(|a| AccuracyIr {
        choice: stored.choice.clone(),
        half_motion: stored.half_motion,
        half_estimate: stored.half_estimate,
        ..a
    });
    let made = Decided {
        accuracy,
        integrator: stored.integrator,
        substeps: stored.substeps,
        integrator_reason: stored.integrator_reason.clone(),
        warning: stored.warning(),
    };
    remember(key, made.clone());
    Some(made)
}

/// [`choose`] itself: the calibration runs.
fn calibrate_choice(
    ir: &mut EffectIr,
    exact_possible: bool,
) -> Result<Option<(Diagnostic, String)>, Checker> {
    let Some(budget) = ir.accuracy.clone() else {
        return Ok(None);
    };
    let path = ValuePath::root()
        .field("accuracy")
        .field(match budget.measure {
            Measure::Metres => "position",
            Measure::Pixels { .. } => "pixels",
        });
    let unit = budget.unit();
    if let (Some(c), Measure::Pixels { .. }) = (budget.host_camera, budget.measure) {
        let sound = c.eye.is_finite()
            && c.target.is_finite()
            && c.fov_y > 0.0
            && c.fov_y < 180.0
            && (c.eye - c.target).length_squared() > 1e-20;
        if !sound {
            let mut checker = Checker::default();
            checker.error(
                &path,
                format!(
                    "the host's camera this budget is measured through (CompileOptions::accuracy_camera: eye {}, target {}, fov_y {}) must be finite, look at a point other than its eye, and have 0 < fov_y < 180",
                    c.eye, c.target, c.fov_y
                ),
            );
            return Err(checker);
        }
    }
    let (metric, floor_at) = measures(ir, &budget);
    let choice = |ir: &mut EffectIr, choice: Choice| {
        if let Some(a) = &mut ir.accuracy {
            a.choice = Some(choice);
        }
    };
    let auto = ir.integrator == Integrator::Auto;
    if ir.integrator == Integrator::Exact || (auto && exact_possible) {
        choice(ir, Choice::Exact);
        return Ok(None);
    }
    let file_scheme = Scheme {
        integrator: if auto {
            Integrator::SemiImplicitEuler
        } else {
            ir.integrator
        },
        substeps: ir.substeps,
    };
    let started = Instant::now();
    let steps = calibrate::window_steps(ir, budget.over);
    let (truth, uncertainty) =
        calibrate::truth(ir, budget.limit, steps, calibrate::SAMPLES, &*metric);
    let samples = truth.particles();
    if samples == 0 {
        choice(
            ir,
            Choice::Uncalibrated {
                scheme: file_scheme,
            },
        );
        return Ok(None);
    }
    let error = |scheme: Scheme| -> f64 {
        calibrate::run(ir, scheme, steps, calibrate::SAMPLES).max_distance(&truth, &*metric)
            + uncertainty
    };
    if !auto {
        let estimated = error(file_scheme);
        choice(
            ir,
            Choice::Kept {
                scheme: file_scheme,
                estimated: Some(estimated),
            },
        );
        let warning = (estimated > budget.limit).then(|| {
            (
                Diagnostic::warning(
                    path.display.clone(),
                    format!(
                        "{} (the file's) strays {estimated:.1e} {unit} from the exact trajectory over {} s, more than the budget's {:.1e} {unit}: `integrator: Auto` would choose a scheme that meets it",
                        file_scheme.describe(),
                        budget.over,
                        budget.limit
                    ),
                ),
                path.lookup.clone(),
            )
        });
        return Ok(warning);
    }
    let target = budget.limit * F64_SHARE;
    // f32's own floor: a position's rounding (2^-24 of its size), a random walk over the steps.
    let walk = f64::from(f32::EPSILON) * 0.5 * (steps as f64).sqrt();
    let floor = truth.max_of(&|x| floor_at(x.length() * walk, x));
    if budget.limit < 2.0 * floor {
        let mut c = Checker::default();
        c.error(
            &path,
            format!(
                "{:.1e} {unit} is below what f32 positions hold here: rounding alone moves these particles (up to {:.1} m from the origin) by about {floor:.1e} {unit} over {steps} steps; the smallest budget that can be met is about {:.1e} {unit}",
                budget.limit,
                truth.max_of(&|x| x.length()),
                2.0 * floor
            ),
        );
        return Err(c);
    }
    let mut met: Vec<(Scheme, f64)> = Vec::new();
    let mut best_missed: Option<(Scheme, f64)> = None;
    // The four searches are independent f64 runs: one thread each.
    let first = ir.substeps.max(1);
    let found: Vec<Result<(Scheme, f64), (Scheme, f64)>> = std::thread::scope(|scope| {
        let searches: Vec<_> = CANDIDATES
            .iter()
            .map(|&integrator| scope.spawn(move || search(integrator, first, target, &error)))
            .collect();
        searches
            .into_iter()
            .map(|s| s.join().expect("a calibration run panicked"))
            .collect()
    });
    for result in found {
        match result {
            Ok(found) => met.push(found),
            Err(missed) => {
                if best_missed.is_none_or(|(_, e)| missed.1 < e) {
                    best_missed = Some(missed);
                }
            }
        }
    }
    met.sort_by(|a, b| {
        a.0.evaluations()
            .cmp(&b.0.evaluations())
            .then(a.1.total_cmp(&b.1))
    });
    let Some(&(scheme, estimated)) = met.first() else {
        let (scheme, e) = best_missed.expect("four candidates were searched");
        let mut c = Checker::default();
        c.error(
            &path,
            format!(
                "no integrator keeps within {:.1e} {unit} over {} s with at most {MAX_SUBSTEPS} substeps: the closest, {}, strays {e:.1e} {unit} in f64 (f32 alone rounds these positions by about {floor:.1e} {unit}); raise the budget or shorten `over`",
                budget.limit,
                budget.over,
                scheme.describe()
            ),
        );
        return Err(c);
    };
    let runner_up = met
        .iter()
        .find(|(s, _)| s.integrator != scheme.integrator)
        .copied();
    ir.integrator = scheme.integrator;
    ir.substeps = scheme.substeps;
    // The motion in 16-bit floats where the chosen scheme, so stored, still keeps its share.
    let halves = calibrate::run_stored(ir, scheme, steps, calibrate::SAMPLES, true)
        .max_distance(&truth, &*metric)
        + uncertainty;
    if let Some(a) = &mut ir.accuracy {
        a.half_estimate = Some(halves);
        a.half_motion = halves <= target;
    }
    let millis = started.elapsed().as_secs_f64() * 1e3;
    choice(
        ir,
        Choice::Stepped {
            scheme,
            estimated,
            runner_up,
            samples,
            millis,
        },
    );
    ir.integrator_reason = ir.accuracy.as_ref().map(|a| a.reason()).unwrap_or_default();
    Ok(None)
}

/// The fewest substeps (from `first`) at which `integrator` keeps `error` within `target`, with
/// that error; or, where none up to `MAX_SUBSTEPS` does, the closest it came.
fn search(
    integrator: Integrator,
    first: u32,
    target: f64,
    error: &dyn Fn(Scheme) -> f64,
) -> Result<(Scheme, f64), (Scheme, f64)> {
    let scheme = |substeps: u32| Scheme {
        integrator,
        substeps: substeps.min(MAX_SUBSTEPS),
    };
    let e1 = error(scheme(first));
    if e1 <= target {
        return Ok((scheme(first), e1));
    }
    if first >= MAX_SUBSTEPS {
        return Err((scheme(first), e1));
    }
    let second = (2 * first).min(MAX_SUBSTEPS);
    let e2 = error(scheme(second));
    // The observed order, kept sensible where rounding or a contact blurs it.
    let order = (e1 / e2.max(f64::MIN_POSITIVE)).log2().clamp(0.5, 6.0);
    let (mut substeps, mut e) = (second, e2);
    for _ in 0..5 {
        if e <= target {
            return Ok((scheme(substeps), e));
        }
        if substeps >= MAX_SUBSTEPS {
            break;
        }
        let predicted = f64::from(substeps) * (e / target).powf(1.0 / order) * 1.05;
        substeps = (predicted.ceil() as u32).clamp(substeps + 1, MAX_SUBSTEPS);
        e = error(scheme(substeps));
    }
    if e <= target {
        Ok((scheme(substeps), e))
    } else {
        Err((scheme(substeps), e))
    }
}

/// How large a shift of some metres at a position is, in a budget's unit.
pub(crate) type Scale = dyn Fn(f64, glam::DVec3) -> f64 + Send + Sync;

/// How a budget measures an error between two positions, and how large a shift of some metres
/// at a position is in its unit: metres themselves, or pixels through the effect's camera, or
/// the host's where one was given (a shift across the view at the position's depth, the most
/// it can move the image).
pub fn measures(ir: &EffectIr, budget: &AccuracyIr) -> (Box<Metric>, Box<Scale>) {
    match budget.measure {
        Measure::Metres => (
            Box::new(|a: glam::DVec3, b: glam::DVec3| (a - b).length()),
            Box::new(|metres, _| metres),
        ),
        Measure::Pixels { height } => {
            let (eye, target, fov_y) = match budget.host_camera {
                Some(c) => (c.eye, c.target, c.fov_y),
                None => (ir.camera.eye, ir.camera.target, ir.camera.fov_y),
            };
            let screen = Screen::new(eye, target, fov_y, height);
            (
                Box::new(move |a, b| screen.pixels(a, b)),
                Box::new(move |metres, x| screen.pixels_of(metres, x)),
            )
        }
    }
}
