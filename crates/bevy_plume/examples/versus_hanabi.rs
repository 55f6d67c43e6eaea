//! The same fountain in bevy_plume and in bevy_hanabi 0.20, one plugin per run, in a headless
//! 1280x720 Bevy app; prints one JSON line of frame, CPU and GPU times.
//!
//! ```sh
//! cargo +nightly run --release --ignore-rust-version --features hanabi --example versus_hanabi -- \
//!     --plugin plume --live 1000000 [--effects 1] [--frames 120] [--out frame.png] \
//!     [--draw auto|raster|compute] [--msaa 1|4] [--view 3d|2d] [--mesh 1]
//! ```
//!
//! The fountain: particles spawned at a constant rate for `live` of them alive at once over a
//! 2 s lifetime, launched up at about 8 m/s (Plume: a 12° cone at 7.5 to 8.5 m/s; hanabi:
//! 8 m/s up plus a uniform ±1.5 m/s per axis: the two have no common velocity form), gravity,
//! linear drag 0.5, size 0.05 m to 0.01 m and a blue that fades out over life, alpha blended,
//! unsorted, each sprite parallel to the camera's image plane (Plume's `orient: Camera`,
//! hanabi's `ParallelCameraDepthPlane`, its cheaper orientation). With `--effects K`, K such
//! fountains of `live` particles each on a grid. `--view 2d` draws them through a `Camera2d`
//! (orthographic, 100 pixels a metre) instead of a `Camera3d`; `--msaa` sets the camera's
//! `Msaa` (default 1: off). `--mesh 1` draws every particle as a mesh instead of a sprite: the
//! same Bevy `Mesh` in both plugins, a UV sphere of 200 triangles (Bevy's `uv(10, 11)`), 1 m
//! across at size 1 (Plume: `PlumeEffect::with_mesh`, unlit as the fountain's look; hanabi:
//! `EffectMesh`, its mesh particles unlit).
//!
//! Timing, per frame once the fountains are full, medians and 90th percentiles over `--frames`
//! frames: `cpu_ms` is `App::update` (main and render worlds: pipelined rendering is off, so the
//! render world runs inside it); `frame_ms` adds the wait until the GPU has finished the frame;
//! `gpu_ms` is the GPU's time from the first to the last of the frame's command buffers
//! (Plume's `GpuTimer`, its stamps placed before every other command buffer of the frame and
//! after them; every other frame is timed; null where the adapter has no timestamp queries).
//! `lit_pixels` counts the last frame's pixels that differ from its background (its most common
//! colour) by more than 2 of 255 in a channel, so that a run that draws nothing shows it.
//! `--draw` picks Plume's renderer (`PlumeDraw`; default auto).

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::renderer::{
    PendingCommandBuffers, RenderDevice, RenderGraph, RenderGraphSystems, RenderQueue,
};
use bevy::render::view::screenshot::{save_to_disk, Screenshot, ScreenshotCaptured};
use bevy::render::RenderApp;
use bevy::time::TimeUpdateStrategy;
use bevy_plume::headless::{default_plugins, Headless};
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeEffectAsset, PlumePlugin};
use plume_runtime::{Gpu, GpuTimer};

/// Seconds each particle lives.
const LIFETIME: f64 = 2.0;

#[derive(Clone, Copy, PartialEq)]
enum Plugin {
    Plume,
    Hanabi,
    /// The same app without particles: the frame's floor.
    Empty,
    /// The same app with `--effects` entities that carry what a `PlumeEffect` requires
    /// (transform, visibility, a render-world twin) and no plugin: Bevy's own cost of them.
    Bare,
}

