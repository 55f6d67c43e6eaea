//! The compute module's bind group layout: one entry per binding of the compiled layout, typed
//! by what it holds (uniforms, read-only and read-write storage).

use plume_compiler::passes::layout::{Role, Space};
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

/// The entries of `effect`'s shared bind group layout: each binding typed by the address
/// space the module declares it in, bound at a dynamic offset where the runtime moves it per
/// step.
pub(crate) fn entries(effect: &CompiledEffect) -> Vec<wgpu::BindGroupLayoutEntry> {
    effect
        .layout
        .bindings
        .iter()
        .map(|b| {
            let ty = match b.space {
                Space::Uniform => wgpu::BufferBindingType::Uniform,
                Space::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Space::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            };
            match b.role {
                // A step's parameters (a batch's: a row per instance), at the step's offset.
                Role::Params => {
                    buffer_entry(b.binding, ty, true, Some(effect.layout.params_bytes()))
                }
                // The step a stateless group's `fire` fires for: one a step of the submission, each
                // at its own offset (`StatelessSteps::record_fire`).
                Role::FireState => buffer_entry(b.binding, ty, true, Some(b.bytes)),
                Role::Chunk | Role::DepthAxis => buffer_entry(b.binding, ty, false, Some(16)),
                Role::SceneCamera => buffer_entry(b.binding, ty, false, Some(b.bytes)),
                _ => buffer_entry(b.binding, ty, false, None),
            }
        })
        .collect()
}
