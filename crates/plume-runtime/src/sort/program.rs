//! A sort's recorded dispatches ([`SortProgram`]) and the buffers its builders make: shared by
//! the reduce-then-scan radix sort ([`crate::sort::radix`]) and OneSweep
//! ([`crate::sort::onesweep`]).

use wgpu::util::DeviceExt;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// One recorded dispatch of a sort.
struct Dispatch {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    x: u32,
    y: u32,
}

/// A sort of fixed buffers and length, built once and recorded any number of times.
#[derive(Default)]
pub struct SortProgram {
    dispatches: Vec<Dispatch>,
}

impl SortProgram {
    /// Records the sort's dispatches into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.record_first(pass, self.dispatches.len());
    }

    /// Records only the first `count` dispatches (the benchmark times the radix sort's
    /// stages by difference: a pass is upsweep, digit scan, downsweep).
    pub(crate) fn record_first(&self, pass: &mut wgpu::ComputePass<'_>, count: usize) {
        for d in self.dispatches.iter().take(count) {
            pass.set_pipeline(&d.pipeline);
            pass.set_bind_group(0, &d.group, &[]);
            pass.dispatch_workgroups(d.x, d.y, 1);
        }
    }

    /// Adds `pipeline` over `groups` workgroups (2D past the per-dimension limit) with the
    /// given (binding, buffer) entries.
    pub(crate) fn push(
        &mut self,
        gpu: &Gpu,
        pipeline: &wgpu::ComputePipeline,
        entries: &[(u32, &wgpu::Buffer)],
        groups: u64,
    ) -> Result<(), RuntimeError> {
        let group = gpu.bind_buffers("sort", &pipeline.get_bind_group_layout(0), entries);
        let (x, y) = gpu.grid(groups, 1)?;
        self.dispatches.push(Dispatch {
            pipeline: pipeline.clone(),
            group,
            x,
            y,
        });
        Ok(())
    }
}

/// A uniform buffer of `words`.
pub(crate) fn uniform(gpu: &Gpu, words: &[u32]) -> wgpu::Buffer {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sort params"),
            contents: &bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// A storage buffer of `words` words (at least one).
pub(crate) fn buffer(gpu: &Gpu, label: &str, words: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: words.max(1) * 4,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
