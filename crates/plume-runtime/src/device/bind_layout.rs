//! The compute module's bind group layout: one entry per binding of the compiled layout, typed
//! by what it holds (uniforms, read-only and read-write storage).

use plume_compiler::CompiledEffect;

/// A compute-visible buffer entry.
pub(crate) fn buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    dynamic: bool,
    min: Option<u64>,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: min.and_then(wgpu::BufferSize::new),
        },
        count: None,
    }
}

/// The entries of `effect`'s shared bind group layout.
pub(crate) fn entries(effect: &CompiledEffect) -> Vec<wgpu::BindGroupLayoutEntry> {
    let rw = wgpu::BufferBindingType::Storage { read_only: false };
    effect
        .layout
        .bindings
        .iter()
        .map(|b| match b.name {
            "params" => buffer_entry(
                b.binding,
                match effect.layout.batched {
                    // A row per instance: more than a uniform binding may hold.
                    true => wgpu::BufferBindingType::Storage { read_only: true },
                    false => wgpu::BufferBindingType::Uniform,
                },
                true,
                Some(effect.layout.params_bytes()),
            ),
            "chunk" | "depth_axis" => {
                buffer_entry(b.binding, wgpu::BufferBindingType::Uniform, false, Some(16))
            }
            // The step a stateless group's `fire` fires for: one a step of the batch, each at
            // its own offset (`StatelessSteps::record_fire`).
            "fire_state" => buffer_entry(
                b.binding,
                wgpu::BufferBindingType::Storage { read_only: true },
                true,
                Some(b.bytes),
            ),
            "scene_camera" => buffer_entry(
                b.binding,
                wgpu::BufferBindingType::Uniform,
                false,
                Some(b.bytes),
            ),
            "frame" | "fire_frame" | "collider_data" | "force_data" | "spawn_data"
            | "scene_depth" | "instance_models" => buffer_entry(
                b.binding,
                wgpu::BufferBindingType::Storage { read_only: true },
                false,
                None,
            ),
            _ => buffer_entry(b.binding, rw, false, None),
        })
        .collect()
}
