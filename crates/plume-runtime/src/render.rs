//! Headless rendering of particles as camera-facing soft round sprites into an RGBA image.
//! Colour and size come from the effect's `render:` section over each particle's life fraction;
//! with `sort: true` sprites are drawn back to front as seen from the camera.

use glam::{DVec3, Mat4, Vec3};
use plume_compiler::ir::{CameraIr, RenderIr};
use plume_compiler::reference::ParticleRecord;
use plume_compiler::schema::Blend;

use crate::error::RuntimeError;
use crate::gpu::Gpu;

/// One sprite: centre (m), diameter (m), colour (RGBA in [0, 1]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sprite {
    /// Centre in world space.
    pub center: [f32; 3],
    /// Diameter in metres.
    pub size: f32,
    /// Colour and opacity.
    pub color: [f32; 4],
}

/// Builds sprites from particle records: colour and size at each particle's life fraction
/// (age / lifetime; 0 for particles that never die); back to front from `camera` when `sort`.
/// Non-finite particles are skipped.
pub fn sprites(
    records: &[ParticleRecord],
    render: &RenderIr,
    camera: &CameraIr,
    sort: bool,
) -> Vec<Sprite> {
    let mut keyed: Vec<(f64, Sprite)> = records
        .iter()
        .filter(|r| r.position.is_finite())
        .map(|r| {
            let t = match r.lifetime {
                Some(l) if l > 0.0 => (r.age / l).clamp(0.0, 1.0),
                _ => 0.0,
            };
            let c = render.color_at(t);
            let p = r.position;
            let depth = (p - camera.eye).dot((camera.target - camera.eye).normalize_or_zero());
            (
                depth,
                Sprite {
                    center: [p.x as f32, p.y as f32, p.z as f32],
                    size: render.size_at(t) as f32,
                    color: [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32],
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

/// View and projection matrices of the camera for an image of `aspect` = width / height.
pub fn camera_matrices(camera: &CameraIr, aspect: f32) -> (Mat4, Mat4) {
    let eye = camera.eye.as_vec3();
    let target = camera.target.as_vec3();
    let forward = (target - eye).normalize_or_zero();
    // Y is up unless the camera looks straight along it.
    let up = if forward.cross(Vec3::Y).length_squared() < 1e-6 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let view = Mat4::look_at_rh(eye, target, up);
    let proj = Mat4::perspective_rh(camera.fov_y.to_radians() as f32, aspect, 0.05, 10_000.0);
    (view, proj)
}

/// Where a world point lands in an image of `width` x `height` (pixels, origin top left), or None
/// when it is behind the camera.
pub fn project(camera: &CameraIr, width: u32, height: u32, p: DVec3) -> Option<(f32, f32)> {
    let (view, proj) = camera_matrices(camera, width as f32 / height as f32);
    let clip = proj * view * p.as_vec3().extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.truncate() / clip.w;
    Some((
        (ndc.x * 0.5 + 0.5) * width as f32,
        (0.5 - ndc.y * 0.5) * height as f32,
    ))
}

/// A render target and the sprite pipeline for one image size and blend mode.
pub struct Renderer<'g> {
    gpu: &'g Gpu,
    width: u32,
    height: u32,
    target: wgpu::Texture,
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    background: DVec3,
}

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl<'g> Renderer<'g> {
    /// A renderer of `width` x `height` images with the given blending and background.
    pub fn new(
        gpu: &'g Gpu,
        width: u32,
        height: u32,
        blend: Blend,
        background: DVec3,
    ) -> Result<Self, RuntimeError> {
        let max = gpu.limits.max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RuntimeError::Output(format!(
                "image size {width}x{height} must be between 1x1 and {max}x{max} on this adapter"
            )));
        }
        let device = &gpu.device;
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("frame"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sprites"),
            source: wgpu::ShaderSource::Wgsl(include_str!("sprite.wgsl").into()),
        });
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: 128,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(128),
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sprites"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let blend_state = match blend {
            Blend::Alpha => wgpu::BlendState::ALPHA_BLENDING,
            Blend::Additive => wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::SrcAlpha,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent::OVER,
            },
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sprites"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 32,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x4],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: FORMAT,
                    blend: Some(blend_state),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        gpu.take_error()?;
        Ok(Self {
            gpu,
            width,
            height,
            target,
            pipeline,
            camera,
            bind_group,
            background,
        })
    }

    /// Draws `sprites` in order over the background as seen from `camera`; returns RGBA8 rows.
    pub fn draw(&self, sprites: &[Sprite], camera: &CameraIr) -> Result<Vec<u8>, RuntimeError> {
        let device = &self.gpu.device;
        let (view, proj) = camera_matrices(camera, self.width as f32 / self.height as f32);
        let mut cam = Vec::with_capacity(128);
        for m in [view, proj] {
            for x in m.to_cols_array() {
                cam.extend_from_slice(&x.to_le_bytes());
            }
        }
        self.gpu.queue.write_buffer(&self.camera, 0, &cam);
        let mut instances = Vec::with_capacity(sprites.len() * 32);
        for s in sprites {
            for x in s.center.iter().chain([s.size].iter()).chain(s.color.iter()) {
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
        let view_tex = self.target.create_view(&Default::default());
        let row = (self.width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame readback"),
            size: u64::from(row) * u64::from(self.height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let bg = self.background;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sprites"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view_tex,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: bg.x,
                            g: bg.y,
                            b: bg.z,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let Some(b) = &instance_buffer {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_vertex_buffer(0, b.slice(..));
                pass.draw(0..6, 0..sprites.len() as u32);
            }
        }
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.target,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.gpu.wait()?;
        rx.recv()
            .map_err(|e| RuntimeError::Readback(e.to_string()))?
            .map_err(|e| RuntimeError::Readback(e.to_string()))?;
        let data = readback
            .get_mapped_range(..)
            .map_err(|e| RuntimeError::Readback(e.to_string()))?;
        let mut pixels = Vec::with_capacity((self.width * self.height * 4) as usize);
        for y in 0..self.height as usize {
            let start = y * row as usize;
            pixels.extend_from_slice(&data[start..start + self.width as usize * 4]);
        }
        drop(data);
        readback.unmap();
        Ok(pixels)
    }
}
