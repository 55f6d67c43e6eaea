//! An accuracy budget checked on the GPU (`plume accuracy` on an effect with `accuracy`): the
//! effect as compiled, in the scheme its budget chose, runs its first `CHECKED` particles in
//! f32, and their positions at the end of every step of the budget's window are compared with
//! the f64 truth of the same particles (the closed form where the budget chose Exact, else the
//! converged RK4 of `plume_compiler::reference::calibrate`).

use plume_compiler::accuracy::{Choice, Scheme};
use plume_compiler::calibration::accuracy::measures;
use plume_compiler::reference::calibrate::{self, Trajectories};
use plume_compiler::{compile_effect, EffectSpec, Integrator};

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sim::effect::Effect as RunningEffect;

/// Particles the check follows.
pub const CHECKED: u32 = 256;

/// A budget against what the GPU did.
#[derive(Clone, Debug)]
pub struct BudgetCheck {
    /// What the compiler chose and why (`AccuracyIr::describe`).
    pub chosen: String,
    /// The budget, in `unit`.
    pub budget: f64,
    /// `m`, or `px` for a budget on screen.
    pub unit: &'static str,
    /// Seconds of each particle's life it covers.
    pub over: f64,
    /// The largest distance between a GPU position and the truth's, in `unit`.
    pub measured: f64,
    /// How far the truth itself may be from the exact trajectory, in `unit`.
    pub truth_uncertainty: f64,
    /// Particles compared.
    pub particles: usize,
    /// Steps compared.
    pub steps: u64,
}

impl BudgetCheck {
    /// Whether the GPU kept within the budget.
    pub fn met(&self) -> bool {
        self.measured <= self.budget
    }
}

/// Checks `effect`'s budget on `gpu`; None for an effect without one.
pub fn check_budget(gpu: &Gpu, effect: &EffectSpec) -> Result<Option<BudgetCheck>, RuntimeError> {
    if effect.accuracy.is_none() {
        return Ok(None);
    }
    let mut checked = effect.clone();
    checked.capacity = checked.capacity.min(CHECKED);
    checked.bursts |= checked.sample_burst.is_some();
    let compiled =
        compile_effect(&checked, "").map_err(|e| RuntimeError::Compile(e.to_string()))?;
    let ir = compiled.ir.clone();
    let Some(budget) = ir.accuracy.clone() else {
        return Ok(None);
    };
    let steps = calibrate::window_steps(&ir, budget.over);
    let (metric, _) = measures(&ir, &budget);
    let (truth, truth_uncertainty) = match budget.choice {
        Some(Choice::Exact) => {
            let exact = Scheme {
                integrator: Integrator::Exact,
                substeps: 1,
            };
            (calibrate::run(&ir, exact, steps, CHECKED), 0.0)
        }
        _ => calibrate::truth(&ir, budget.limit, steps, CHECKED, &*metric),
    };
    let window = steps as f64 * ir.dt + 0.5 * ir.dt;
    let mut sim = RunningEffect::new(gpu, compiled)?;
    // A group fed by events alone is measured on its sample burst, as it was calibrated.
    if let Some(burst) = checked.sample_burst {
        sim.burst(0, burst)?;
    }
    let mut on_gpu = Vec::with_capacity(steps as usize);
    for _ in 0..steps {
        sim.run(1, |_| {})?;
        on_gpu.push(
            sim.records()?
                .into_iter()
                .filter(|r| r.age <= window)
                .map(|r| (r.id, r.position))
                .collect(),
        );
    }
    let on_gpu: Trajectories = on_gpu.into_iter().collect();
    Ok(Some(BudgetCheck {
        chosen: budget.describe(),
        budget: budget.limit,
        unit: budget.unit(),
        over: budget.over,
        measured: on_gpu.max_distance(&truth, &*metric),
        truth_uncertainty,
        particles: truth.particles(),
        steps,
    }))
}
