//! Recording an [`EffectBatch`]'s steps: the instances' slots freed and their transforms
//! uploaded as needed, then per [`BATCH_STEPS`] steps one upload of every instance's row of
//! step parameters and one compute pass of three dispatches a step over every instance.

use plume_compiler::passes::layout::Role;
use plume_compiler::placement::Placement;
use plume_compiler::wgsl::WORKGROUP;

use crate::device::buffers::staging;
use crate::device::resources::BATCH_STEPS;
use crate::error::RuntimeError;
use crate::sim::batch::{BatchInstance, EffectBatch};
use crate::sim::steps::write_params_row;

impl EffectBatch {
    /// Records this frame's steps into `encoder`: `steps(instance)` steps for each instance (0
    /// for one that is paused). The batch takes as many steps as the instance that takes
    /// most; the others sit out the rest, held. First the slots of instances added, restarted
    /// or removed since the last call are freed. Then, per `BATCH_STEPS` steps, one upload
    /// of every instance's rows and one compute pass. The schedules advance now.
    pub fn advance(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: impl Fn(BatchInstance) -> u64,
    ) -> Result<(), RuntimeError> {
        let parts: Vec<Vec<(u64, Option<Placement>)>> = (0..self.instances.len())
            .map(|k| match self.instances[k] {
                Some(_) => vec![(steps(BatchInstance(k as u32)), None)],
                None => Vec::new(),
            })
            .collect();
        self.advance_along(encoder, &parts)
    }

    /// [`Self::advance`] with each instance's steps in parts: `parts[k]`, for the instance in
    /// place k ([`BatchInstance`]`(k)`), is a list of (steps, the placement they spawn at, or
    /// None to keep the one set), in order; a place without an instance, or past the list, is
    /// ignored. A host whose emitter moved far in a frame of several steps spawns along the
    /// way so.
    pub fn advance_along(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[Vec<(u64, Option<Placement>)>],
    ) -> Result<(), RuntimeError> {
        let wants: Vec<u64> = (0..self.instances.len())
            .map(|k| match (&self.instances[k], parts.get(k)) {
                (Some(_), Some(p)) => p.iter().map(|q| q.0).sum(),
                _ => 0,
            })
            .collect();
        let most = wants.iter().copied().max().unwrap_or(0);
        // Dispatches cover the instances up to the last one there is.
        let layers = self
            .instances
            .iter()
            .rposition(Option::is_some)
            .map_or(0, |k| k + 1);
        self.record_inits(encoder)?;
        self.record_models(encoder)?;
        let mut done = 0;
        while done < most {
            let n = (most - done).min(u64::from(BATCH_STEPS));
            self.record_plan(encoder, parts, done, n, layers as u32)?;
            done += n;
        }
        Ok(())
    }

    /// Uploads the instances' transforms when they changed.
    fn record_models(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<(), RuntimeError> {
        if !self.models_changed {
            return Ok(());
        }
        let bytes: Vec<u8> = self
            .models
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        let group = &self.effect.groups[0];
        let models = group
            .res
            .extra_of(&group.effect, Role::InstanceModels)
            .ok_or_else(|| RuntimeError::Gpu("a batch has no instance transforms".into()))?;
        let src = staging(&self.effect.gpu, "batch transforms", &bytes)?;
        encoder.copy_buffer_to_buffer(&src, 0, models, 0, bytes.len() as u64);
        self.models_changed = false;
        Ok(())
    }

    /// Frees the slots of every instance added, restarted or removed since the last steps.
    fn record_inits(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<(), RuntimeError> {
        if self.to_init.is_empty() {
            return Ok(());
        }
        let gpu = &self.effect.gpu;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("batch init"),
            timestamp_writes: None,
        });
        let (x, y) = gpu.grid(u64::from(self.batched.ir.capacity), u64::from(WORKGROUP))?;
        pass.set_pipeline(&self.kernels.init_last);
        pass.set_bind_group(0, &self.group().chunks()?[0].bind_group, &[0]);
        self.to_init.sort_unstable();
        self.to_init.dedup();
        for &k in &self.to_init {
            // `init_last` inits the last layer of its dispatch: instance k.
            pass.dispatch_workgroups(x, y, k + 1);
        }
        drop(pass);
        self.to_init.clear();
        Ok(())
    }

