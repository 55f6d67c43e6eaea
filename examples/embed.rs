//! Embedding Plume in a host wgpu application.
//!
//! The host owns the device, the queue, the window, the depth buffer and a scene of its own (a
//! checkered ground and a cube). Plume gets the host's device and queue, records its steps into
//! the host's command encoder, and draws in the host's render pass after the host's geometry,
//! testing against the host's depth buffer without writing it: the cube hides the particles
//! behind it. The particles never leave the GPU.
//!
//! ```sh
//! cargo run --release --example embed -- effects/fountain.ron             # a window
//! cargo run --release --example embed -- effects/fountain.ron --headless out.png [--size 640x360] [--frames 120] [--steps-per-frame 1]
//! cargo run --release --example embed -- effects/fountain.ron --draw compute  # the compute renderer
//! ```
//!
//! Either renderer draws the same way for the host: Plume's preparation goes into the host's
//! encoder after the pass that draws the host's depth (the compute renderer reads that depth
//! in a compute pass), then the particles go into a second pass over the host's colour.
//!
//! `--headless` renders offscreen through the same code and writes the last frame as a PNG
//! (tests/embed.rs runs it). In the window the effect steps in real time (the effect's dt,
//! driven by the wall clock); Esc or closing the window quits.

#![allow(dead_code)] // tests/embed.rs includes this file as a module and uses part of it.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::{Mat4, Vec3};
use plume::runtime::wgpu;
use plume::runtime::{Camera, DrawTarget, Effect, EffectRenderer, Gpu};

/// The host's depth buffer format.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The host's own geometry: flat-coloured triangles (the ground's tiles and a cube) with their
/// own pipeline, which writes depth.
struct HostScene {
    pipeline: wgpu::RenderPipeline,
    vertices: wgpu::Buffer,
    count: u32,
    uniform: wgpu::Buffer,
    group: wgpu::BindGroup,
}

const HOST_WGSL: &str = r#"
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec3<f32>,
}

@vertex
fn vs(@location(0) position: vec3<f32>, @location(1) color: vec3<f32>) -> Out {
    var out: Out;
    out.clip = view_proj * vec4<f32>(position, 1.0);
    out.color = color;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color, 1.0);
}
"#;

/// The cube's colour: a red no particle in the examples has, so tests can find it.
pub const CUBE_COLOR: [f32; 3] = [0.55, 0.12, 0.1];

/// Where the host puts its cube for the effect's camera: between the eye and the target, a
/// little to the right and below the line of sight, big enough to hide part of the effect.
/// Returns (centre, half size).
pub fn cube_for(eye: Vec3, target: Vec3) -> (Vec3, f32) {
    let dist = (target - eye).length().max(1e-3);
    let forward = (target - eye) / dist;
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = right.cross(forward);
    (
        eye + forward * (0.55 * dist) + right * (0.06 * dist) - up * (0.05 * dist),
        0.055 * dist,
    )
}

/// The cube's turn about the vertical (radians), so that two sides and the top show.
const CUBE_YAW: f32 = 0.6;

/// Six faces of a cube (turned by [`CUBE_YAW`]) and a checkered ground around
/// `ground_center` at y = 0, as (position, colour) triangles.
fn host_triangles(cube: (Vec3, f32), ground_center: Vec3) -> Vec<[f32; 6]> {
    let mut out = Vec::new();
    let mut quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, color: [f32; 3]| {
        for p in [a, b, c, a, c, d] {
            out.push([p.x, p.y, p.z, color[0], color[1], color[2]]);
        }
    };
    let (c, s) = cube;
    // Faces shaded by direction, so the cube reads as a solid.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z, 0.8),
        (-Vec3::X, Vec3::Z, Vec3::Y, 0.6),
        (Vec3::Y, Vec3::Z, Vec3::X, 1.0),
        (-Vec3::Y, Vec3::X, Vec3::Z, 0.4),
        (Vec3::Z, Vec3::X, Vec3::Y, 0.9),
        (-Vec3::Z, Vec3::Y, Vec3::X, 0.7),
    ];
    let turn = glam::Quat::from_rotation_y(CUBE_YAW);
    for (n, u, v, shade) in faces {
        let o = c + turn * (n * s);
        let (u, v) = (turn * (u * s), turn * (v * s));
        let col = CUBE_COLOR.map(|x| x * shade);
        quad(o - u - v, o + u - v, o + u + v, o - u + v, col);
    }
    // A 16 m x 16 m ground of 1 m tiles in two greys.
    let (gx, gz) = (ground_center.x.round(), ground_center.z.round());
    for i in -8..8 {
        for j in -8..8 {
            let (x, z) = (gx + i as f32, gz + j as f32);
            let grey = if (i + j) % 2 == 0 { 0.16 } else { 0.11 };
            quad(
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 0.0, z + 1.0),
                Vec3::new(x + 1.0, 0.0, z + 1.0),
                Vec3::new(x + 1.0, 0.0, z),
                [grey, grey, grey * 1.1],
            );
        }
    }
    out
}

