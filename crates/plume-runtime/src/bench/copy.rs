//! The copy kernel `plume bench` times the update against: the same bytes read once and
//! written once (or in place, or only written), over buffers of its own.

use crate::bench::timer::PassTimer;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// The copy kernel: 16 bytes a thread, 2D-indexed like the effect kernels.
const COPY_WGSL: &str = r#"
@group(0) @binding(0) var<storage, read> src: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> dst: array<vec4<u32>>;

@compute @workgroup_size(256)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = src[i];
    }
}

// The same words read and written back in place, as the update does (one buffer, not two).
@compute @workgroup_size(256)
fn copy_in_place(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = dst[i] + vec4<u32>(1u);
    }
}

// Write-only: the ceiling of a kernel that reads no state (the stateless evaluate). It takes
// src's length only, so both kernels share one bind group layout.
@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = vec4<u32>(i);
    }
}
"#;

/// A pass of `entry` (`copy`: read and write `bytes`, rounded up to 16; `copy_in_place`: the
/// same, reading and writing one buffer; `fill`: write them only) over buffers of its own,
/// split into buffers of at most one binding each.
pub(crate) struct CopyKernel {
    pipeline: wgpu::ComputePipeline,
    /// Per buffer: its bind group, the dispatch size, and the buffers it binds.
    parts: Vec<(wgpu::BindGroup, u32, u32, wgpu::Buffer, wgpu::Buffer)>,
    gpu: Gpu,
}

impl CopyKernel {
    pub(crate) fn new(gpu: &Gpu, bytes: u64, entry: &str) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size)
            / 16
            * 16;
        let module = gpu.shader_module("copy", COPY_WGSL);
        let pipeline = gpu.compute_pipeline(&module, entry, None);
        let layout = pipeline.get_bind_group_layout(0);
        let mut parts = Vec::new();
        let mut left = bytes.next_multiple_of(16).max(16);
        while left > 0 {
            let size = left.min(limit);
            left -= size;
            let make = |label| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            };
            let (src, dst) = (make("copy src"), make("copy dst"));
            let group = gpu.bind_buffers("copy", &layout, &[(0, &src), (1, &dst)]);
            let (x, y) = gpu.grid(size / 16, 256)?;
            parts.push((group, x, y, src, dst));
        }
        let kernel = Self {
            pipeline,
            parts,
            gpu: gpu.clone(),
        };
        gpu.take_error()?;
        Ok(kernel)
    }

    /// Seconds for `repeats` passes, in one compute pass (after one untimed pass).
    pub(crate) fn time(&self, timer: &PassTimer<'_>, repeats: u32) -> Result<f64, RuntimeError> {
        let record = |pass: &mut wgpu::ComputePass<'_>, n: u32| {
            pass.set_pipeline(&self.pipeline);
            for _ in 0..n {
                for (group, x, y, _, _) in &self.parts {
                    pass.set_bind_group(0, group, &[]);
                    pass.dispatch_workgroups(*x, *y, 1);
                }
            }
            Ok(())
        };
        timer.time(|pass| record(pass, 1))?;
        let seconds = timer.time(|pass| record(pass, repeats))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }
}