    /// Records `n` batch steps from step `from` of this frame: each instance's rows (its
    /// plan while its parts still hold steps, placed as its part says, else a held row), one
    /// upload, one compute pass.
    fn record_plan(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[Vec<(u64, Option<Placement>)>],
        from: u64,
        n: u64,
        layers: u32,
    ) -> Result<(), RuntimeError> {
        let row = self.row_bytes as usize;
        let stride = self.step_stride as usize;
        let layout = &self.batched.layout;
        let wraps = self.batched.ir.wraps_kernel_time();
        let mut bytes = vec![0u8; stride * n as usize];
        let mut most_requested = vec![0u32; n as usize];
        // One plan's lists, refilled for every instance and step.
        let plan = &mut self.plan;
        for (j, most) in most_requested.iter_mut().enumerate() {
            self.effect.groups[0].schedule.next_plan_into(plan);
            let step = plan.step as u32;
            for (k, state) in self.instances.iter_mut().enumerate() {
                let at = j * stride + k * row;
                let out = &mut bytes[at..at + row];
                let Some(state) = state else {
                    continue;
                };
                if let Some(placement) = parts.get(k).and_then(|p| part_at(p, from + j as u64)) {
                    if let Some(placement) = placement {
                        state.placement = placement;
                    }
                    state.schedule.next_plan_into(plan);
                    *most = (*most).max(plan.requested());
                    write_params_row(
                        out,
                        plan,
                        layout,
                        wraps,
                        &state.placement,
                        &state.live_params,
                    );
                    // Active this step.
                    out[row - 16..row - 12].copy_from_slice(&1u32.to_le_bytes());
                } else {
                    state.held += 1;
                }
                // Every row carries the batch's step index: deaths and ages reckon from it.
                out[12..16].copy_from_slice(&step.to_le_bytes());
            }
        }
        let src = staging(&self.effect.gpu, "batch step params", &bytes)?;
        let params = self
            .group()
            .res
            .params
            .as_ref()
            .expect("a batch is stateful");
        encoder.copy_buffer_to_buffer(&src, 0, params, 0, bytes.len() as u64);
        let gpu = &self.effect.gpu;
        let group = &self.effect.groups[0];
        let bind_group = &group.chunks()?[0].bind_group;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("batch steps"),
            timestamp_writes: None,
        });
        let (ux, uy) = gpu.grid(u64::from(self.batched.ir.capacity), u64::from(WORKGROUP))?;
        for (j, requested) in most_requested.iter().enumerate() {
            pass.set_bind_group(0, bind_group, &[(j * stride) as u32]);
            if *requested > 0 {
                pass.set_pipeline(&self.kernels.prepare);
                pass.dispatch_workgroups(1, 1, layers);
                let (x, y) = gpu.grid(u64::from(*requested), u64::from(WORKGROUP))?;
                pass.set_pipeline(&self.kernels.spawn);
                pass.dispatch_workgroups(x, y, layers);
            }
            pass.set_pipeline(&self.kernels.update);
            pass.dispatch_workgroups(ux, uy, layers);
        }
        Ok(())
    }
}

/// The placement of step `t` of an instance's frame in `parts` (Some(None): its own), or None
/// past its steps.
fn part_at(parts: &[(u64, Option<Placement>)], t: u64) -> Option<Option<Placement>> {
    let mut end = 0;
    for (steps, placement) in parts {
        end += steps;
        if t < end {
            return Some(*placement);
        }
    }
    None
}
