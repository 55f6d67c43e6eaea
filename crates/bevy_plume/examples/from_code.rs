//! An effect driven from game code: click the ground and sparks burst where it was hit; the
//! left and right arrow keys change the wind that blows them (a param of the effect file,
//! read at run time, so nothing recompiles); space clears the air by restarting the effect.
//!
//! In a window: `cargo +nightly run --ignore-rust-version --example from_code`.
//! Headless: `... --example from_code -- --headless from_code.png --frames 90`: with no mouse,
//! a burst fires every quarter second along a line and the wind blows from the left.
//! The effect file is `crates/bevy_plume/assets/impact.plume.ron`. `tests/app/click.rs` includes
//! this file as a module and clicks through [`burst_on_click`].

#![allow(dead_code)] // tests/app/click.rs uses part of it.

use bevy::core_pipeline::prepass::DepthPrepass;
use bevy::prelude::*;
use bevy_plume::headless::{default_plugins, Headless, HeadlessPlugin};
use bevy_plume::{PlumeBurst, PlumeEffect, PlumePlugin};

/// The example's asset folder.
pub const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets");

/// How much one press of an arrow key changes the wind (m/s²), and its limit either way.
const WIND_STEP: f32 = 2.0;
const WIND_LIMIT: f32 = 20.0;

fn main() -> AppExit {
    let headless = match Headless::from_args() {
        Ok(h) => h,
        Err(message) => {
            eprintln!(
                "error: {message}\nusage: from_code [--headless OUT.png [--frames N] [--size WxH]]"
            );
            return AppExit::from_code(2);
        }
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(headless.as_ref(), ASSETS))
        .add_plugins(PlumePlugin)
        .add_systems(Startup, setup);
    match headless {
        Some(headless) => {
            app.add_plugins(HeadlessPlugin(headless))
                .add_systems(Update, demo_bursts);
        }
        None => {
            app.add_systems(Update, (burst_on_click, wind_on_keys));
        }
    }
    app.run()
}

/// Marks the sparks' effect, which sits at the origin so that a burst's position is the
/// world position it was fired at.
#[derive(Component)]
pub struct Impacts;

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(30.0, 30.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.2, 0.22, 0.25))),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 4_000.0,
            ..default()
        },
        Transform::from_xyz(3.0, 10.0, 5.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    // Crates the sparks bounce off: they meet what the camera's depth prepass draws (the
    // effect's SceneDepth collider), so nothing about the crates is in the effect file.
    let crate_mesh = meshes.add(Cuboid::new(1.2, 0.9, 1.2));
    let wood = materials.add(Color::srgb(0.55, 0.38, 0.2));
    // Between the headless demo's burst points (x = -6 + 1.5 k), downwind of one each.
    for (x, z) in [(-3.75, -2.0), (0.75, -2.6), (3.75, -1.0)] {
        commands.spawn((
            Mesh3d(crate_mesh.clone()),
            MeshMaterial3d(wood.clone()),
            Transform::from_xyz(x, 0.45, z),
        ));
    }
    commands.spawn((
        Camera3d::default(),
        DepthPrepass,
        Transform::from_xyz(0.0, 6.0, 12.0).looking_at(Vec3::new(0.0, 0.5, 0.0), Vec3::Y),
    ));
    // Takes bursts, and reads `wind` at run time (set now, so later changes need no rebuild).
    commands.spawn((
        Impacts,
        PlumeEffect::new(assets.load("impact.plume.ron"))
            .with_bursts()
            .with_param("wind", 0.0),
    ));
}

/// A burst of sparks where the cursor's ray meets the ground (y = 0), on a left click.
pub fn burst_on_click(
    buttons: Res<ButtonInput<MouseButton>>,
    windows: Query<&Window>,
    cameras: Query<(&Camera, &GlobalTransform)>,
    mut impacts: Query<&mut PlumeEffect, With<Impacts>>,
) {
    if !buttons.just_pressed(MouseButton::Left) {
        return;
    }
    let Some(cursor) = windows.iter().find_map(Window::cursor_position) else {
        return;
    };
    let Ok((camera, eye)) = cameras.single() else {
        return;
    };
    let Ok(ray) = camera.viewport_to_world(eye, cursor) else {
        return;
    };
    let Some(distance) = ray.intersect_plane(Vec3::ZERO, InfinitePlane3d::new(Vec3::Y)) else {
        return;
    };
    let hit = ray.get_point(distance);
    for mut effect in &mut impacts {
        effect.burst(PlumeBurst::new(400).at(hit));
    }
}

/// The arrow keys change the wind; space restarts the effect (every spark gone at once).
fn wind_on_keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut impacts: Query<&mut PlumeEffect, With<Impacts>>,
) {
    let change = match () {
        _ if keys.just_pressed(KeyCode::ArrowRight) => WIND_STEP,
        _ if keys.just_pressed(KeyCode::ArrowLeft) => -WIND_STEP,
        _ => 0.0,
    };
    for mut effect in &mut impacts {
        if change != 0.0 {
            let wind = effect.params.get("wind").copied().unwrap_or(0.0);
            let wind = (wind + change).clamp(-WIND_LIMIT, WIND_LIMIT);
            effect.set_param("wind", wind);
            info!("wind {wind} m/s²");
        }
        if keys.just_pressed(KeyCode::Space) {
            effect.restart();
        }
    }
}

/// Headless, with no mouse or keys: a burst every quarter second along a line across the
/// ground, with the wind from the left, so the image shows bursts of every age drifting right.
fn demo_bursts(time: Res<Time>, mut impacts: Query<&mut PlumeEffect, With<Impacts>>) {
    let period = 0.25;
    let now = time.elapsed_secs_f64();
    let index = (now / period).floor();
    if index == ((now - time.delta_secs_f64()) / period).floor() {
        return;
    }
    let x = -6.0 + 1.5 * (index as f32 % 9.0);
    let z = -2.0 + (index as f32 * 1.7).sin() * 2.0;
    for mut effect in &mut impacts {
        effect.set_param("wind", 4.0);
        effect.burst(PlumeBurst::new(400).at(Vec3::new(x, 0.0, z)));
    }
}