struct Args {
    plugin: Plugin,
    live: u32,
    effects: u32,
    frames: u32,
    out: Option<String>,
    /// Plume's renderer.
    draw: PlumeDraw,
    /// Samples a pixel: 1 or 4.
    msaa: u32,
    /// A `Camera2d` instead of a `Camera3d`.
    two_d: bool,
    /// Every particle drawn as a 200-triangle sphere.
    mesh: bool,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        plugin: Plugin::Plume,
        live: 1_000_000,
        effects: 1,
        frames: 120,
        out: None,
        draw: PlumeDraw::Auto,
        msaa: 1,
        two_d: false,
        mesh: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let number = || {
            value
                .parse::<u32>()
                .map_err(|_| format!("{flag} {value}: not a count"))
        };
        match flag.as_str() {
            "--plugin" => {
                args.plugin = match value.as_str() {
                    "plume" => Plugin::Plume,
                    "hanabi" => Plugin::Hanabi,
                    "empty" => Plugin::Empty,
                    "bare" => Plugin::Bare,
                    _ => return Err(format!("--plugin {value}: plume, hanabi, empty or bare")),
                }
            }
            "--live" => args.live = number()?.max(1),
            "--effects" => args.effects = number()?.max(1),
            "--frames" => args.frames = number()?.max(1),
            "--out" => args.out = Some(value),
            "--draw" => {
                args.draw = match value.as_str() {
                    "auto" => PlumeDraw::Auto,
                    "raster" => PlumeDraw::Raster,
                    "compute" => PlumeDraw::Compute,
                    _ => return Err(format!("--draw {value}: auto, raster or compute")),
                }
            }
            "--msaa" => {
                args.msaa = match number()? {
                    n @ (1 | 4) => n,
                    _ => return Err(format!("--msaa {value}: 1 or 4")),
                }
            }
            "--mesh" => args.mesh = number()? == 1,
            "--view" => {
                args.two_d = match value.as_str() {
                    "3d" => false,
                    "2d" => true,
                    _ => return Err(format!("--view {value}: 3d or 2d")),
                }
            }
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    Ok(args)
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let headless = Headless {
        out: "unused.png".into(),
        frames: 0,
        size: UVec2::new(1280, 720),
        window: false,
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(Some(&headless), "assets"))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 60.0,
        )));
    match args.plugin {
        Plugin::Plume => {
            app.add_plugins(PlumePlugin);
        }
        Plugin::Hanabi => {
            app.add_plugins(bevy_hanabi::HanabiPlugin);
        }
        Plugin::Empty | Plugin::Bare => {}
    }
    app.finish();
    app.cleanup();
    let timer = FrameTimer::new(&mut app);
    let image = Image::new_target_texture(1280, 720, TextureFormat::Rgba8UnormSrgb, None);
    let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    let spread = grid_spacing(args.effects);
    let msaa = if args.msaa == 4 {
        Msaa::Sample4
    } else {
        Msaa::Off
    };
    let target = RenderTarget::Image(image.clone().into());
    if args.two_d {
        // 100 pixels a metre: the 7.2 m the image is high hold the fountain's 3 m.
        app.world_mut().spawn((
            Camera2d,
            msaa,
            target,
            Projection::Orthographic(OrthographicProjection {
                scale: 0.01,
                ..OrthographicProjection::default_2d()
            }),
            Transform::from_xyz(0.0, 3.0, 0.0),
        ));
    } else {
        app.world_mut().spawn((
            Camera3d::default(),
            msaa,
            target,
            Transform::from_xyz(0.0, 4.0, 14.0 + spread * (args.effects as f32).sqrt())
                .looking_at(Vec3::new(0.0, 3.0, 0.0), Vec3::Y),
        ));
    }
    let rate = f64::from(args.live) / LIFETIME;
    let mesh = args.mesh.then(|| {
        let sphere = Sphere::new(0.5).mesh().uv(10, 11);
        app.world_mut().resource_mut::<Assets<Mesh>>().add(sphere)
    });
    match args.plugin {
        Plugin::Plume => spawn_plume(&mut app, &args, rate, spread, mesh),
        Plugin::Hanabi => spawn_hanabi(&mut app, &args, rate, spread, mesh),
        Plugin::Bare => {
            for i in 0..args.effects {
                app.world_mut().spawn((
                    Transform::from_translation(grid_position(i, args.effects, spread)),
                    Visibility::default(),
                    bevy::render::sync_world::SyncToRenderWorld::default(),
                ));
            }
        }
        Plugin::Empty => {}
    }
    // Fill the fountains: a lifetime and a half of frames.
    let fill = (LIFETIME * 1.5 * 60.0) as u32;
    let device = app.world().resource::<RenderDevice>().wgpu_device().clone();
    let wait = || {
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
    };
    for _ in 0..fill {
        app.update();
        wait();
    }
    let mut cpu = Vec::new();
    let mut frame = Vec::new();
    if let Some(timer) = &timer {
        timer.readings.lock().unwrap().clear();
    }
    for _ in 0..args.frames {
        let t0 = Instant::now();
        app.update();
        let t1 = Instant::now();
        wait();
        let t2 = Instant::now();
        cpu.push((t1 - t0).as_secs_f64() * 1e3);
        frame.push((t2 - t0).as_secs_f64() * 1e3);
    }
    let captured: Arc<Mutex<Option<Image>>> = Arc::default();
    let sink = captured.clone();
    let mut screenshot = app.world_mut().spawn(Screenshot::image(image));
    screenshot.observe(move |shot: On<ScreenshotCaptured>| {
        *sink.lock().unwrap() = Some(shot.image.clone());
    });
    if let Some(out) = &args.out {
        screenshot.observe(save_to_disk(out.clone()));
    }
    let mut lit_pixels = None;
    for _ in 0..30 {
        app.update();
        wait();
        if let Some(shot) = captured.lock().unwrap().take() {
            lit_pixels = Some(count_lit_pixels(&shot));
        }
        if lit_pixels.is_some() {
            break;
        }
    }
    // Let the screenshot's file be written.
    for _ in 0..3 {
        app.update();
        wait();
    }
    let name = match args.plugin {
        Plugin::Plume => "plume",
        Plugin::Hanabi => "hanabi",
        Plugin::Empty => "empty",
        Plugin::Bare => "bare",
    };
    let optional = |v: Option<f64>| v.map_or("null".to_string(), |v| format!("{v:.3}"));
    let mut gpu = timer.map_or_else(Vec::new, |t| {
        std::mem::take(&mut *t.readings.lock().unwrap())
    });
    let (gpu_median, gpu_p90) = if gpu.is_empty() {
        (None, None)
    } else {
        (Some(quantile(&mut gpu, 0.5)), Some(quantile(&mut gpu, 0.9)))
    };
    println!(
        "{{\"plugin\":\"{name}\",\"draw\":\"{:?}\",\"view\":\"{}\",\"mesh\":{},\"msaa\":{},\"live_per_effect\":{},\"effects\":{},\"frames\":{},\"frame_ms\":{:.3},\"frame_ms_p90\":{:.3},\"cpu_ms\":{:.3},\"cpu_ms_p90\":{:.3},\"gpu_ms\":{},\"gpu_ms_p90\":{},\"lit_pixels\":{}}}",
        args.draw,
        if args.two_d { "2d" } else { "3d" },
        args.mesh,
        args.msaa,
        args.live,
        args.effects,
        args.frames,
        quantile(&mut frame, 0.5),
        quantile(&mut frame, 0.9),
        quantile(&mut cpu, 0.5),
        quantile(&mut cpu, 0.9),
        optional(gpu_median),
        optional(gpu_p90),
        lit_pixels.map_or("null".to_string(), |n| n.to_string()),
    );
}

