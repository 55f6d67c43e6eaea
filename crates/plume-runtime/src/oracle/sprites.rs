//! The reference drawing, the oracle the GPU draw ([`crate::draw::raster`]) is tested against: particles
//! read back to the CPU, coloured and sized there in f64 from the effect's `render:` section at
//! each particle's life fraction ([`sprites`]), uploaded as one instance per sprite and drawn by
//! a fixed sprite shader. This was Plume's only drawing path before the GPU draw; it now serves
//! the tests (as the f64 reference serves the simulation), never `plume render`.

use glam::DVec3;
use plume_compiler::by_expression::Seen;
use plume_compiler::ir::{EffectIr, RenderIr};
use plume_compiler::reference::ParticleRecord;
use plume_compiler::rotation::RotationIr;

use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::pipeline::blend_state;
use crate::draw::pipeline::vertex_pipeline;
use crate::draw::texture::SpriteTexture;
use crate::error::RuntimeError;
use crate::oracle::strips::{StripPipeline, StripVertex};
use crate::outputs::offscreen::{Offscreen, FORMAT};

/// One sprite: centre (m), the quad's half axes (m), colour (RGBA in [0, 1]). Corner
/// (cx, cy) in [-1, 1]² lies at centre + cx · half_x + cy · half_y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sprite {
    /// Centre in world space.
    pub center: [f32; 3],
    /// Half of the quad's first side, in world space.
    pub half_x: [f32; 3],
    /// Half of the quad's second side, in world space.
    pub half_y: [f32; 3],
    /// Colour and opacity.
    pub color: [f32; 4],
    /// The texel rectangle `(x0, y0, width, height)` of the texture frame it shows; all zero
    /// for the soft round dot of an effect without a texture.
    pub texels: [f32; 4],
}

/// Builds sprites from particle records: colour and size at each particle's life fraction
/// (age / lifetime; 0 for particles that never die), the quad oriented as `render.orient` says
/// for `camera` (its view, and for sizes in the image, its projection) and turned as
/// `render.rotation` says, the flipbook frame for its age; back to front from the
/// effect's camera when `sort`. Non-finite particles are skipped. For a look whose
/// expressions read the time `t`, use [`sprites_at`].
pub fn sprites(
    records: &[ParticleRecord],
    ir: &EffectIr,
    camera_used: &crate::Camera,
    sort: bool,
) -> Vec<Sprite> {
    assert!(
        !ir.render.by.reads_time(),
        "{}: its look reads the time: draw it with sprites_at and the frame's time",
        ir.name
    );
    sprites_at(records, ir, camera_used, sort, 0.0)
}

/// [`sprites`] of a frame at simulation time `time` (s: steps done × dt), which the look's
/// expressions read as `t`.
pub fn sprites_at(
    records: &[ParticleRecord],
    ir: &EffectIr,
    camera_used: &crate::Camera,
    sort: bool,
    time: f64,
) -> Vec<Sprite> {
    let (render, camera) = (&ir.render, &ir.camera);
    let proj = camera_used.proj.as_dmat4();
    // The camera's right and up in world space: rows 0 and 1 of the view rotation.
    let view = camera_used.view.as_dmat4();
    let camera_right = DVec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
    let camera_up = DVec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
    // The eye: the view's inverse applied to the origin.
    let camera_eye = view.inverse().transform_point3(DVec3::ZERO);
    let f32s = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
    let mut keyed: Vec<(f64, Sprite)> = records
        .iter()
        .filter(|r| r.position.is_finite())
        .map(|r| {
            let t = match r.lifetime {
                Some(l) if l > 0.0 => (r.age / l).clamp(0.0, 1.0),
                _ => 0.0,
            };
            let seen = Seen {
                x: r.position,
                v: r.velocity,
                age: r.age,
                life: r.lifetime.unwrap_or(0.0),
                id: r.id,
                attrs: ir
                    .attributes
                    .from_words(ir.kept_attributes(), &r.attributes),
                // The GPU's f32(steps) * dt: steps are whole, so their f32 is exact.
                t: time,
            };
            let by = render.by.color_factor(&seen, ir.seed_mix) * r.tint;
            let c = render.color_at(render.by.color_t_at(&seen, ir.seed_mix).unwrap_or(t));
            let alpha = render.by.alpha_factor(&seen, ir.seed_mix);
            let c = [c[0] * by.x, c[1] * by.y, c[2] * by.z, c[3] * alpha];
            let p = r.position;
            let scale = render.by.size_factor(&seen, ir.seed_mix)
                * match render.size_in {
                    plume_compiler::screen_size::SizeIn::World => 1.0,
                    plume_compiler::screen_size::SizeIn::Screen => {
                        plume_compiler::screen_size::metres_per_height(view, proj, r.position)
                    }
                };
            let (half_x, half_y) = render.orient.half_axes(
                (render.size_at(t) * scale, render.height_at(t) * scale),
                (r.velocity, camera_eye - p),
                camera_right,
                camera_up,
            );
            // Whole steps, as the records' ages and lifetimes are.
            let steps = |seconds: f64| (seconds / ir.dt).round() as u64;
            let (half_x, half_y) = match &render.rotation {
                Some(rotation) => {
                    let angle = rotation.angle(r.id, ir.seed_mix, steps(r.age), ir.dt);
                    RotationIr::turn(half_x, half_y, angle)
                }
                None => (half_x, half_y),
            };
            let texels = render.texture.as_ref().map_or([0.0; 4], |texture| {
                let life = r.lifetime.map_or(0, steps);
                let frame = render
                    .by
                    .frame_at(&seen, ir.seed_mix, texture.frames())
                    .unwrap_or_else(|| texture.frame(r.id, ir.seed_mix, steps(r.age), life, ir.dt));
                texture.frame_texels(frame).map(|x| x as f32)
            });
            let depth = (p - camera.eye).dot((camera.target - camera.eye).normalize_or_zero());
            (
                depth,
                Sprite {
                    center: f32s(p),
                    half_x: f32s(half_x),
                    half_y: f32s(half_y),
                    color: [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32],
                    texels,
                },
            )
        })
        .collect();
    if sort {
        // Farthest first; equal depths keep id order (a stable sort).
        keyed.sort_by(|a, b| b.0.total_cmp(&a.0));
    }
    keyed.into_iter().map(|(_, s)| s).collect()
}

