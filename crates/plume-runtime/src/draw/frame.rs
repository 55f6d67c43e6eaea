//! A group's frame: what any view of it needs before it is drawn (a stateless group's segment
//! table, the depth keys and their sort along the camera's axis), whatever draws it, the
//! raster draw or the compute renderer; and the draw order that sort gives, read back.

use plume_compiler::reference::ParticleRecord;

use crate::device::buffers::staging;
use crate::device::readback::read_words;
use crate::draw::camera::Camera;
use crate::error::RuntimeError;
use crate::sim::group::Group;
use crate::sim::steps::Steps;
use crate::sort::depth::sort_buffers;
use crate::sort::radix::SortAlgorithm;

/// What a frame's preparation recorded: the steps done, and for a stateless group the slots
/// its segment table covers.
pub(crate) struct PreparedFrame {
    /// Steps done.
    pub steps: u64,
    /// A stateless group's frame threads (0 for a stateful one).
    pub threads: u32,
}

impl Group {
    /// Records what any view of this frame needs, whatever draws it: a stateless effect's
    /// segment table, and for `sort: true` the depth keys and their sort along `camera`'s axis.
    pub(crate) fn prepare_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> Result<PreparedFrame, RuntimeError> {
        let mut frame = PreparedFrame {
            steps: self.schedule.steps_done(),
            threads: 0,
        };
        if let Steps::Stateless(stateless) = &self.steps {
            frame.threads = self.copy_frame(encoder, stateless)?;
        }
        if let Some(depth) = &self.depth {
            self.copy_depth_axis(encoder, camera)?;
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("depth sort"),
                timestamp_writes: None,
            });
            depth.record(
                &self.gpu,
                &mut pass,
                &self.res,
                self.sort_chunks()?,
                SortAlgorithm::Radix,
            )?;
        }
        Ok(frame)
    }

    /// Records the copy of `camera`'s depth axis into the sort's uniform.
    fn copy_depth_axis(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        let src = staging(&self.gpu, "depth axis", &camera.depth_axis_bytes())?;
        encoder.copy_buffer_to_buffer(&src, 0, &sort_buffers(&self.res)?.depth_axis, 0, 16);
        Ok(())
    }

    /// The effect's own camera (its view matrix is all the sort uses).
    pub(crate) fn effect_camera(&self) -> Camera {
        Camera::from_effect(&self.effect.ir.camera, 1.0)
    }

    /// Sorts every slot by depth along `camera`'s axis on the GPU (farthest first, free slots
    /// last) and returns the live slots in draw order, each with its 16-bit key
    /// ([`crate::sort::quantise`]).
    pub(crate) fn draw_order_from(
        &self,
        camera: &Camera,
        algorithm: SortAlgorithm,
    ) -> Result<Vec<(u32, u32)>, RuntimeError> {
        let depth = self.depth()?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        if let Steps::Stateless(stateless) = &self.steps {
            self.copy_frame(&mut encoder, stateless)?;
        }
        self.copy_depth_axis(&mut encoder, camera)?;
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            depth.record(
                &self.gpu,
                &mut pass,
                &self.res,
                self.sort_chunks()?,
                algorithm,
            )?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        let alive = self.totals()?.alive as usize;
        let buffers = sort_buffers(&self.res)?;
        let keys = read_words(&self.gpu, &buffers.keys, alive)?;
        let slots = read_words(&self.gpu, &buffers.vals, alive)?;
        Ok(slots.into_iter().zip(keys).collect())
    }

    /// [`Self::draw_order_from`] the effect's own camera.
    pub(crate) fn draw_order(
        &self,
        algorithm: SortAlgorithm,
    ) -> Result<Vec<(u32, u32)>, RuntimeError> {
        self.draw_order_from(&self.effect_camera(), algorithm)
    }

    /// The live particles in draw order: sorted by their 16-bit depth keys on the GPU,
    /// farthest first; equal keys by id, so the order is the same run after run.
    pub(crate) fn records_in_draw_order(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let order = self.draw_order(SortAlgorithm::Radix)?;
        let by_slot = self.records_by_slot()?;
        let mut out: Vec<(u32, ParticleRecord)> = Vec::with_capacity(order.len());
        for (slot, key) in order {
            let record = by_slot
                .get(slot as usize)
                .copied()
                .flatten()
                .ok_or_else(|| {
                    RuntimeError::Readback(format!("sorted slot {slot} holds no live particle"))
                })?;
            out.push((key, record));
        }
        // Stable: equal keys (depths within one key step) by id.
        out.sort_by_key(|(key, r)| (*key, r.id));
        Ok(out.into_iter().map(|(_, r)| r).collect())
    }
}