/// The GPU's time for a frame, by Plume's `GpuTimer`: its start stamped in a command buffer
/// placed before every other of the frame, its end in one placed after them (each an empty
/// compute pass; Vulkan writes the end once every command before it has finished). A reading
/// comes back two frames later, without waiting, and the timer stamps again once it has: every
/// other frame is timed.
#[derive(Resource, Clone)]
struct FrameTimer {
    timer: Arc<Mutex<GpuTimer>>,
    /// Milliseconds of each timed frame, as they came back.
    readings: Arc<Mutex<Vec<f64>>>,
}

impl FrameTimer {
    /// Adds the timer's two systems to the render world's root schedule; `None` where the
    /// device has no timestamp queries.
    fn new(app: &mut App) -> Option<Self> {
        let render = app.sub_app_mut(RenderApp);
        let gpu = Gpu::from_device(
            render.world().resource::<RenderDevice>().wgpu_device(),
            render.world().resource::<RenderQueue>(),
        );
        let timer = Self {
            timer: Arc::new(Mutex::new(GpuTimer::new(&gpu)?)),
            readings: Arc::default(),
        };
        render.insert_resource(timer.clone()).add_systems(
            RenderGraph,
            (
                stamp_frame_start.in_set(RenderGraphSystems::Begin),
                stamp_frame_end
                    .after(RenderGraphSystems::Render)
                    .before(RenderGraphSystems::Submit),
            ),
        );
        Some(timer)
    }
}