impl HostScene {
    fn new(
        device: &wgpu::Device,
        color_format: wgpu::TextureFormat,
        cube: (Vec3, f32),
        ground_center: Vec3,
    ) -> Self {
        use wgpu::util::DeviceExt;
        let triangles = host_triangles(cube, ground_center);
        let bytes: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("host geometry"),
            contents: &bytes,
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("host camera"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("host"),
            source: wgpu::ShaderSource::Wgsl(HOST_WGSL.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("host"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
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
                targets: &[Some(color_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("host"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        Self {
            pipeline,
            vertices,
            count: triangles.len() as u32,
            uniform,
            group,
        }
    }
}

/// What the host draws each frame: its scene and, optionally, the effect.
#[derive(Clone, Copy, Debug)]
pub struct Layers {
    /// Draw the host's ground and cube.
    pub host: bool,
    /// Draw the effect.
    pub particles: bool,
    /// Test the effect against the host's depth buffer (as a real host does).
    pub depth_test: bool,
    /// Draw the effect with the compute renderer (`Effect::compute_renderer`) instead of the
    /// raster one.
    pub compute: bool,
}

impl Default for Layers {
    fn default() -> Self {
        Self {
            host: true,
            particles: true,
            depth_test: true,
            compute: false,
        }
    }
}

/// The host application's state: its device and scene, and one embedded effect.
pub struct Host {
    device: wgpu::Device,
    queue: wgpu::Queue,
    scene: HostScene,
    effect: Effect,
    /// What the particles are drawn into, and how (raster or compute).
    draw_target: DrawTarget,
    compute: bool,
    /// Made on the first frame, and again when a compute renderer's target changes size.
    particles: Option<EffectRenderer>,
    background: wgpu::Color,
}

impl Host {
    /// Loads `path` (any effect file, with or without groups) and embeds it on the host's
    /// `device` and `queue`, drawing into `color_format` targets.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        path: &Path,
        color_format: wgpu::TextureFormat,
        layers: Layers,
    ) -> Result<Self, Box<dyn Error>> {
        // Plume on the host's device: the host keeps its own error handling. Errors in the
        // file come back located in it.
        let effect =
            Effect::from_file(&Gpu::from_device(device, queue), path, &Default::default())?;
        let ir = &effect.compiled().ir;
        let (eye, target) = (ir.camera.eye.as_vec3(), ir.camera.target.as_vec3());
        let bg = ir.render.background;
        let scene = HostScene::new(device, color_format, cube_for(eye, target), target);
        // The pass has the host's depth attachment, so the particles' pipeline names its
        // format; `Always` (for the test's comparison) draws over everything.
        let draw_target = match layers.depth_test {
            true => DrawTarget::new(color_format).with_depth(DEPTH),
            false => DrawTarget::new(color_format)
                .with_depth_compare(DEPTH, wgpu::CompareFunction::Always),
        };
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            scene,
            effect,
            draw_target,
            compute: layers.compute,
            particles: None,
            background: wgpu::Color {
                r: bg.x,
                g: bg.y,
                b: bg.z,
                a: 1.0,
            },
        })
    }

    /// The effect's camera at `aspect`: the host could use any view and projection.
    pub fn camera(&self, aspect: f32) -> Camera {
        self.effect.camera(aspect)
    }

    /// One frame: `steps` simulation steps, the host's geometry (writing depth), then the
    /// particles (testing it) in a second pass, all in one submission.
    pub fn frame(
        &mut self,
        color: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        camera: &Camera,
        steps: u64,
        layers: Layers,
    ) -> Result<(), Box<dyn Error>> {
        let view_proj = camera.proj * camera.view;
        self.queue
            .write_buffer(&self.scene.uniform, 0, bytemuck_mat(&view_proj).as_slice());
        let size = (color.texture().width(), color.texture().height());
        // A compute renderer draws one size: a resized window needs a new one.
        let stale = match &self.particles {
            None => true,
            Some(p) => p.size().is_some_and(|s| s != size),
        };
        if stale {
            let particles = match self.compute {
                true => self
                    .effect
                    .compute_renderer(&self.draw_target, size.0, size.1)?,
                false => self.effect.renderer(&self.draw_target)?,
            };
            self.particles = Some(particles);
        }
        let particles = self.particles.as_mut().expect("made above");
        // The compute renderer reads the host's depth itself (this frame's texture: a resized
        // window has a new one).
        if particles.is_compute() {
            particles.set_scene_depth(depth);
        }
        let particles = &*particles;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        // Plume records its steps into the host's encoder ...
        self.effect.advance(&mut encoder, steps)?;
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host geometry"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(self.background),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
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
            // ... the host draws its opaque geometry first ...
            if layers.host {
                pass.set_pipeline(&self.scene.pipeline);
                pass.set_bind_group(0, &self.scene.group, &[]);
                pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
                pass.draw(0..self.scene.count, 0..1);
            }
        }
        if layers.particles {
            // ... Plume prepares its draw once the host's depth is drawn (the compute
            // renderer composites its particles here, tested against that depth) ...
            self.effect.prepare_draw(&mut encoder, particles, camera)?;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("particles"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                // Tested, not written.
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            // ... and draws its particles over the host's image.
            particles.draw(&mut pass);
        }
        self.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Shows a finished surface frame.
    pub fn present(&self, frame: wgpu::SurfaceTexture) {
        self.queue.present(frame);
    }

    /// The embedded effect's dt (s).
    pub fn dt(&self) -> f64 {
        self.effect.compiled().ir.dt
    }
}

fn bytemuck_mat(m: &Mat4) -> Vec<u8> {
    m.to_cols_array()
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// A host's own adapter and device (Plume is handed these; it opens nothing itself).
fn host_device(
    instance: &wgpu::Instance,
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<(wgpu::Adapter, wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        compatible_surface: surface,
        ..Default::default()
    }))
    .map_err(|_| {
        "no GPU adapter found. Without a GPU, install a software driver: Debian/Ubuntu \
         `apt-get install mesa-vulkan-drivers` (lavapipe) or `libegl1 libgl1-mesa-dri` (llvmpipe)"
    })?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;
    Ok((adapter, device, queue))
}

/// Options of the headless mode.
#[derive(Clone, Copy, Debug)]
pub struct Headless {
    /// Image width and height.
    pub size: (u32, u32),
    /// Frames rendered; the last is returned.
    pub frames: u32,
    /// Simulation steps per frame.
    pub steps_per_frame: u64,
    /// What is drawn.
    pub layers: Layers,
}

/// Renders `path` embedded in the host scene offscreen, through the same [`Host`] the window
/// uses; returns the last frame as RGBA8 rows.
pub fn render_headless(path: &Path, options: &Headless) -> Result<Vec<u8>, Box<dyn Error>> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let (_, device, queue) = host_device(&instance, None)?;
    let (w, h) = options.size;
    let format = wgpu::TextureFormat::Rgba8Unorm;
    // Plume's handle on the host's device also makes plain 2D textures.
    let gpu = Gpu::from_device(&device, &queue);
    let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let color = gpu.texture_2d(
        "color",
        (w, h),
        format,
        attachment | wgpu::TextureUsages::COPY_SRC,
    );
    // Bindable: the compute renderer copies it.
    let depth = gpu.texture_2d(
        "depth",
        (w, h),
        DEPTH,
        attachment | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let (color_view, depth_view) = (
        color.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    let mut host = Host::new(&device, &queue, path, format, options.layers)?;
    let camera = host.camera(w as f32 / h as f32);
    for _ in 0..options.frames.max(1) {
        host.frame(
            &color_view,
            &depth_view,
            &camera,
            options.steps_per_frame,
            options.layers,
        )?;
    }
    Ok(plume::runtime::outputs::read_texture(&gpu, &color, w, h)?)
}

/// The window: the host's surface, depth buffer and real-time loop.
#[path = "embed/window.rs"]
mod window;

/// The effect, the headless output (None: a window), and the options (`--draw` for both).
fn parse_args() -> Result<(PathBuf, Option<PathBuf>, Headless), String> {
    let usage =
        "usage: embed EFFECT.ron [--draw raster|compute] [--headless OUT.png [--size WxH] [--frames N] [--steps-per-frame K]]";
    let mut args = std::env::args().skip(1);
    let mut effect = None;
    let mut out = None;
    let mut headless = Headless {
        size: (640, 360),
        frames: 120,
        steps_per_frame: 1,
        layers: Layers::default(),
    };
    while let Some(a) = args.next() {
        match a.as_str() {
            "--headless" => out = Some(PathBuf::from(args.next().ok_or(usage)?)),
            "--size" => {
                let s = args.next().ok_or(usage)?;
                let (w, h) = s.split_once('x').ok_or(usage)?;
                headless.size = (w.parse().map_err(|_| usage)?, h.parse().map_err(|_| usage)?);
            }
            "--frames" => {
                headless.frames = args.next().ok_or(usage)?.parse().map_err(|_| usage)?;
            }
            "--draw" => match args.next().as_deref() {
                Some("raster") => headless.layers.compute = false,
                Some("compute") => headless.layers.compute = true,
                _ => return Err(usage.into()),
            },
            "--steps-per-frame" => {
                headless.steps_per_frame = args.next().ok_or(usage)?.parse().map_err(|_| usage)?;
            }
            _ if effect.is_none() && !a.starts_with("--") => effect = Some(PathBuf::from(a)),
            _ => return Err(usage.into()),
        }
    }
    Ok((effect.ok_or(usage)?, out, headless))
}

/// `--headless`: renders and writes the last frame to `out` as a PNG.
pub fn write_headless(effect: &Path, out: &Path, options: &Headless) -> Result<(), Box<dyn Error>> {
    let pixels = render_headless(effect, options)?;
    let (w, h) = options.size;
    image::save_buffer(out, &pixels, w, h, image::ExtendedColorType::Rgba8)
        .map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    Ok(())
}

fn main() -> std::process::ExitCode {
    let result = parse_args()
        .map_err(Box::<dyn Error>::from)
        .and_then(|(effect, out, options)| match out {
            None => window::run(effect, options.layers),
            Some(out) => {
                write_headless(&effect, &out, &options)?;
                eprintln!("wrote {}", out.display());
                Ok(())
            }
        });
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
