//! The scene around an effect in `plume render` and `plume preview`: the meshes the effect
//! names (its mesh colliders and mesh emitters, [`plume_compiler::EffectIr::scene_triangles`]),
//! drawn plainly (one grey, flat per triangle) into the colour image and a depth buffer before
//! the particles, so that an author sees what the particles hit: meshes hide the particles
//! behind them, and soft particles fade against them. They are lit by a plain light from
//! above ([`Scene::plain_lights`]), or by a lit effect's own lights ([`Scene::set_lights`]), so
//! that the particles and what they meet are lit alike; a directional light that casts a
//! shadow is blocked by the meshes' shadow map ([`Scene::cast_shadow`]), on them and on the
//! particles.

use glam::{DVec3, Mat4};
use plume_compiler::lights::{LightSource, Lights, LIGHTS_BYTES};
use plume_compiler::shadow::SHADOW_WGSL;

use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::lights::ShadowBinding;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::outputs::scene_shadow::SceneShadow;

/// The scene's depth buffer format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The surfaces' grey (linear RGB).
pub const SCENE_GREY: [f32; 3] = [0.42, 0.40, 0.38];

/// Bytes of one vertex: position and normal.
const VERTEX_BYTES: u64 = 24;

/// Bytes of the scene's uniforms: the view-projection, the eye and the surfaces' colour.
const UNIFORM_BYTES: u64 = 96;

/// Meshes ready to draw, and the depth buffer they are drawn into.
pub struct Scene {
    gpu: Gpu,
    vertices: wgpu::Buffer,
    count: u32,
    uniforms: wgpu::Buffer,
    /// The lights, world space (`plume_compiler::lights`' uniform).
    lights: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
    /// The box around the triangles (world space).
    bounds: (DVec3, DVec3),
    /// The shadow map the pass reads (a stand-in until a light casts one) and its samplers.
    shadow_binding: ShadowBinding,
    /// The meshes' shadow map, once a light casts one.
    shadow: Option<SceneShadow>,
    depth_texture: wgpu::Texture,
    depth: wgpu::TextureView,
    size: (u32, u32),
}

fn depth_buffer(gpu: &Gpu, (width, height): (u32, u32)) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = gpu.texture_2d(
        "scene depth",
        (width, height),
        DEPTH_FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let view = texture.create_view(&Default::default());
    (texture, view)
}

