//! What the benchmarks time on a running effect: a group's steps, its depth sort and its
//! flocking stages, each in a pass of its own; an effect graph's steps, and each event
//! stream's ordering alone. The state advances only where steps are timed.

use plume_compiler::schedule::StepPlan;

use crate::bench::timer::{median_after_warmup, PassTimer};
use crate::device::resources::STEPS_PER_SUBMIT;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use crate::sim::group::Group;
use crate::sim::steps::{params_bytes, Steps};
use crate::sort::depth::{sort_buffers, DEPTH_SORT_STAGES};
use crate::sort::radix::SortAlgorithm;

impl Group {
    /// Times the depth keys and the sort of every slot in one pass (seconds), from the
    /// effect's camera.
    pub(crate) fn time_sort(
        &self,
        timer: &PassTimer<'_>,
        algorithm: SortAlgorithm,
    ) -> Result<f64, RuntimeError> {
        let depth = self.depth()?;
        self.sort_from_effect_camera()?;
        let chunks = self.sort_chunks()?;
        let seconds =
            timer.time(|pass| depth.record(&self.gpu, pass, &self.res, chunks, algorithm))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// Readies a timed sort: a stateless effect's frame, and the effect camera's depth axis.
    fn sort_from_effect_camera(&self) -> Result<(), RuntimeError> {
        if let Steps::Stateless(stateless) = &self.steps {
            self.write_frame_now(stateless)?;
        }
        self.gpu.queue.write_buffer(
            &sort_buffers(&self.res)?.depth_axis,
            0,
            &self.effect_camera().depth_axis_bytes(),
        );
        Ok(())
    }

    /// Times the radix depth sort's stages ([`DEPTH_SORT_STAGES`]) by difference: the first
    /// one, the first two, all three, each the median of `repeats` passes; (name, seconds).
    pub(crate) fn time_sort_stages(
        &self,
        timer: &PassTimer<'_>,
        repeats: u32,
    ) -> Result<Vec<(&'static str, f64)>, RuntimeError> {
        let depth = self.depth()?;
        self.sort_from_effect_camera()?;
        let chunks = self.sort_chunks()?;
        let mut before = 0.0;
        let mut out = Vec::new();
        for (k, name) in DEPTH_SORT_STAGES.iter().enumerate() {
            let seconds = median_after_warmup(repeats, || {
                timer.time(|pass| {
                    depth.record_stages(
                        &self.gpu,
                        pass,
                        &self.res,
                        chunks,
                        SortAlgorithm::Radix,
                        k + 1,
                    )
                })
            })?;
            out.push((*name, (seconds - before).max(0.0)));
            before = seconds;
        }
        self.gpu.take_error()?;
        Ok(out)
    }

    /// Runs `steps` (at most [`STEPS_PER_SUBMIT`]) in one timed compute pass; returns seconds.
    /// A stateless effect advances its bookkeeping by `steps` and times as many evaluations of
    /// the view (each one what a frame read back costs), so the two compare per step.
    pub(crate) fn time_steps(
        &mut self,
        timer: &PassTimer<'_>,
        steps: u32,
    ) -> Result<f64, RuntimeError> {
        let steps = steps.min(STEPS_PER_SUBMIT);
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, u64::from(steps), |_| {});
            let Steps::Stateless(stateless) = &self.steps else {
                unreachable!("matched above");
            };
            self.write_frame_now(stateless)?;
            let chunks = self.chunks()?;
            let seconds = timer.time(|pass| {
                for _ in 0..steps {
                    stateless.record_evaluate(&self.gpu, pass, chunks)?;
                }
                Ok(())
            })?;
            self.gpu.take_error()?;
            stateless.mark_view_current();
            return Ok(seconds);
        }
        let Steps::Stateful(stateful) = &self.steps else {
            unreachable!("stateless returned above");
        };
        let plans: Vec<StepPlan> = (0..steps).map(|_| self.schedule.next_plan()).collect();
        let bytes = params_bytes(
            &plans,
            &self.effect.layout,
            self.res.params_stride,
            self.effect.ir.wraps_kernel_time(),
            &self.placement,
            &self.live_params,
        );
        let params = self
            .res
            .params
            .as_ref()
            .expect("a stateful effect has params");
        self.gpu.queue.write_buffer(params, 0, &bytes);
        let chunks = self.chunks()?;
        let stride = self.res.params_stride;
        let seconds =
            timer.time(|pass| stateful.record(&self.gpu, pass, chunks, &plans, stride))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// Times each stage of the flocking pass on the current state (seconds, by stage name),
    /// the median of `repeats` runs of each stage prefix, by difference. Empty when the effect
    /// does not flock. The state does not change: the pass writes only its own buffers.
    pub(crate) fn time_flock_stages(
        &self,
        timer: &PassTimer<'_>,
        repeats: u32,
    ) -> Result<Vec<(&'static str, f64)>, RuntimeError> {
        let Steps::Stateful(stateful) = &self.steps else {
            return Ok(Vec::new());
        };
        let Some(flock) = stateful.flock() else {
            return Ok(Vec::new());
        };
        let chunk = &self.chunks()?[0];
        let mut prefix = vec![0.0];
        for stages in 1..=flock.stage_names().len() {
            prefix.push(median_after_warmup(repeats, || {
                timer.time(|pass| flock.record_stages(&self.gpu, pass, chunk, 0, stages))
            })?);
        }
        self.gpu.take_error()?;
        Ok(flock
            .stage_names()
            .iter()
            .zip(prefix.windows(2))
            .map(|(name, w)| (*name, w[1] - w[0]))
            .collect())
    }
}

impl Effect {
    /// Runs `steps` steps (at most [`STEPS_PER_SUBMIT`]) in one timed compute pass; returns
    /// seconds. One group steps as [`Group::time_steps`]; a graph's steps' parameters are
    /// copied in a submission of their own first.
    pub(crate) fn time_steps(
        &mut self,
        timer: &PassTimer<'_>,
        steps: u32,
    ) -> Result<f64, RuntimeError> {
        let gpu = self.gpu().clone();
        if self.events().is_none() {
            return self.groups_mut()[0].time_steps(timer, steps);
        }
        let n = u64::from(steps.min(STEPS_PER_SUBMIT));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let plans = self
            .groups_mut()
            .iter_mut()
            .map(|g| g.plan_graph_submission(&mut encoder, n))
            .collect::<Result<Vec<Vec<StepPlan>>, _>>()?;
        gpu.queue.submit([encoder.finish()]);
        let events = self.events().expect("a graph has its streams");
        let seconds =
            timer.time(|pass| events.record_submission(self.groups(), pass, &plans, n))?;
        gpu.take_error()?;
        Ok(seconds)
    }

    /// Times each stream's ordering of the last step's firings alone, in stream order
    /// (seconds each, the median of `repeats`). The state does not change: it orders the
    /// same firings again, and does not prepare their children's spawn.
    pub(crate) fn time_orders(
        &self,
        timer: &PassTimer<'_>,
        repeats: u32,
    ) -> Result<Vec<f64>, RuntimeError> {
        let Some(events) = self.events() else {
            return Ok(Vec::new());
        };
        events
            .orders
            .iter()
            .map(|s| {
                // The last step's firings came from the last submission's table, as step 1's of it
                // would: the ordering that the steps took.
                let order = s.for_step(&self.groups()[s.stream.parent], 1);
                median_after_warmup(repeats, || {
                    timer.time(|pass| {
                        order.record_alone(pass);
                        Ok(())
                    })
                })
            })
            .collect()
    }
}