/// Bytes of one sprite instance: three vec3 and two vec4 of f32.
const SPRITE_BYTES: u64 = 68;

/// A filterable 2D texture the fragment shader reads, at `binding`.
fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Bytes of the reference camera uniform: view and projection (128), the eye, the lit
/// look's terms and the blend's (`reference_sprite.wgsl`'s `Camera`).
const CAMERA_BYTES: u64 = 176;

/// A render target and the reference sprite pipeline for one image size and blend mode.
pub struct ReferenceRenderer {
    gpu: Gpu,
    target: Offscreen,
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    lights: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    strips: StripPipeline,
    background: DVec3,
    /// (1 when lit; normals 0 flat, 1 sphere, 2 a normal map, 3 six-way lightmaps; wrap;
    /// emissive).
    lit: [f32; 4],
    /// The blend's fragment output (0 as written, 1 Multiply, 2 Mask, 3 Premultiplied, 4
    /// Opaque; the
    /// Mask's cutoff; the texture's sample mapping: 0 Modulate, 1 ModulateRgb, 2
    /// OpacityFromRed).
    blend: [f32; 4],
}

impl ReferenceRenderer {
    /// A renderer of `width` x `height` images with the blending, background, texture and
    /// lighting (`render.lit`, by the effect's lights) of `ir`.
    pub fn new(gpu: &Gpu, width: u32, height: u32, ir: &EffectIr) -> Result<Self, RuntimeError> {
        let render: &RenderIr = &ir.render;
        let (blend, background) = (render.blend, render.background);
        let target = Offscreen::new(gpu, width, height)?;
        let device = &gpu.device;
        let source = [
            include_str!("../outputs/world_lights.wgsl"),
            include_str!("reference_camera.wgsl"),
            include_str!("reference_sprite.wgsl"),
        ]
        .concat();
        let module = gpu.shader_module("sprites", &source);
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: CAMERA_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights"),
            size: plume_compiler::lights::LIGHTS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&lights, 0, &ir.lights.uniform_bytes());
        let texture = match &render.texture {
            Some(t) => SpriteTexture::new(gpu, t)?,
            // Bound but never sampled: the sprites' texel rectangles are empty.
            None => SpriteTexture::from_rgba(gpu, 1, 1, &[255; 4], 1)?,
        };
        // Where the texture has no second image: a white one, which multiplies by 1.
        let white = SpriteTexture::from_rgba(gpu, 1, 1, &[255; 4], 1)?;
        // A lit look's maps, laid out as the texture; 1x1 stand-ins where it has fewer.
        let mut lit_maps = Vec::new();
        for k in 0..2 {
            lit_maps.push(match render.lit_maps.get(k) {
                Some(map) => SpriteTexture::new(gpu, map)?,
                None => SpriteTexture::from_rgba(gpu, 1, 1, &[128, 128, 255, 255], 1)?,
            });
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(CAMERA_BYTES),
                    },
                    count: None,
                },
                texture_entry(4),
                texture_entry(5),
                texture_entry(6),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(
                            plume_compiler::lights::LIGHTS_BYTES,
                        ),
                    },
                    count: None,
                },
                texture_entry(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: camera.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&texture.view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&texture.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: lights.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&lit_maps[0].view),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::TextureView(&lit_maps[1].view),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::TextureView(
                        texture.second.as_ref().unwrap_or(&white.view),
                    ),
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sprites"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = vertex_pipeline(
            gpu,
            &module,
            ("vs", "fs"),
            crate::draw::pipeline::plain(wgpu::PrimitiveTopology::TriangleList),
            &crate::draw::target::DrawTarget::new(FORMAT),
            blend_state(blend),
            Some(&pipeline_layout),
            &[Some(wgpu::VertexBufferLayout {
                array_stride: SPRITE_BYTES,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x4, 4 => Float32x4],
            })],
        );
        let strips = StripPipeline::new(gpu, blend, &camera);
        gpu.take_error()?;
        let lit = render.lit.as_ref().map_or([0.0; 4], |lit| {
            let normals = match lit.normals {
                plume_compiler::lit::Normals::Flat => 0.0,
                plume_compiler::lit::Normals::Sphere => 1.0,
                plume_compiler::lit::Normals::Map { .. } => 2.0,
                plume_compiler::lit::Normals::SixWay { .. } => 3.0,
            };
            [1.0, normals, lit.wrap as f32, lit.emissive as f32]
        });
        Ok(Self {
            gpu: gpu.clone(),
            target,
            pipeline,
            camera,
            lights,
            bind_group,
            strips,
            background,
            lit,
            blend: {
                use plume_compiler::schema::Blend;
                use plume_compiler::texture::Sample;
                let (mode, cutoff) = match blend {
                    Blend::Multiply => (1.0, 0.0),
                    Blend::Mask(cutoff) => (2.0, cutoff as f32),
                    Blend::Premultiplied => (3.0, 0.0),
                    Blend::Opaque => (4.0, 0.0),
                    Blend::Alpha | Blend::Additive => (0.0, 0.0),
                };
                let code = |sample: Option<Sample>| match sample {
                    Some(Sample::ModulateRgb) => 1.0,
                    Some(Sample::OpacityFromRed) => 2.0,
                    _ => 0.0,
                };
                let texture = render.texture.as_ref();
                [
                    mode,
                    cutoff,
                    code(texture.map(|t| t.sample)),
                    code(texture.and_then(|t| t.second.as_ref()).map(|s| s.sample)),
                ]
            },
        })
    }

    /// Draws a lit look with `lights` instead of the effect's own (as a host's
    /// `EffectRenderer::set_lights` does).
    pub fn set_lights(&self, lights: &plume_compiler::lights::Lights) {
        self.gpu
            .queue
            .write_buffer(&self.lights, 0, &lights.uniform_bytes());
    }

    /// Draws `sprites` in order over the background as seen from `camera`; returns RGBA8 rows.
    pub fn draw(&self, sprites: &[Sprite], camera: &Camera) -> Result<Vec<u8>, RuntimeError> {
        self.draw_with_strips(&[], sprites, camera)
    }

    /// Draws the `strips` (triangles: [`crate::oracle::trail_strips`] or
    /// [`crate::oracle::ribbon_strips`]), then `sprites` in order, as the GPU draw records an
    /// effect with trails; returns RGBA8 rows.
    pub fn draw_with_strips(
        &self,
        strips: &[StripVertex],
        sprites: &[Sprite],
        camera: &Camera,
    ) -> Result<Vec<u8>, RuntimeError> {
        let device = &self.gpu.device;
        let mut cam = Vec::with_capacity(CAMERA_BYTES as usize);
        for m in [camera.view, camera.proj] {
            for x in m.to_cols_array() {
                cam.extend_from_slice(&x.to_le_bytes());
            }
        }
        // The eye (perspective), or the world direction toward the viewer (orthographic).
        let view = camera.view.as_dmat4();
        let eye = match camera.proj.w_axis.w == 1.0 {
            true => DVec3::new(view.x_axis.z, view.y_axis.z, view.z_axis.z).extend(0.0),
            false => view.inverse().transform_point3(DVec3::ZERO).extend(1.0),
        };
        let terms = self.lit.into_iter().chain(self.blend);
        for x in eye.to_array().map(|x| x as f32).into_iter().chain(terms) {
            cam.extend_from_slice(&x.to_le_bytes());
        }
        self.gpu.queue.write_buffer(&self.camera, 0, &cam);
        let mut instances = Vec::with_capacity(sprites.len() * SPRITE_BYTES as usize);
        for s in sprites {
            let fields = [
                &s.center[..],
                &s.half_x[..],
                &s.half_y[..],
                &s.color[..],
                &s.texels[..],
            ];
            for x in fields.into_iter().flatten() {
                instances.extend_from_slice(&x.to_le_bytes());
            }
        }
        let instance_buffer = (!sprites.is_empty()).then(|| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("sprites"),
                size: instances.len() as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.gpu.queue.write_buffer(&b, 0, &instances);
            b
        });
        let strip_buffer = StripPipeline::upload(&self.gpu, strips);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sprites"),
                color_attachments: &[Some(self.target.attachment(self.background))],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let Some(b) = &strip_buffer {
                self.strips.record(&mut pass, b, strips.len() as u32);
            }
            if let Some(b) = &instance_buffer {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_vertex_buffer(0, b.slice(..));
                pass.draw(0..6, 0..sprites.len() as u32);
            }
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        self.target.read()
    }
}
