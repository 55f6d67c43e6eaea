//! The shadow map of the scene's meshes (`outputs/scene.rs`) for the directional light that
//! casts a shadow (`Directional(.., shadow: true)`): the meshes' depth seen from the light by
//! an orthographic projection that holds their bounding sphere and reaches far past it, one
//! 2048 x 2048 layer. The
//! scene's own pass and the particles' lit draws read it (`plume_compiler::shadow`).

use glam::{DMat4, DVec3};
use plume_compiler::shadow::{Shadow, ShadowDepths};

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Texels on a side of the scene's shadow map.
pub const SHADOW_MAP_SIZE: u32 = 2048;

/// The map's format.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The depth-only pass: each vertex through the light's projection.
const SHADER: &str = r#"
@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;

@vertex
fn vs(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return clip_from_world * vec4<f32>(position, 1.0);
}
"#;

/// The scene's meshes seen from a directional light: the map and its projection.
pub struct SceneShadow {
    texture: wgpu::Texture,
    clip_from_world: DMat4,
    /// The unit direction the light travels, which the map was drawn for.
    direction: DVec3,
    gpu: Gpu,
}

impl SceneShadow {
    /// Draws the map of the `count` vertices in `vertices` (position then normal, 24 bytes
    /// each, world space; inside the box `bounds`) seen along `direction`, and waits for it.
    pub(crate) fn draw(
        gpu: &Gpu,
        (vertices, count): (&wgpu::Buffer, u32),
        bounds: (DVec3, DVec3),
        direction: DVec3,
    ) -> Result<Self, RuntimeError> {
        let direction = direction.normalize_or_zero();
        let clip_from_world = projection(bounds, direction);
        let device = &gpu.device;
        let texture = gpu.texture_2d(
            "scene shadow map",
            (SHADOW_MAP_SIZE, SHADOW_MAP_SIZE),
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let words: Vec<u8> = clip_from_world
            .as_mat4()
            .to_cols_array()
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let uniform = crate::device::buffers::filled_buffer(
            gpu,
            "shadow projection",
            64,
            wgpu::BufferUsages::UNIFORM,
            |b| b.copy_from_slice(&words),
        )?;
        let module = gpu.shader_module("scene shadow", SHADER);
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("scene shadow"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            // Biased by its slope, so that a lit surface is not shadowed by its own texels.
            depth_stencil: Some(wgpu::DepthStencilState {
                format: FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: wgpu::DepthBiasState {
                    constant: 4,
                    slope_scale: 2.5,
                    clamp: 0.0,
                },
            }),
            multisample: Default::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene shadow"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        let view = texture.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.draw(0..count, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error()?;
        Ok(Self {
            texture,
            clip_from_world,
            direction,
            gpu: gpu.clone(),
        })
    }

    /// Whether the map was drawn for light travelling along `direction`.
    pub(crate) fn is_along(&self, direction: DVec3) -> bool {
        self.direction == direction.normalize_or_zero()
    }

    /// The map (for [`crate::EffectRenderer::set_shadow_map`]).
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// The shadow that this map casts for source `source` (its one cascade).
    pub fn shadow(&self, source: usize) -> Shadow {
        Shadow {
            cascades: vec![self.clip_from_world],
            ..Shadow::of_source(source)
        }
    }

    /// The map's depths read back (waits for the GPU), for the f64 light
    /// ([`Shadow::visibility`]).
    pub fn read_depths(&self) -> Result<ShadowDepths, RuntimeError> {
        let depths = crate::device::depth_copy::read_depths(&self.gpu, &self.texture)?;
        Ok(ShadowDepths {
            width: SHADOW_MAP_SIZE,
            height: SHADOW_MAP_SIZE,
            layers: vec![depths],
        })
    }
}

/// How far past the meshes' bounding sphere the map reaches, in radii: a point beyond it is
/// in no cascade, and lit.
const REACH: f64 = 100.0;

/// The light's orthographic projection of the sphere around `bounds`: looking along
/// `direction` from outside it, the sphere filling the square, depth 0 at its near side and
/// 1 [`REACH`] radii past its far side (a particle below the meshes is still in their
/// shadow).
fn projection((min, max): (DVec3, DVec3), direction: DVec3) -> DMat4 {
    let centre = (min + max) * 0.5;
    let radius = ((max - min).length() * 0.5).max(1e-3) * 1.01;
    let eye = centre - direction * (2.0 * radius);
    // Any up that is not along the light.
    let up = match direction.y.abs() > 0.9 {
        true => DVec3::Z,
        false => DVec3::Y,
    };
    let view = DMat4::look_at_rh(eye, centre, up);
    let far = (3.0 + REACH) * radius;
    DMat4::orthographic_rh(-radius, radius, -radius, radius, radius, far) * view
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_projection_holds_the_bounds_between_its_planes() {
        let bounds = (DVec3::new(-2.0, 0.0, -1.0), DVec3::new(3.0, 4.0, 1.0));
        let direction = DVec3::new(0.3, -1.0, 0.2).normalize();
        let m = projection(bounds, direction);
        for i in 0..8 {
            let corner = DVec3::new(
                if i & 1 == 0 { bounds.0.x } else { bounds.1.x },
                if i & 2 == 0 { bounds.0.y } else { bounds.1.y },
                if i & 4 == 0 { bounds.0.z } else { bounds.1.z },
            );
            let q = m.project_point3(corner);
            assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0, "{q}");
            assert!((0.0..=1.0).contains(&q.z), "{q}");
        }
        // Nearer the light is smaller depth.
        let c = (bounds.0 + bounds.1) * 0.5;
        assert!(m.project_point3(c - direction).z < m.project_point3(c + direction).z);
    }
}
