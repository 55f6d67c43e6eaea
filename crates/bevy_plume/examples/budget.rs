//! A scene of 1,000 effects, most of them out of view or far away, with and without thinning:
//! the measurement behind docs/bevy.md's "Thinning a scene of 1,000 effects". A headless app
//! (no window: frames stepped by hand at 1/60 s, each timed around `App::update`) spreads
//! 1,000 small fountains over a field 200 m wide and 400 m deep around a camera at its middle
//! (a 60° view: 381 of them in view, most of those far; the rest behind or beside it). Each
//! case, in a process of its own, runs 60 frames to settle (more than a particle's life), then
//! 60 timed frames, and prints one JSON line: the median and 90th-percentile frame (ms), the
//! GPU time of the steps where the device has timestamps, the particles alive (read back by
//! `PlumeDiagnosticsPlugin`), and how many effects are seen, how many spawn at all and how
//! many the budget's GPU time pauses. The
//! cases: `none`; `lod` (`PlumeLod::new(24.0, 0.0)` on every effect: every spawn from 24
//! pixels across, none unseen); `budget` (`PlumeBudget::live_particles(20_000)`, a tenth of
//! what they keep alive unthinned); `both`; `gpu=MS` (`PlumeBudget::step_gpu_ms(MS)`: the
//! unseen effects' steps paused while the steps would take more; not among the defaults,
//! since what fits depends on the device).
//!
//! `cargo +nightly run --ignore-rust-version --example budget [CASE ...]` (a debug build, as
//! the tests run; docs/bevy.md gives its figures on lavapipe).

use std::time::{Duration, Instant};

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::RenderApp;
use bevy::time::TimeUpdateStrategy;
use bevy_plume::headless::{default_plugins, Headless};
use bevy_plume::{
    PlumeBudget, PlumeDiagnosticsPlugin, PlumeEffect, PlumeEffectAsset, PlumeLod, PlumePlugin,
    PlumeRenderStats, PlumeThinning,
};

