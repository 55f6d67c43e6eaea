//! What the sprite and trail draws share: a render pipeline of a draw module's entry points
//! into a target, and bind group 0 of the buffers, texture and scene depth it binds.

use plume_compiler::schema::Blend;
use plume_compiler::texture::{SAMPLER_BINDING, TEXTURE_BINDING};

use crate::device::gpu::Gpu;
use crate::device::pipeline_cache::RenderKey;
use crate::draw::target::DrawTarget;
use crate::draw::texture::SpriteTexture;

/// A render pipeline of `module`'s (vertex, fragment) entry points into `target`, with its
/// layout derived from the module (only the bindings the shaders use), writing depth where
/// `target` has a depth test and `writes_depth`.
pub(crate) fn render_pipeline(
    gpu: &Gpu,
    module: &wgpu::ShaderModule,
    entries: (&str, &str),
    primitive: wgpu::PrimitiveState,
    target: &DrawTarget,
    blend: wgpu::BlendState,
) -> wgpu::RenderPipeline {
    vertex_pipeline(gpu, module, entries, primitive, target, blend, None, &[])
}

/// Primitives of `topology`, both faces drawn.
pub(crate) fn plain(topology: wgpu::PrimitiveTopology) -> wgpu::PrimitiveState {
    wgpu::PrimitiveState {
        topology,
        ..Default::default()
    }
}

/// [`render_pipeline`] with a pipeline layout of the caller's (None: derived) and vertex
/// buffers (the reference drawing feeds its quads and ribbons so).
#[allow(clippy::too_many_arguments)]
pub(crate) fn vertex_pipeline(
    gpu: &Gpu,
    module: &wgpu::ShaderModule,
    (vs, fs): (&str, &str),
    primitive: wgpu::PrimitiveState,
    target: &DrawTarget,
    blend: wgpu::BlendState,
    layout: Option<&wgpu::PipelineLayout>,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
) -> wgpu::RenderPipeline {
    let make = || {
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(vs),
                layout,
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive,
                depth_stencil: target.depth.map(|d| wgpu::DepthStencilState {
                    format: d.format,
                    depth_write_enabled: Some(target.writes_depth),
                    depth_compare: Some(d.compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: target.sample_count,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: target.color_format,
                        blend: Some(blend),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    };
    // Shared through the device's cache where the module and the target say it all (the
    // reference drawing's pipelines, with layouts and vertex buffers of their own, are not).
    if layout.is_some() || !buffers.is_empty() {
        return make();
    }
    let key = RenderKey {
        module: module.clone(),
        entries: (vs.to_string(), fs.to_string()),
        primitive,
        depth: target
            .depth
            .map(|d| (d.format, d.compare, target.writes_depth)),
        samples: target.sample_count,
        color: target.color_format,
        blend,
    };
    gpu.cache.render(key, make)
}

/// Bind group 0 of a draw: its buffers, the sprite texture and sampler when it has one, and
/// its `extra` resources (the scene depth when it is soft, a lit draw's shadow map).
pub(crate) fn draw_group(
    gpu: &Gpu,
    pipeline: &wgpu::RenderPipeline,
    buffers: &[(u32, wgpu::Buffer)],
    texture: Option<&SpriteTexture>,
    extra: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    bind_resources(
        gpu,
        &pipeline.get_bind_group_layout(0),
        buffers,
        texture,
        extra,
    )
}

/// A bind group of `layout` (a render pipeline's or the compute renderer's): `buffers`, the
/// sprite texture and sampler (and a lit look's maps, a second image) when there is one, and
/// the `extra` resources at their bindings (the scene depth, a shadow map and its samplers).
pub(crate) fn bind_resources(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, wgpu::Buffer)],
    texture: Option<&SpriteTexture>,
    extra: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    let mut bindings: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    if let Some(t) = texture {
        bindings.push(wgpu::BindGroupEntry {
            binding: TEXTURE_BINDING,
            resource: wgpu::BindingResource::TextureView(&t.view),
        });
        bindings.push(wgpu::BindGroupEntry {
            binding: SAMPLER_BINDING,
            resource: wgpu::BindingResource::Sampler(&t.sampler),
        });
    }
    let lit_maps = texture.map_or(&[][..], |t| &t.lit_maps[..]);
    for (map, binding) in lit_maps.iter().zip(plume_compiler::lit::LIT_MAP_BINDINGS) {
        bindings.push(wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(map),
        });
    }
    if let Some(second) = texture.and_then(|t| t.second.as_ref()) {
        bindings.push(wgpu::BindGroupEntry {
            binding: plume_compiler::texture::SECOND_TEXTURE_BINDING,
            resource: wgpu::BindingResource::TextureView(second),
        });
    }
    for (binding, resource) in extra {
        bindings.push(wgpu::BindGroupEntry {
            binding: *binding,
            resource: resource.clone(),
        });
    }
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("draw"),
        layout,
        entries: &bindings,
    })
}

/// The blend state of an effect's `Blend`: non-premultiplied "over" for `Alpha`; for
/// `Additive`, src · α added to the target (alpha composited over, so it stays 1); for
/// `Multiply` (whose fragments write rgb · α), target · (src + 1 − α); for `Mask` (opaque
/// fragments or none) and `Opaque`, the fragment replaces the target; for `Premultiplied` (fragments of
/// rgb · coverage), src + target · (1 − α).
pub(crate) fn blend_state(blend: Blend) -> wgpu::BlendState {
    match blend {
        Blend::Multiply => wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Dst,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        },
        Blend::Mask(_) | Blend::Opaque => wgpu::BlendState::REPLACE,
        Blend::Premultiplied => wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
        Blend::Alpha => wgpu::BlendState::ALPHA_BLENDING,
        Blend::Additive => wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::SrcAlpha,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::OVER,
        },
    }
}