/// Stamps the frame's start (taking a reading that came back) before its other command buffers.
fn stamp_frame_start(
    timer: Res<FrameTimer>,
    device: Res<RenderDevice>,
    pending: ResMut<PendingCommandBuffers>,
) {
    push_stamp(&device, pending, "frame timer start", |encoder| match timer
        .timer
        .lock()
        .unwrap()
        .begin(encoder)
    {
        Ok(Some(ns)) => timer.readings.lock().unwrap().push(ns as f64 * 1e-6),
        Ok(None) => {}
        Err(err) => warn_once!("frame timer: {err}"),
    });
}

/// Stamps the frame's end after its other command buffers.
fn stamp_frame_end(
    timer: Res<FrameTimer>,
    device: Res<RenderDevice>,
    pending: ResMut<PendingCommandBuffers>,
) {
    push_stamp(&device, pending, "frame timer end", |encoder| {
        timer.timer.lock().unwrap().end(encoder);
    });
}

/// A command buffer of its own, recorded by `record`, among the frame's pending ones.
fn push_stamp(
    device: &RenderDevice,
    mut pending: ResMut<PendingCommandBuffers>,
    name: &'static str,
    record: impl FnOnce(&mut wgpu::CommandEncoder),
) {
    let mut encoder = device
        .wgpu_device()
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    record(&mut encoder);
    pending.push_encoder(encoder, name);
}

/// Pixels that differ from the image's most common colour by more than 2 in a channel.
fn count_lit_pixels(image: &Image) -> u64 {
    let rgba = image
        .clone()
        .try_into_dynamic()
        .expect("an RGBA8 image")
        .to_rgba8();
    let mut counts = std::collections::HashMap::new();
    for p in rgba.pixels() {
        *counts.entry(p.0).or_insert(0u64) += 1;
    }
    let background = counts
        .into_iter()
        .max_by_key(|&(_, n)| n)
        .map(|(c, _)| c)
        .unwrap_or_default();
    rgba.pixels()
        .filter(|p| p.0.iter().zip(background).any(|(&a, b)| a.abs_diff(b) > 2))
        .count() as u64
}

/// Metres between fountains on the grid of `n`.
fn grid_spacing(n: u32) -> f32 {
    if n > 1 {
        1.5
    } else {
        0.0
    }
}

/// Where fountain `i` of `n` stands: a square grid centred on the origin.
fn grid_position(i: u32, n: u32, spacing: f32) -> Vec3 {
    let side = (n as f32).sqrt().ceil() as u32;
    let (x, z) = (i % side, i / side);
    let half = (side as f32 - 1.0) * 0.5;
    Vec3::new(
        (x as f32 - half) * spacing,
        0.0,
        (z as f32 - half) * spacing,
    )
}

fn quantile(values: &mut [f64], q: f64) -> f64 {
    values.sort_by(|a, b| a.total_cmp(b));
    values[((values.len() - 1) as f64 * q).round() as usize]
}

/// The fountain as a Plume effect file.
fn plume_source(live: u32, rate: f64) -> String {
    // Capacity: what a rate with its fractional carry can have alive, plus a margin.
    let capacity = live + live / 50 + 64;
    format!(
        r#"Effect(name: "fountain", capacity: {capacity}, seed: 1, dt: 0.016666666666666666,
    emitters: [Emitter(rate: {rate:?}, shape: Point((0.0, 0.0, 0.0)),
        velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 12.0, speed: (7.5, 8.5)),
        lifetime: Some(({LIFETIME:?}, {LIFETIME:?})))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5)],
    integrator: SemiImplicitEuler,
    render: Render(
        color: [(0.0, (0.4, 0.7, 1.0, 1.0)), (1.0, (0.4, 0.7, 1.0, 0.0))],
        size: [(0.0, 0.05), (1.0, 0.01)],
        blend: Alpha))
