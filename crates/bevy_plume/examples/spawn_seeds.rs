//! Frame times while effects with seeds of their own are spawned: the measurement behind
//! docs/bevy.md's "No hitches". A headless app (no window: frames stepped by hand, each
//! timed around `App::update`) runs one effect for 60 frames, then spawns one more entity
//! of the same file every frame, each with a new seed (a variant to compile), for 100 frames,
//! then 60 more frames. The file has an accuracy budget (its first compile calibrates; the
//! seeds take the remembered choice and only compile). Prints one JSON line: the medians and
//! maxima of each phase, ms.
//!
//! `cargo +nightly run --ignore-rust-version --example spawn_seeds` (a debug build, as the
//! tests run; docs/bevy.md gives its figures on lavapipe).

use std::time::{Duration, Instant};

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::time::TimeUpdateStrategy;
use bevy_plume::headless::{default_plugins, Headless};
use bevy_plume::{PlumeEffect, PlumeEffectAsset, PlumePlugin, SimulationSpace};

/// A small effect whose integrator a budget chooses (an attractor has no closed form).
const EFFECT: &str = r#"Effect(name: "seeded", capacity: 2000,
    emitters: [Emitter(rate: 400.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
        velocity: Radial(speed: (0.5, 1.5)), lifetime: Some((2.0, 3.0)))],
    forces: [Attractor(center: (0.0, 0.0, 0.0), strength: 4.0, range: 5.0)],
    accuracy: (position: 0.01, over: 2.0),
    render: Render(color: [(0.0, (1.0, 0.6, 0.2, 1.0))], size: [(0.0, 0.05)], blend: Additive),
)"#;

fn main() -> AppExit {
    let dir = std::env::temp_dir().join(format!("plume-spawn-seeds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    std::fs::write(dir.join("seeded.plume.ron"), EFFECT).expect("the effect file");
    let headless = Headless {
        out: "unused.png".into(),
        frames: 0,
        size: UVec2::new(320, 180),
        window: false,
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(
        Some(&headless),
        dir.to_str().expect("UTF-8"),
    ))
    .add_plugins(PlumePlugin)
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )));
    app.finish();
    app.cleanup();
    let image = Image::new_target_texture(320, 180, TextureFormat::Rgba8UnormSrgb, None);
    let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    app.world_mut().spawn((
        Camera3d::default(),
        RenderTarget::Image(image.into()),
        Transform::from_xyz(0.0, 0.0, 8.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    let handle: Handle<PlumeEffectAsset> = app
        .world()
        .resource::<AssetServer>()
        .load("seeded.plume.ron");
    let spawn = |app: &mut App, seed: Option<u32>| {
        let effect = PlumeEffect::new(handle.clone()).with_space(SimulationSpace::Local);
        let effect = match seed {
            Some(seed) => effect.with_seed(seed),
            None => effect,
        };
        app.world_mut().spawn((effect, Transform::IDENTITY));
    };
    spawn(&mut app, None);
    // Until the file has loaded (at most 1,000 frames of 2 ms).
    let mut waited = 0;
    while !app.world().resource::<AssetServer>().is_loaded(&handle) {
        if waited == 1000 {
            eprintln!("error: the effect file did not load");
            return AppExit::from_code(1);
        }
        app.update();
        std::thread::sleep(Duration::from_millis(2));
        waited += 1;
    }
    let frame = |app: &mut App| {
        let start = Instant::now();
        app.update();
        start.elapsed().as_secs_f64() * 1e3
    };
    let before: Vec<f64> = (0..60).map(|_| frame(&mut app)).collect();
    let spawning: Vec<f64> = (0..100u32)
        .map(|k| {
            spawn(&mut app, Some(1000 + k));
            frame(&mut app)
        })
        .collect();
    let after: Vec<f64> = (0..60).map(|_| frame(&mut app)).collect();
    let stats = |times: &[f64]| {
        let mut sorted = times.to_vec();
        sorted.sort_by(f64::total_cmp);
        (sorted[sorted.len() / 2], sorted[sorted.len() - 1])
    };
    let (b, s, a) = (stats(&before), stats(&spawning), stats(&after));
    println!(
        "{{\"before_median_ms\":{:.3},\"before_max_ms\":{:.3},\"spawning_median_ms\":{:.3},\"spawning_max_ms\":{:.3},\"after_median_ms\":{:.3},\"after_max_ms\":{:.3},\"spawning_max_over_median\":{:.2}}}",
        b.0, b.1, s.0, s.1, a.0, a.1, s.1 / s.0
    );
    AppExit::Success
}
