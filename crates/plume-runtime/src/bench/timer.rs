//! GPU timing of one compute or render pass: timestamp queries at the pass's beginning and end
//! where the adapter has them, otherwise the wall clock around a submission and its completion.

use std::time::Instant;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Measures one compute pass at a time.
pub struct PassTimer<'g> {
    gpu: &'g Gpu,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
}

/// How a duration was measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingSource {
    /// GPU timestamps at the pass boundaries.
    Timestamps,
    /// Wall clock from submission to completion (includes submission overhead).
    WallClock,
}

impl<'g> PassTimer<'g> {
    /// A timer on `gpu`.
    pub fn new(gpu: &'g Gpu) -> Self {
        let queries = gpu.has_timestamps().then(|| {
            let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        Self { gpu, queries }
    }

    /// Which clock this timer uses.
    pub fn source(&self) -> TimingSource {
        if self.queries.is_some() {
            TimingSource::Timestamps
        } else {
            TimingSource::WallClock
        }
    }

    /// Records one compute pass with `record`, submits it, waits, and returns its duration (s).
    pub fn time(
        &self,
        record: impl FnOnce(&mut wgpu::ComputePass<'_>) -> Result<(), RuntimeError>,
    ) -> Result<f64, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let timestamp_writes =
                self.queries
                    .as_ref()
                    .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("timed"),
                timestamp_writes,
            });
            record(&mut pass)?;
        }
        self.finish(encoder)
    }

    /// Records with `record`, which must pass the given timestamp writes (None without
    /// timestamps) to the one render pass it times; submits, waits, and returns the render
    /// pass's duration (s), or the whole submission's without timestamps.
    pub(crate) fn time_render(
        &self,
        record: impl FnOnce(
            &mut wgpu::CommandEncoder,
            Option<wgpu::RenderPassTimestampWrites<'_>>,
        ) -> Result<(), RuntimeError>,
    ) -> Result<f64, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let timestamp_writes =
            self.queries
                .as_ref()
                .map(|(set, _)| wgpu::RenderPassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                });
        record(&mut encoder, timestamp_writes)?;
        self.finish(encoder)
    }

    /// Resolves the timestamps (if any), submits, waits and returns the duration (s).
    fn finish(&self, mut encoder: wgpu::CommandEncoder) -> Result<f64, RuntimeError> {
        let device = &self.gpu.device;
        let readback = self.queries.as_ref().map(|(set, resolve)| {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            let read = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps read"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_buffer_to_buffer(resolve, 0, &read, 0, 16);
            read
        });
        let start = Instant::now();
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.wait()?;
        let wall = start.elapsed().as_secs_f64();
        let Some(read) = readback else {
            return Ok(wall);
        };
        let (tx, rx) = std::sync::mpsc::channel();
        read.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.gpu.wait()?;
        rx.recv()
            .map_err(|e| RuntimeError::Readback(e.to_string()))?
            .map_err(|e| RuntimeError::Readback(e.to_string()))?;
        let ticks = {
            let data = read
                .get_mapped_range(..)
                .map_err(|e| RuntimeError::Readback(e.to_string()))?;
            let t =
                |i: usize| u64::from_le_bytes(data[8 * i..8 * i + 8].try_into().expect("8 bytes"));
            t(1).saturating_sub(t(0))
        };
        read.unmap();
        Ok(ticks as f64 * f64::from(self.gpu.queue.get_timestamp_period()) * 1e-9)
    }
}

/// Runs `run` once to warm up, then `repeats` times (at least once), and returns the median of
/// the timed runs' seconds.
pub fn median_after_warmup(
    repeats: u32,
    mut run: impl FnMut() -> Result<f64, RuntimeError>,
) -> Result<f64, RuntimeError> {
    run()?;
    let mut samples = (0..repeats.max(1))
        .map(|_| run())
        .collect::<Result<Vec<f64>, RuntimeError>>()?;
    samples.sort_by(f64::total_cmp);
    Ok(samples[samples.len() / 2])
}
