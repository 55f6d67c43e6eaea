//! The f64 runs behind an accuracy budget (`features::accuracy`): sample particles of a group
//! stepped by one scheme, their positions at the end of every step, and the largest distance
//! between two such runs over the first seconds of each particle's life. The truth they are
//! measured against is RK4 with substeps doubled until it has converged well below the budget.
//!
//! A sample is the group's first `SAMPLES` particles: the same IR with that capacity, so its
//! emitters spawn what they always do and drop the rest. Particles are matched by id, and an
//! id is the same spawn in every run (ids are handed out whether or not a spawn finds room).

use std::collections::HashMap;

use glam::DVec3;

use crate::base::values::Integrator;
use crate::features::accuracy::Scheme;
use crate::ir::EffectIr;
use crate::reference::sim::ReferenceSim;

/// Particles a calibration follows.
pub(crate) const SAMPLES: u32 = 64;

/// The most substeps a budget may ask of a scheme (and of the truth).
pub(crate) const MAX_SUBSTEPS: u32 = 64;

/// The truth's most substeps: RK4 doubled up to here.
const TRUTH_MAX_SUBSTEPS: u32 = 256;

/// Positions by id at the end of every step, of the particles no older than the window.
#[derive(Clone, Debug, Default)]
pub struct Trajectories {
    steps: Vec<HashMap<u32, DVec3>>,
}

impl Trajectories {
    /// How many particles the run followed (over all its steps).
    pub fn particles(&self) -> usize {
        let mut ids: Vec<u32> = self.steps.iter().flat_map(|s| s.keys().copied()).collect();
        ids.sort_unstable();
        ids.dedup();
        ids.len()
    }

    /// The largest `f` of any followed position.
    pub(crate) fn max_of(&self, f: &dyn Fn(DVec3) -> f64) -> f64 {
        self.steps
            .iter()
            .flat_map(|s| s.values())
            .map(|x| f(*x))
            .fold(0.0, f64::max)
    }

    /// The largest distance, as `metric` measures it, between the same particle's positions
    /// in `self` and `other` at the end of the same step (particles followed in both).
    pub fn max_distance(&self, other: &Trajectories, metric: &Metric) -> f64 {
        self.steps
            .iter()
            .zip(&other.steps)
            .flat_map(|(a, b)| {
                a.iter()
                    .filter_map(|(id, x)| b.get(id).map(|y| metric(*x, *y)))
            })
            .fold(0.0, f64::max)
    }
}

/// How far apart two positions are, in a budget's unit (metres, or pixels on screen).
pub(crate) type Metric = dyn Fn(DVec3, DVec3) -> f64 + Send + Sync;

/// The trajectories' positions, step by step, for a run made elsewhere (the GPU's).
impl FromIterator<HashMap<u32, DVec3>> for Trajectories {
    fn from_iter<I: IntoIterator<Item = HashMap<u32, DVec3>>>(steps: I) -> Self {
        Self {
            steps: steps.into_iter().collect(),
        }
    }
}

/// Steps a window of `over` seconds takes at the group's dt (at least one).
pub fn window_steps(ir: &EffectIr, over: f64) -> u64 {
    ((over / ir.dt).ceil() as u64).max(1)
}

/// Runs the first `particles` of `ir` (its capacity cut to that) with `scheme` for `steps`
/// steps, keeping the positions of particles no older than `steps` steps.
pub fn run(ir: &EffectIr, scheme: Scheme, steps: u64, particles: u32) -> Trajectories {
    run_stored(ir, scheme, steps, particles, false)
}

/// [`run`], with each particle's motion rounded to 16-bit floats wherever the GPU stores it
/// when `halves` (a half-motion layout's model).
pub(crate) fn run_stored(
    ir: &EffectIr,
    scheme: Scheme,
    steps: u64,
    particles: u32,
    halves: bool,
) -> Trajectories {
    let mut sample = ir.clone();
    sample.capacity = particles.min(ir.capacity);
    sample.integrator = scheme.integrator;
    sample.substeps = scheme.substeps;
    sample.stateless = None;
    let window = steps as f64 * ir.dt + 0.5 * ir.dt;
    // A group fed by events alone is sampled by a burst of its spawn rule at its parent's first
    // firing (`AccuracyIr::sample_burst`), spawned at the first step as its children would be.
    let sample_burst = ir.accuracy.as_ref().and_then(|a| a.sample_burst);
    if sample_burst.is_some() {
        sample.bursts = true;
    }
    let mut sim = ReferenceSim::new(&sample);
    sim.set_motion_in_halves(halves);
    if let Some(burst) = sample_burst {
        sim.burst(burst)
            .expect("the sample burst names one of the group's emitters");
    }
    let mut out = Trajectories::default();
    for _ in 0..steps {
        sim.step();
        out.steps.push(
            sim.records()
                .into_iter()
                .filter(|r| r.age <= window)
                .map(|r| (r.id, r.position))
                .collect(),
        );
    }
    out
}

/// The truth for a budget of `limit` (as `metric` measures) over `steps` steps of the first
/// `particles`: RK4 with its substeps
/// doubled until two in a row agree within a fiftieth of the budget (from 4), or up to
/// `TRUTH_MAX_SUBSTEPS`. Returns the finer run and how far it may be from the exact
/// trajectory: the last difference over 15 (RK4's error falls 16-fold a doubling), or the
/// difference itself where it did not converge.
pub fn truth(
    ir: &EffectIr,
    limit: f64,
    steps: u64,
    particles: u32,
    metric: &Metric,
) -> (Trajectories, f64) {
    let rk4 = |substeps| Scheme {
        integrator: Integrator::Rk4,
        substeps,
    };
    let mut substeps = 4;
    let mut coarse = run(ir, rk4(substeps), steps, particles);
    loop {
        let fine = run(ir, rk4(2 * substeps), steps, particles);
        let difference = coarse.max_distance(&fine, metric);
        if difference <= limit / 50.0 {
            return (fine, difference / 15.0);
        }
        if 2 * substeps >= TRUTH_MAX_SUBSTEPS {
            return (fine, difference);
        }
        substeps *= 2;
        coarse = fine;
    }
}
