//! Steps of many effects in one compute pass: [`Effect::plan_steps`] records an effect's step
//! parameters into the host's encoder, [`Effect::record_planned`] its kernels into a compute
//! pass the host shares between effects. Beginning and ending a compute pass costs the CPU
//! (wgpu validates and tracks each), and a game with hundreds of small effects paid it for
//! every effect every frame with [`Effect::advance`].

use plume_compiler::schedule::StepPlan;

use crate::device::resources::STEPS_PER_SUBMIT;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;

/// An effect's steps planned by [`Effect::plan_steps`], for [`Effect::record_planned`].
#[derive(Debug)]
pub struct PlannedSteps {
    plans: Vec<StepPlan>,
}

impl PlannedSteps {
    /// How many steps are planned.
    pub fn steps(&self) -> usize {
        self.plans.len()
    }
}

impl Effect {
    /// Whether [`Self::plan_steps`] can plan this effect's steps: a single group without
    /// events (an effect with groups steps its events between its groups' kernels, in passes of
    /// its own: [`Self::advance`]).
    pub fn plans_steps(&self) -> bool {
        self.events.is_none() && self.groups().len() == 1
    }

    /// Plans `steps` steps (at most 256) and records their parameters' copy into `encoder`; the
    /// kernels are recorded by [`Self::record_planned`] into a compute pass that may hold other
    /// effects' steps too, recorded after this copy in the same encoder. The effect's schedule
    /// advances now, as with [`Self::advance`], and its placement, params and bursts are those
    /// set before this call. Record the plan before planning again (the effect keeps one
    /// buffer of step parameters). An error for an effect that does not plan
    /// ([`Self::plans_steps`]) or for more than 256 steps.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "puff", capacity: 64,
    ///     emitters: [Emitter(rate: 600.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mut puffs: Vec<Effect> = (0..3)
    ///     .map(|_| Effect::from_source(&gpu, source, &Default::default()))
    ///     .collect::<Result<_, _>>()?;
    /// let mut encoder = gpu.device.create_command_encoder(&Default::default());
    /// let plans: Vec<_> = puffs
    ///     .iter_mut()
    ///     .map(|puff| puff.plan_steps(&mut encoder, 2))
    ///     .collect::<Result<_, _>>()?;
    /// {
    ///     let mut pass = encoder.begin_compute_pass(&Default::default());
    ///     for (puff, plan) in puffs.iter().zip(&plans) {
    ///         puff.record_planned(&mut pass, plan)?;
    ///     }
    /// }
    /// gpu.queue.submit([encoder.finish()]);
    /// assert!(puffs.iter().all(|p| p.steps_done() == 2));
    /// # Ok(())
    /// # }
    /// ```
    pub fn plan_steps(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<PlannedSteps, RuntimeError> {
        if !self.plans_steps() {
            return Err(RuntimeError::Control(format!(
                "{}: an effect with groups and events steps in passes of its own: use Effect::advance",
                self.compiled().ir.name
            )));
        }
        if steps > u64::from(STEPS_PER_SUBMIT) {
            return Err(RuntimeError::Control(format!(
                "{steps} steps are more than one plan holds ({STEPS_PER_SUBMIT}): plan them in parts, recording each before the next"
            )));
        }
        let plans = self.groups_mut()[0].plan_steps(encoder, steps)?;
        Ok(PlannedSteps { plans })
    }

    /// Records the kernels of `planned` (from [`Self::plan_steps`] on this effect) into the
    /// host's compute pass.
    pub fn record_planned(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        planned: &PlannedSteps,
    ) -> Result<(), RuntimeError> {
        self.groups()[0].record_planned(pass, &planned.plans)
    }
}
