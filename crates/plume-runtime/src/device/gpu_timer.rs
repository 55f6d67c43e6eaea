//! The GPU time of work a host records into its encoder, read back without waiting: a
//! timestamp written by an empty compute pass before the work and one after (or, for a draw
//! among others in the host's render pass, written inside that pass), resolved and copied into
//! a reading ([`crate::device::async_read`]) a frame or two before it is taken.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::device::async_read::AsyncRead;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Times the work recorded between [`Self::begin`] and [`Self::end`] on the GPU, without
/// waiting for it: each `begin` hands back the time of an earlier frame's work once its
/// reading has come back. A frame whose `begin` finds the last reading still out is not
/// timed.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::{Effect, Gpu, GpuTimer};
/// let source = r#"Effect(name: "puff", capacity: 64, state: Stateful,
///     emitters: [Emitter(burst: 64, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))])"#;
/// let gpu = Gpu::new(&Default::default())?;
/// let Some(mut timer) = GpuTimer::new(&gpu) else {
///     return Ok(()); // the adapter has no timestamp queries
/// };
/// let mut puff = Effect::from_source(&gpu, source, &Default::default())?;
/// let mut timed = None;
/// for _ in 0..4 {
///     let mut encoder = gpu.device.create_command_encoder(&Default::default());
///     timed = timer.begin(&mut encoder)?.or(timed);
///     puff.advance(&mut encoder, 1)?;
///     timer.end(&mut encoder);
///     gpu.queue.submit([encoder.finish()]);
///     gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
/// }
/// let ns = timed.expect("a reading came back");
/// assert!(ns < 1_000_000_000);
/// # Ok(())
/// # }
/// ```
pub struct GpuTimer {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    reading: AsyncRead,
    /// Nanoseconds a tick.
    period: f32,
    /// Whether this frame's work is timed: its first timestamp written, or for stamps inside
    /// a render pass, to be written.
    begun: bool,
    /// Whether the end of the work was stamped inside a render pass this frame.
    stamped_in_pass: AtomicBool,
}

impl GpuTimer {
    /// A timer on `gpu`; None where the device has no timestamp queries.
    pub fn new(gpu: &Gpu) -> Option<Self> {
        if !gpu.has_timestamps() {
            return None;
        }
        Some(Self {
            set: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("gpu timer"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gpu timer resolved"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            reading: AsyncRead::new(gpu, "gpu timer reading", 16),
            period: gpu.queue.get_timestamp_period(),
            begun: false,
            stamped_in_pass: AtomicBool::new(false),
        })
    }

    /// A timer whose stamps go inside the host's render pass ([`Self::stamp_in_pass`]), for a
    /// draw recorded among others in a pass the host owns; None where the device cannot write
    /// timestamps inside passes (`TIMESTAMP_QUERY_INSIDE_PASSES`).
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{Gpu, GpuTimer};
    /// let gpu = Gpu::new(&Default::default())?;
    /// let Some(mut timer) = GpuTimer::in_passes(&gpu) else {
    ///     return Ok(()); // no timestamps inside passes
    /// };
    /// let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
    ///     label: None,
    ///     size: wgpu::Extent3d { width: 4, height: 4, depth_or_array_layers: 1 },
    ///     mip_level_count: 1,
    ///     sample_count: 1,
    ///     dimension: wgpu::TextureDimension::D2,
    ///     format: wgpu::TextureFormat::Rgba8Unorm,
    ///     usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
    ///     view_formats: &[],
    /// });
    /// let view = target.create_view(&Default::default());
    /// let mut timed = None;
    /// for _ in 0..4 {
    ///     timed = timer.begin_in_pass()?.or(timed);
    ///     let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ///     {
    ///         let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
    ///             color_attachments: &[Some(wgpu::RenderPassColorAttachment {
    ///                 view: &view,
    ///                 depth_slice: None,
    ///                 resolve_target: None,
    ///                 ops: wgpu::Operations::default(),
    ///             })],
    ///             ..Default::default()
    ///         });
    ///         timer.stamp_in_pass(&mut pass, false);
    ///         // ... the host's draw, e.g. `EffectRenderer::draw(&mut pass)` ...
    ///         timer.stamp_in_pass(&mut pass, true);
    ///     }
    ///     timer.end_after_pass(&mut encoder);
    ///     gpu.queue.submit([encoder.finish()]);
    ///     gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    /// }
    /// assert!(timed.expect("a reading came back") < 1_000_000_000);
    /// # Ok(())
    /// # }
    /// ```
    pub fn in_passes(gpu: &Gpu) -> Option<Self> {
        let inside = wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES;
        match gpu.device.features().contains(inside) {
            true => Self::new(gpu),
            false => None,
        }
    }

    /// An empty compute pass that writes timestamp `index` at its start (0) or end (1).
    fn stamp(&self, encoder: &mut wgpu::CommandEncoder, index: u32) {
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gpu timer stamp"),
            timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                query_set: &self.set,
                beginning_of_pass_write_index: (index == 0).then_some(0),
                end_of_pass_write_index: (index == 1).then_some(1),
            }),
        });
    }

    /// Before the work: takes a reading that came back (nanoseconds) and, when the last one
    /// was taken, stamps this frame's start.
    pub fn begin(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Option<u64>, RuntimeError> {
        let taken = self.take_reading()?;
        self.begun = self.reading.is_free();
        if self.begun {
            self.stamp(encoder, 0);
        }
        Ok(taken)
    }

    /// Before the render pass that [`Self::stamp_in_pass`] stamps: takes a reading that came
    /// back (nanoseconds) and, when the last one was taken, times this frame's work.
    pub fn begin_in_pass(&mut self) -> Result<Option<u64>, RuntimeError> {
        let taken = self.take_reading()?;
        self.begun = self.reading.is_free();
        self.stamped_in_pass.store(false, Ordering::Relaxed);
        Ok(taken)
    }

    /// Writes the start (`end` false) or the end of the timed work into the host's render
    /// pass, when this frame is timed. Only for a timer made by [`Self::in_passes`].
    pub fn stamp_in_pass(&self, pass: &mut wgpu::RenderPass<'_>, end: bool) {
        if self.begun {
            pass.write_timestamp(&self.set, u32::from(end));
            self.stamped_in_pass.store(end, Ordering::Relaxed);
        }
    }

    /// After the render pass: records the timestamps' copy when both were written this frame
    /// (a frame whose work was not recorded goes untimed).
    pub fn end_after_pass(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let stamped = self.stamped_in_pass.swap(false, Ordering::Relaxed);
        if std::mem::take(&mut self.begun) && stamped {
            encoder.resolve_query_set(&self.set, 0..2, &self.resolved, 0);
            self.reading.record_copy(encoder, &self.resolved);
        }
    }

    /// The nanoseconds between an earlier frame's stamps, once their reading has come back.
    fn take_reading(&mut self) -> Result<Option<u64>, RuntimeError> {
        Ok(self.reading.poll()?.map(|bytes| {
            let tick =
                |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
            (tick(8).saturating_sub(tick(0)) as f64 * f64::from(self.period)) as u64
        }))
    }

    /// Whether the last [`Self::begin`] stamped a start (the work then recorded is timed).
    pub fn is_begun(&self) -> bool {
        self.begun
    }

    /// After the work: stamps its end and records the timestamps' copy, when begun.
    pub fn end(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if !std::mem::take(&mut self.begun) {
            return;
        }
        self.stamp(encoder, 1);
        encoder.resolve_query_set(&self.set, 0..2, &self.resolved, 0);
        self.reading.record_copy(encoder, &self.resolved);
    }
}
