//! What the compute renderer's groups bind: the tile kernels of `splat.wgsl` and their shared layout (which
//! `additive_lists.wgsl` shares too), the bind groups of the generated kernels (buffers, and the sprite texture where there is one),
//! the trail module a group's ribbons are drawn from, and the check that a frame's entry lists are
//! complete.

use plume_compiler::wgsl::draw::DrawShape;
use plume_compiler::wgsl::trail;

use crate::device::buffers::filled_buffer;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// The tile kernels' bindings: (binding, read-only storage?, uniform?), as `splat.wgsl`
/// declares them.
const TILE_BINDINGS: [(u32, bool, bool); 12] = [
    (0, true, true),
    (1, true, false),
    (2, true, false),
    (3, true, false),
    (4, false, false),
    (5, false, false),
    (6, false, false),
    (7, false, false),
    (8, false, false),
    (9, true, false),
    (10, false, false),
    (11, false, false),
];

/// The layout every tile kernel shares (each uses a subset).
pub(super) fn tile_layout(gpu: &Gpu) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = TILE_BINDINGS
        .iter()
        .map(
            |&(binding, read_only, is_uniform)| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: if is_uniform {
                        wgpu::BufferBindingType::Uniform
                    } else {
                        wgpu::BufferBindingType::Storage { read_only }
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        )
        .collect();
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("splat tiles"),
            entries: &entries,
        })
}

/// The five tile kernels of `splat.wgsl` on the shared layout.
pub(super) fn tile_kernels(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
) -> Result<[wgpu::ComputePipeline; 5], RuntimeError> {
    let device = &gpu.device;
    // The fixed point additive discs are summed in, as the generated composites sum light.
    let source = format!(
        "{}\n{}{}",
        plume_compiler::wgsl::draw::splat_light_constants(),
        include_str!("tiles_shared.wgsl"),
        include_str!("splat.wgsl")
    );
    let module = gpu.shader_module("splat", &source);
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("splat tiles"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let kernel = |entry| gpu.compute_pipeline(&module, entry, Some(&pipeline_layout));
    let kernels = [
        kernel("clear"),
        kernel("emit"),
        kernel("find_ranges"),
        kernel("raster"),
        kernel("merge_discs"),
    ];
    gpu.take_error()?;
    Ok(kernels)
}

/// A uniform buffer of `words`.
pub(super) fn uniform(gpu: &Gpu, label: &str, words: &[u32]) -> Result<wgpu::Buffer, RuntimeError> {
    filled_buffer(
        gpu,
        label,
        (words.len() as u64 * 4).next_multiple_of(16),
        wgpu::BufferUsages::UNIFORM,
        |b| {
            for (w, out) in words.iter().zip(b.chunks_exact_mut(4)) {
                out.copy_from_slice(&w.to_le_bytes());
            }
        },
    )
}

/// A bind group of `layout` from (binding, buffer) pairs.
pub(super) fn bind(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    all: &[(u32, wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<(u32, &wgpu::Buffer)> = all.iter().map(|(b, buffer)| (*b, buffer)).collect();
    gpu.bind_buffers("splat", layout, &entries)
}

/// The trail draw module of `effect` in the compute renderer's shape (its `project` and `composite` for
/// ribbon segments) and the buffers it reads, as the raster trail draw binds them: every
/// slot, in the depth order when the effect sorts.
pub(super) fn ribbon_module(
    gpu: &Gpu,
    effect: &plume_compiler::CompiledEffect,
    res: &crate::device::resources::Resources,
    shape: DrawShape,
) -> Result<(wgpu::ShaderModule, Vec<(u32, wgpu::Buffer)>), RuntimeError> {
    let shape = DrawShape {
        through_list: effect.ir.sort,
        primitive: plume_compiler::wgsl::draw::Primitive::Quad,
        ..shape
    };
    let source = trail::emit(&effect.ir, &effect.layout, &shape);
    let module = gpu.shader_module("splat ribbons", &source);
    let entries = crate::draw::trail::trail_buffers(effect, res, shape.through_list)?;
    Ok((module, entries))
}

/// Whether a frame's sorted entries hold every sprite exactly as many times as `project`
/// counted tiles for it, from `[status, counts, entries]` read back (for tests).
pub(super) fn entries_are_complete(
    gpu: &crate::device::gpu::Gpu,
    [status, counts, entries]: [&wgpu::Buffer; 3],
) -> Result<bool, crate::error::RuntimeError> {
    let read = |b: &wgpu::Buffer| crate::device::readback::read_words(gpu, b, usize::MAX);
    let needed = read(status)?[0] as usize;
    let counts = read(counts)?;
    let sprites = read(entries)?;
    let mut seen = vec![0u32; counts.len()];
    for &k in sprites.iter().take(needed) {
        match seen.get_mut(k as usize) {
            Some(n) => *n += 1,
            None => return Ok(false),
        }
    }
    Ok(needed <= sprites.len() && seen == counts[..seen.len()])
}

/// Records a part's view before the compute renderer's pass: its lit look's lights in the
/// camera's view (`lights`, if lit), then the camera, the steps done and the sprites' size
/// scale into `draw_view`.
pub(super) fn record_part_view(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    (draw_view, lights): (&wgpu::Buffer, Option<&crate::draw::lights::LightsUniform>),
    camera: &crate::draw::camera::Camera,
    (steps, size_scale): (u64, f32),
) -> Result<(), RuntimeError> {
    if let Some(lights) = lights {
        lights.record(gpu, encoder, camera)?;
    }
    crate::draw::camera::record_draw_view(gpu, encoder, draw_view, camera, steps, size_scale)
}
