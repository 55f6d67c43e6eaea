//! How many instances a particle draw issues ([`Instances`]): every slot, the stateless
//! frame's threads, the compacted live list, or as many as are alive, counted on the GPU into
//! an indirect draw's arguments ([`alive_instances`]).

use std::sync::atomic::AtomicU32;

use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::device::resources::Resources;
use crate::draw::live_list::LiveList;
use crate::error::RuntimeError;

/// How many instances a draw issues.
pub(crate) enum Instances {
    /// One per slot of the capacity.
    Slots(u32),
    /// The stateless frame's threads, set when the frame is prepared.
    Frame(AtomicU32),
    /// The compacted live slots, drawn indirectly.
    Compacted(Box<LiveList>),
    /// Written on the GPU: an indirect draw whose instance count is capacity − free count.
    Alive {
        args: wgpu::Buffer,
        kernel: wgpu::ComputePipeline,
        group: wgpu::BindGroup,
    },
}

/// Writes the indirect draw's instance count (word 1, in both the plain and the indexed
/// form) from the counters: capacity − free count. Word 0 holds the vertices (or indices) per
/// sprite and word 5, past both forms, the capacity, written once; the rest are zero.
const DRAW_ARGS_WGSL: &str = r#"
@group(0) @binding(0) var<storage, read> counters: array<u32>;
@group(0) @binding(1) var<storage, read_write> args: array<u32>;

@compute @workgroup_size(1)
fn draw_args() {
    args[1] = args[5] - min(counters[0], args[5]);
}
"#;

/// An indirect draw of the live particles (a sorted stateful effect: they come first in the
/// depth order) and the kernel that writes its count.
pub(crate) fn alive_instances(
    gpu: &Gpu,
    res: &Resources,
    capacity: u32,
    vertices: u32,
) -> Result<Instances, RuntimeError> {
    let device = &gpu.device;
    let args = filled_buffer(
        gpu,
        "draw args",
        32,
        STORAGE | wgpu::BufferUsages::INDIRECT,
        |b| {
            b[..4].copy_from_slice(&vertices.to_le_bytes());
            b[20..24].copy_from_slice(&capacity.to_le_bytes());
        },
    )?;
    let module = gpu.shader_module("draw args", DRAW_ARGS_WGSL);
    let kernel = gpu.compute_pipeline(&module, "draw_args", None);
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("draw args"),
        layout: &kernel.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: res
                    .counters
                    .as_ref()
                    .expect("a stateful effect has counters")
                    .as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: args.as_entire_binding(),
            },
        ],
    });
    Ok(Instances::Alive {
        args,
        kernel,
        group,
    })
}
