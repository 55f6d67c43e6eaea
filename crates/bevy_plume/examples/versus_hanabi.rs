//! The same fountain in bevy_plume and in bevy_hanabi 0.20, one plugin per run, in a headless
//! 1280x720 Bevy app; prints one JSON line of frame times.
//!
//! ```sh
//! cargo +nightly run --release --ignore-rust-version --features hanabi --example versus_hanabi -- \
//!     --plugin plume --live 1000000 [--effects 1] [--frames 120] [--out frame.png] \
//!     [--draw auto|raster|compute]
//! ```
//!
//! The fountain: particles spawned at a constant rate for `live` of them alive at once over a
//! 2 s lifetime, launched up at about 8 m/s (Plume: a 12° cone at 7.5 to 8.5 m/s; hanabi:
//! 8 m/s up plus a uniform ±1.5 m/s per axis: the two have no common velocity form), gravity,
//! linear drag 0.5, size 0.05 m to 0.01 m and a blue that fades out over life, alpha blended,
//! unsorted. With `--effects K`, K such fountains of `live` particles each on a grid.
//!
//! Timing, per frame once the fountains are full: `cpu_ms` is `App::update` (main and render
//! worlds: pipelined rendering is off, so the render world runs inside it); `frame_ms` adds the
//! wait until the GPU has finished the frame. Medians over `--frames` frames. `--draw` picks
//! Plume's renderer (`PlumeDraw`; default auto).

use std::time::{Duration, Instant};

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::renderer::RenderDevice;
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use bevy::time::TimeUpdateStrategy;
use bevy_plume::headless::{default_plugins, Headless};
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeEffectAsset, PlumePlugin};

/// Seconds each particle lives.
const LIFETIME: f64 = 2.0;

#[derive(Clone, Copy, PartialEq)]
enum Plugin {
    Plume,
    Hanabi,
    /// The same app without particles: the frame's floor.
    Empty,
}

struct Args {
    plugin: Plugin,
    live: u32,
    effects: u32,
    frames: u32,
    out: Option<String>,
    /// Plume's renderer.
    draw: PlumeDraw,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        plugin: Plugin::Plume,
        live: 1_000_000,
        effects: 1,
        frames: 120,
        out: None,
        draw: PlumeDraw::Auto,
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
                    _ => return Err(format!("--plugin {value}: plume, hanabi or empty")),
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
        Plugin::Empty => {}
    }
    app.finish();
    app.cleanup();
    let image = Image::new_target_texture(1280, 720, TextureFormat::Rgba8UnormSrgb, None);
    let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    let spread = grid_spacing(args.effects);
    app.world_mut().spawn((
        Camera3d::default(),
        RenderTarget::Image(image.clone().into()),
        Transform::from_xyz(0.0, 4.0, 14.0 + spread * (args.effects as f32).sqrt())
            .looking_at(Vec3::new(0.0, 3.0, 0.0), Vec3::Y),
    ));
    let rate = f64::from(args.live) / LIFETIME;
    match args.plugin {
        Plugin::Plume => spawn_plume(&mut app, &args, rate, spread),
        Plugin::Hanabi => spawn_hanabi(&mut app, &args, rate, spread),
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
    for _ in 0..args.frames {
        let t0 = Instant::now();
        app.update();
        let t1 = Instant::now();
        wait();
        let t2 = Instant::now();
        cpu.push((t1 - t0).as_secs_f64() * 1e3);
        frame.push((t2 - t0).as_secs_f64() * 1e3);
    }
    if let Some(out) = &args.out {
        app.world_mut()
            .spawn(Screenshot::image(image))
            .observe(save_to_disk(out.clone()));
        for _ in 0..10 {
            app.update();
            wait();
        }
    }
    let name = match args.plugin {
        Plugin::Plume => "plume",
        Plugin::Hanabi => "hanabi",
        Plugin::Empty => "empty",
    };
    println!(
        "{{\"plugin\":\"{name}\",\"draw\":\"{:?}\",\"live_per_effect\":{},\"effects\":{},\"frames\":{},\"frame_ms\":{:.3},\"frame_ms_p90\":{:.3},\"cpu_ms\":{:.3}}}",
        args.draw,
        args.live,
        args.effects,
        args.frames,
        quantile(&mut frame, 0.5),
        quantile(&mut frame, 0.9),
        quantile(&mut cpu, 0.5),
    );
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

fn spawn_plume(app: &mut App, args: &Args, rate: f64, spread: f32) {
    let source = plume_source(args.live, rate);
    let asset = PlumeEffectAsset::compile("fountain.plume.ron", &source, None)
        .unwrap_or_else(|e| panic!("the benchmark's fountain does not compile:\n{e}"));
    let draw = args.draw;
    spawn_grid(app, args.effects, spread, asset, |h| {
        PlumeEffect::new(h).with_draw(draw)
    });
}

/// Adds `asset` and spawns `n` effects of it on the grid, each made by `effect`.
fn spawn_grid<A: Asset, C: Component>(
    app: &mut App,
    n: u32,
    spread: f32,
    asset: A,
    effect: impl Fn(Handle<A>) -> C,
) {
    let handle = app.world_mut().resource_mut::<Assets<A>>().add(asset);
    for i in 0..n {
        app.world_mut().spawn((
            effect(handle.clone()),
            Transform::from_translation(grid_position(i, n, spread)),
        ));
    }
}

fn spawn_hanabi(app: &mut App, args: &Args, rate: f64, spread: f32) {
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
    .render(OrientModifier::new(OrientMode::FaceCameraPosition));
    spawn_grid(app, args.effects, spread, asset, ParticleEffect::new);
}