impl Scene {
    /// The scene of `triangles` (world space) for a `width` x `height` image of
    /// `color_format`; None when there are no triangles.
    pub fn new(
        gpu: &Gpu,
        triangles: &[[DVec3; 3]],
        color_format: wgpu::TextureFormat,
        (width, height): (u32, u32),
    ) -> Result<Option<Self>, RuntimeError> {
        if triangles.is_empty() {
            return Ok(None);
        }
        let device = &gpu.device;
        let mut bytes = Vec::with_capacity(triangles.len() * 3 * VERTEX_BYTES as usize);
        for [a, b, c] in triangles {
            let n = (*b - *a).cross(*c - *a).normalize_or_zero().as_vec3();
            for p in [a, b, c] {
                for x in p.as_vec3().to_array().into_iter().chain(n.to_array()) {
                    bytes.extend_from_slice(&x.to_le_bytes());
                }
            }
        }
        let vertices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene vertices"),
            size: bytes.len() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue.write_buffer(&vertices, 0, &bytes);
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene uniforms"),
            size: UNIFORM_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene lights"),
            size: LIGHTS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&lights, 0, &Self::plain_lights().uniform_bytes());
        let source = [
            include_str!("world_lights.wgsl"),
            SHADOW_WGSL,
            include_str!("scene.wgsl"),
        ]
        .concat();
        let module = gpu.shader_module("scene", &source);
        let mut entries = [0, 1]
            .map(|binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .to_vec();
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            count: None,
        });
        for binding in [3, 4] {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            });
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &entries,
        });
        let shadow = ShadowBinding::new(gpu);
        let bind_group = scene_group(gpu, &layout, (&uniforms, &lights), &shadow);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("scene"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: VERTEX_BYTES,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: color_format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let (depth_texture, depth) = depth_buffer(gpu, (width, height));
        gpu.take_error()?;
        let corners = triangles.iter().flatten();
        let bounds = (
            corners.clone().fold(DVec3::INFINITY, |a, p| a.min(*p)),
            corners.fold(DVec3::NEG_INFINITY, |a, p| a.max(*p)),
        );
        Ok(Some(Self {
            gpu: gpu.clone(),
            vertices,
            count: (triangles.len() * 3) as u32,
            uniforms,
            lights,
            layout,
            bind_group,
            pipeline,
            bounds,
            shadow_binding: shadow,
            shadow: None,
            depth_texture,
            depth,
            size: (width, height),
        }))
    }

    /// The scene of `triangles` drawn once from `camera` at `size` (into a colour image made and
    /// dropped here), for its depth alone: what a `SceneDepth` collider meets where nothing
    /// else draws the scene (`plume run`, `plume bench`). None when there are no triangles.
    pub fn depth_only(
        gpu: &Gpu,
        triangles: &[[DVec3; 3]],
        camera: &Camera,
        size: (u32, u32),
    ) -> Result<Option<Self>, RuntimeError> {
        let format = wgpu::TextureFormat::Rgba8UnormSrgb;
        let Some(scene) = Self::new(gpu, triangles, format, size)? else {
            return Ok(None);
        };
        let colour = gpu
            .texture_2d(
                "scene colour (dropped)",
                size,
                format,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
            .create_view(&Default::default());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        scene.record(
            &mut encoder,
            wgpu::RenderPassColorAttachment {
                view: &colour,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Discard,
                },
            },
            camera,
        );
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error()?;
        Ok(Some(scene))
    }

    /// The scene's light unless a lit effect brings its own: 0.3 of ambient light and 0.7 of a
    /// white light from above, a little behind and to the right ((0.35, 1, 0.5), toward it).
    pub fn plain_lights() -> Lights {
        Lights {
            ambient: DVec3::splat(0.3),
            sources: vec![LightSource::Directional {
                direction: -DVec3::new(0.35, 1.0, 0.5).normalize(),
                color: DVec3::splat(0.7),
            }],
            shadow: None,
        }
    }

    /// `lights` with their shadow ([`Lights::shadow`], a directional light's) cast by the
    /// meshes: the meshes' shadow map is drawn (again only for another direction), bound to
    /// the scene's own pass, and its projection put in the lights returned. Give those to
    /// [`Self::set_lights`] and to the particles' renderer (`EffectRenderer::set_lights`,
    /// with [`Self::shadow_map`] to `EffectRenderer::set_shadow_map`). Lights without a
    /// shadow come back as they are.
    pub fn cast_shadow(&mut self, lights: &Lights) -> Result<Lights, RuntimeError> {
        let Some(shadow) = &lights.shadow else {
            return Ok(lights.clone());
        };
        let Some(LightSource::Directional { direction, .. }) = lights.sources.get(shadow.source)
        else {
            return Ok(lights.clone());
        };
        if !self.shadow.as_ref().is_some_and(|s| s.is_along(*direction)) {
            let map = SceneShadow::draw(
                &self.gpu,
                (&self.vertices, self.count),
                self.bounds,
                *direction,
            )?;
            self.shadow_binding.map = crate::draw::lights::shadow_map_view(map.texture())?;
            let buffers = (&self.uniforms, &self.lights);
            self.bind_group = scene_group(&self.gpu, &self.layout, buffers, &self.shadow_binding);
            self.shadow = Some(map);
        }
        let map = self.shadow.as_ref().expect("drawn above");
        Ok(Lights {
            shadow: Some(map.shadow(shadow.source)),
            ..lights.clone()
        })
    }

    /// Binds what a particle `renderer` drawn over this scene reads of it: the depth buffer
    /// (soft particles fade against it) and, once the meshes cast a shadow, `lights` (what
    /// [`Self::cast_shadow`] gave) with the shadow map. Call it again after
    /// [`Self::resize`].
    pub fn bind_to(
        &self,
        renderer: &mut crate::EffectRenderer,
        lights: &Lights,
    ) -> Result<(), RuntimeError> {
        renderer.set_scene_depth(self.depth_view());
        if let Some(map) = &self.shadow {
            renderer.set_lights(lights);
            renderer.set_shadow_map(map.texture())?;
        }
        Ok(())
    }

    /// The meshes' shadow map, once [`Self::cast_shadow`] has drawn one.
    pub fn shadow_map(&self) -> Option<&SceneShadow> {
        self.shadow.as_ref()
    }

    /// Lights the meshes with `lights` (world space) from the next pass on: a lit effect's, so
    /// that its particles and what they meet are lit alike.
    pub fn set_lights(&self, lights: &Lights) {
        self.gpu
            .queue
            .write_buffer(&self.lights, 0, &lights.uniform_bytes());
    }

    /// Makes the depth buffer `size` (a window resized); returns whether it changed, and with
    /// it [`Self::depth_view`].
    pub fn resize(&mut self, size: (u32, u32)) -> bool {
        if size == self.size || size.0 == 0 || size.1 == 0 {
            return false;
        }
        (self.depth_texture, self.depth) = depth_buffer(&self.gpu, size);
        self.size = size;
        true
    }

    /// What a particle renderer drawn over this scene must match: `color` with this scene's
    /// depth test.
    pub fn target(color: DrawTarget) -> DrawTarget {
        color.with_depth(DEPTH_FORMAT)
    }

    /// The depth buffer the scene is drawn into (for soft particles:
    /// [`crate::EffectRenderer::set_scene_depth`]).
    pub fn depth_view(&self) -> &wgpu::TextureView {
        &self.depth
    }

    /// The depth buffer's texture (for a `SceneDepth` collider: [`crate::Effect::set_scene_depth`]).
    pub fn depth_texture(&self) -> &wgpu::Texture {
        &self.depth_texture
    }

    /// The depth buffer read back, row by row from the top (waits for the GPU): what a
    /// `SceneDepth` collider's f64 reference collides with.
    pub fn read_depth(&self) -> Result<Vec<f32>, RuntimeError> {
        crate::device::depth_copy::read_depths(&self.gpu, &self.depth_texture)
    }

    /// The depth attachment of a particle pass over the scene: tested, not written, so that
    /// soft particles may read it in the same pass.
    pub fn particle_depth(&self) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth,
            depth_ops: None,
            stencil_ops: None,
        }
    }

    /// Records the scene's pass from `camera`: `color` (cleared or loaded as its operations
    /// say) gets the meshes, and the depth buffer is cleared and written. The camera reaches
    /// the GPU by a queue write, so record one scene pass per submission.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        color: wgpu::RenderPassColorAttachment<'_>,
        camera: &Camera,
    ) {
        let eye = camera.view.inverse().w_axis.truncate();
        let mut uniforms = Vec::with_capacity(UNIFORM_BYTES as usize);
        let view_proj: Mat4 = camera.proj * camera.view;
        for x in view_proj
            .to_cols_array()
            .into_iter()
            .chain(eye.extend(1.0).to_array())
            .chain(SCENE_GREY.into_iter().chain([1.0]))
        {
            uniforms.extend_from_slice(&x.to_le_bytes());
        }
        self.gpu.queue.write_buffer(&self.uniforms, 0, &uniforms);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(color)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth,
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
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..self.count, 0..1);
    }
}

/// The scene pass's bind group: its uniforms, its lights and the shadow map with its
/// samplers.
fn scene_group(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    (uniforms, lights): (&wgpu::Buffer, &wgpu::Buffer),
    shadow: &ShadowBinding,
) -> wgpu::BindGroup {
    let mut entries = vec![
        wgpu::BindGroupEntry {
            binding: 0,
            resource: uniforms.as_entire_binding(),
        },
        wgpu::BindGroupEntry {
            binding: 1,
            resource: lights.as_entire_binding(),
        },
    ];
    // The draw modules' bindings of the map and samplers, in order, are 2, 3 and 4 here.
    for (binding, (_, resource)) in (2..).zip(shadow.entries()) {
        entries.push(wgpu::BindGroupEntry { binding, resource });
    }
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout,
        entries: &entries,
    })
}
