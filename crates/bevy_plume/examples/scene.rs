//! A small 3D scene with Plume effects: fireworks (a graph of groups and events), smoke
//! (textured, sorted, soft, lit by the scene's sun and shadowed by a wall) and sparks riding a
//! moving block, under an orbiting camera.
//!
//! In a window: `cargo +nightly run --ignore-rust-version --example scene`.
//! Headless: `... --example scene -- --headless scene.png --frames 120`.
//! The effect files are the repository's `effects/` (edit one while it runs: it reloads).

use bevy::camera::Hdr;
use bevy::core_pipeline::prepass::DepthPrepass;
use bevy::post_process::bloom::Bloom;
use bevy::prelude::*;
use bevy_plume::headless::{default_plugins, Headless, HeadlessPlugin};
use bevy_plume::{PlumeEffect, PlumePlugin};

/// The repository's effect files, as the asset folder.
const EFFECTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../effects");

fn main() -> AppExit {
    let headless = match Headless::from_args() {
        Ok(h) => h,
        Err(message) => {
            eprintln!(
                "error: {message}\nusage: scene [--headless OUT.png [--frames N] [--size WxH]]"
            );
            return AppExit::from_code(2);
        }
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(headless.as_ref(), EFFECTS))
        .add_plugins(PlumePlugin)
        .add_systems(Startup, setup)
        .add_systems(Update, (orbit_camera, move_cart, relight_sparks));
    if let Some(headless) = headless {
        app.add_plugins(HeadlessPlugin(headless));
    }
    app.run()
}

/// Marks the block the sparks ride on.
#[derive(Component)]
struct Cart;

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(40.0, 40.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.22, 0.24, 0.22))),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 6_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(10.0, 8.0, -2.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    // A wall between the sun and the smoke: the plume rises out of its shadow.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.4, 4.5, 4.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.5, 0.47, 0.42))),
        Transform::from_xyz(-3.5, 2.25, 0.0),
    ));
    // The depth prepass, single-sampled, lets soft particles (the smoke) fade where they meet
    // the ground instead of cutting into it.
    commands.spawn((
        Camera3d::default(),
        Hdr,
        Bloom::NATURAL,
        Msaa::Off,
        DepthPrepass,
        Transform::from_xyz(0.0, 5.0, 20.0).looking_at(Vec3::new(0.0, 4.0, 0.0), Vec3::Y),
    ));
    // Fireworks far back, smoke on the left.
    commands.spawn((
        PlumeEffect::new(assets.load("fireworks.ron")),
        Transform::from_xyz(2.0, 0.0, -6.0),
    ));
    commands.spawn((
        PlumeEffect::new(assets.load("lit_smoke.ron")).with_warm_up(3.0),
        Transform::from_xyz(-6.0, 0.0, 0.0).with_scale(Vec3::splat(0.6)),
    ));
    // Sparks on a block that drives back and forth: local space, they ride with it.
    commands
        .spawn((
            Cart,
            Mesh3d(meshes.add(Cuboid::new(1.0, 0.6, 1.0))),
            MeshMaterial3d(materials.add(Color::srgb(0.7, 0.45, 0.2))),
            Transform::from_xyz(4.0, 0.3, 3.0),
        ))
        .with_child((
            Sparks,
            PlumeEffect::new(assets.load("sparks.ron")),
            Transform::from_xyz(0.0, 0.3, 0.0),
        ));
}

/// Marks the sparks, which game code bursts again every two seconds.
#[derive(Component)]
struct Sparks;

/// Restarts the sparks' one burst every two seconds (control from game code).
fn relight_sparks(time: Res<Time>, mut sparks: Query<&mut PlumeEffect, With<Sparks>>) {
    let period = 2.0;
    let now = time.elapsed_secs_f64();
    if (now / period).floor() != ((now - time.delta_secs_f64()) / period).floor() {
        for mut effect in &mut sparks {
            effect.restart();
        }
    }
}

/// Circles the camera slowly round the scene.
fn orbit_camera(time: Res<Time>, mut camera: Query<&mut Transform, With<Camera3d>>) {
    let angle = time.elapsed_secs() * 0.15;
    for mut transform in &mut camera {
        let eye = Vec3::new(20.0 * angle.sin(), 5.0, 20.0 * angle.cos());
        *transform = Transform::from_translation(eye).looking_at(Vec3::new(0.0, 4.0, 0.0), Vec3::Y);
    }
}

/// Drives the cart back and forth.
fn move_cart(time: Res<Time>, mut cart: Query<&mut Transform, With<Cart>>) {
    for mut transform in &mut cart {
        transform.translation.x = 4.0 + 2.5 * (time.elapsed_secs() * 0.8).sin();
    }
}