/// A small fountain: 200 particles alive, in a declared box (so Bevy culls it by its bounds).
const FOUNTAIN: &str = r#"Effect(name: "small fountain", capacity: 256,
    emitters: [Emitter(rate: 200.0, lifetime: Some((1.0, 1.0)), shape: Point((0.0, 0.0, 0.0)),
        velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 15.0, speed: (3.0, 4.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    bounds: Some((min: (-1.0, -5.0, -1.0), max: (1.0, 1.0, 1.0))),
    render: Render(color: [(0.0, (0.4, 0.7, 1.0, 1.0)), (1.0, (0.1, 0.2, 1.0, 0.0))],
                   size: [(0.0, 0.06)], blend: Additive),
)"#;

const EFFECTS: u32 = 1000;
const SIZE: UVec2 = UVec2::new(640, 360);

fn main() -> AppExit {
    let cases: Vec<String> = std::env::args().skip(1).collect();
    if cases.len() != 1 {
        // Each case in a process of its own: a fresh app, device and logger.
        let cases = match cases.is_empty() {
            true => ["none", "lod", "budget", "both"].map(String::from).to_vec(),
            false => cases,
        };
        let exe = std::env::current_exe().expect("this program's path");
        for case in cases {
            match std::process::Command::new(&exe).arg(&case).status() {
                Ok(status) if status.success() => {}
                _ => return AppExit::from_code(1),
            }
        }
        return AppExit::Success;
    }
    let case = cases[0].as_str();
    let (lod, budget) = match case {
        "none" => (false, None),
        "lod" => (true, None),
        "budget" => (false, Some(PlumeBudget::live_particles(20_000))),
        "both" => (true, Some(PlumeBudget::live_particles(20_000))),
        other => match other.strip_prefix("gpu=").map(str::parse::<f32>) {
            Some(Ok(ms)) => (false, Some(PlumeBudget::step_gpu_ms(ms))),
            _ => {
                eprintln!("error: unknown case `{other}`: none, lod, budget, both or gpu=MS");
                return AppExit::from_code(2);
            }
        },
    };
    match run(case, lod, budget) {
        Ok(()) => AppExit::Success,
        Err(message) => {
            eprintln!("error: {message}");
            AppExit::from_code(1)
        }
    }
}

/// Runs one case and prints its line.
fn run(case: &str, lod: bool, budget: Option<PlumeBudget>) -> Result<(), String> {
    let dir = std::env::temp_dir().join(format!("plume-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    std::fs::write(dir.join("fountain.plume.ron"), FOUNTAIN).map_err(|e| e.to_string())?;
    let headless = Headless {
        out: "unused.png".into(),
        frames: 0,
        size: SIZE,
        window: false,
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(
        Some(&headless),
        dir.to_str().expect("UTF-8"),
    ))
    .add_plugins((PlumePlugin, PlumeDiagnosticsPlugin))
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )));
    if let Some(budget) = budget {
        app.insert_resource(budget);
    }
    app.finish();
    app.cleanup();
    let image = Image::new_target_texture(SIZE.x, SIZE.y, TextureFormat::Rgba8UnormSrgb, None);
    let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    app.world_mut().spawn((
        Camera3d::default(),
        Projection::Perspective(PerspectiveProjection {
            fov: 60f32.to_radians(),
            ..default()
        }),
        RenderTarget::Image(image.into()),
        Transform::from_xyz(0.0, 2.0, 0.0).looking_at(Vec3::new(0.0, 2.0, -1.0), Vec3::Y),
    ));
    let handle: Handle<PlumeEffectAsset> = app
        .world()
        .resource::<AssetServer>()
        .load("fountain.plume.ron");
    // A field 200 m wide and 400 m deep, the camera at its middle looking down −z: a
    // deterministic scatter (golden-ratio steps) so every case sees the same scene.
    for k in 0..EFFECTS {
        let u = (f64::from(k) * 0.618_033_988_749_895).fract() as f32;
        let v = (f64::from(k) * 0.754_877_666_246_693).fract() as f32;
        let at = Vec3::new(200.0 * u - 100.0, 0.0, 200.0 - 400.0 * v);
        let mut entity = app.world_mut().spawn((
            PlumeEffect::new(handle.clone()),
            Transform::from_translation(at),
        ));
        if lod {
            entity.insert(PlumeLod::new(24.0, 0.0));
        }
    }
    let mut waited = 0;
    while !app.world().resource::<AssetServer>().is_loaded(&handle) {
        if waited == 1000 {
            return Err("the effect file did not load".into());
        }
        app.update();
        std::thread::sleep(Duration::from_millis(2));
        waited += 1;
    }
    for _ in 0..60 {
        app.update();
    }
    let mut frames = Vec::new();
    let mut gpu = Vec::new();
    for _ in 0..60 {
        let start = Instant::now();
        app.update();
        frames.push(start.elapsed().as_secs_f64() * 1e3);
        let stats = app
            .sub_app(RenderApp)
            .world()
            .resource::<PlumeRenderStats>();
        gpu.extend(stats.step_gpu_ns.map(|ns| ns as f64 / 1e6));
    }
    let stats = *app
        .sub_app(RenderApp)
        .world()
        .resource::<PlumeRenderStats>();
    let world = app.world_mut();
    let thinnings: Vec<PlumeThinning> = world
        .query::<&PlumeThinning>()
        .iter(world)
        .copied()
        .collect();
    let spawning = thinnings.iter().filter(|t| t.scale > 0.0).count();
    let seen = thinnings.iter().filter(|t| t.pixels > 0.0).count();
    let paused = thinnings.iter().filter(|t| t.paused).count();
    let percentile = |times: &mut Vec<f64>, p: f64| -> Option<f64> {
        times.sort_by(f64::total_cmp);
        let i = ((times.len() as f64 - 1.0) * p).round() as usize;
        times.get(i).copied()
    };
    let gpu_median = percentile(&mut gpu, 0.5).map_or("null".into(), |ms| format!("{ms:.3}"));
    println!(
        "{{\"case\":\"{case}\",\"effects\":{EFFECTS},\"seen\":{seen},\"spawning\":{spawning},\"paused\":{paused},\"live_particles\":{},\"frame_median_ms\":{:.3},\"frame_p90_ms\":{:.3},\"step_gpu_median_ms\":{gpu_median}}}",
        stats.live_particles,
        percentile(&mut frames, 0.5).unwrap_or(f64::NAN),
        percentile(&mut frames, 0.9).unwrap_or(f64::NAN),
    );
    Ok(())
}