"#
    )
}

fn spawn_plume(app: &mut App, args: &Args, rate: f64, spread: f32, mesh: Option<Handle<Mesh>>) {
    let source = plume_source(args.live, rate);
    let asset = PlumeEffectAsset::compile("fountain.plume.ron", &source, None)
        .unwrap_or_else(|e| panic!("the benchmark's fountain does not compile:\n{e}"));
    let draw = args.draw;
    spawn_grid(app, args.effects, spread, asset, |h| {
        let effect = PlumeEffect::new(h).with_draw(draw);
        match &mesh {
            Some(mesh) => effect.with_mesh(mesh.clone()),
            None => effect,
        }
    });
}

/// Adds `asset` and spawns `n` effects of it on the grid, each made by `effect`; returns them.
fn spawn_grid<A: Asset, C: Component>(
    app: &mut App,
    n: u32,
    spread: f32,
    asset: A,
    effect: impl Fn(Handle<A>) -> C,
) -> Vec<Entity> {
    let handle = app.world_mut().resource_mut::<Assets<A>>().add(asset);
    (0..n)
        .map(|i| {
            let at = Transform::from_translation(grid_position(i, n, spread));
            app.world_mut().spawn((effect(handle.clone()), at)).id()
        })
        .collect()
}

fn spawn_hanabi(app: &mut App, args: &Args, rate: f64, spread: f32, mesh: Option<Handle<Mesh>>) {
    use bevy_hanabi::prelude::*;
    let w = ExprWriter::new();
    let age = SetAttributeModifier::new(Attribute::AGE, w.lit(0.).expr());
    let lifetime = SetAttributeModifier::new(Attribute::LIFETIME, w.lit(LIFETIME as f32).expr());
    let position = SetAttributeModifier::new(Attribute::POSITION, w.lit(Vec3::ZERO).expr());
    let velocity = (w.lit(Vec3::new(0., 8., 0.))
        + (w.rand(VectorType::VEC3F) * w.lit(2.) - w.lit(1.)) * w.lit(1.5))
    .expr();
    let velocity = SetAttributeModifier::new(Attribute::VELOCITY, velocity);
    let gravity = AccelModifier::new(w.lit(Vec3::new(0., -9.81, 0.)).expr());
    let drag = LinearDragModifier::new(w.lit(0.5).expr());
    let mut color = bevy_hanabi::Gradient::new();
    color.add_key(0.0, Vec4::new(0.4, 0.7, 1.0, 1.0));
    color.add_key(1.0, Vec4::new(0.4, 0.7, 1.0, 0.0));
    let size = bevy_hanabi::Gradient::linear(Vec3::splat(0.05), Vec3::splat(0.01));
    let capacity = args.live + args.live / 50 + 64;
    let asset = EffectAsset::new(
        capacity,
        SpawnerSettings::rate((rate as f32).into()),
        w.finish(),
    )
    .with_name("fountain")
    .with_alpha_mode(bevy_hanabi::AlphaMode::Blend)
    .init(position)
    .init(velocity)
    .init(age)
    .init(lifetime)
    .update(gravity)
    .update(drag)
    .render(ColorOverLifetimeModifier::new(color))
    .render(SizeOverLifetimeModifier {
        gradient: size,
        screen_space_size: false,
    })
    .render(OrientModifier::new(OrientMode::ParallelCameraDepthPlane));
    let effects = spawn_grid(app, args.effects, spread, asset, ParticleEffect::new);
    if let Some(mesh) = mesh {
        for e in effects {
            app.world_mut()
                .entity_mut(e)
                .insert(EffectMesh(mesh.clone()));
        }
    }
}
