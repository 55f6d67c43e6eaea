//! bevy_hanabi's `2d` example with bevy_plume: `effects/hanabi/2d.ron`, a widening ring of pale
//! blue dots in the plane z = 0, seen by a `Camera2d` whose orthographic view is 1 m tall.
//! (hanabi's white square moving through z = 0 is a `Mesh2d`, which needs Bevy's sprite
//! renderer, a feature this crate leaves out; tests/app/two_d.rs checks the sorting by z.)
//!
//! In a window: `cargo +nightly run --ignore-rust-version --example two_d`.
//! Headless: `... --example two_d -- --headless two_d.png --frames 180`.

use bevy::camera::ScalingMode;
use bevy::prelude::*;
use bevy_plume::headless::{default_plugins, Headless, HeadlessPlugin};
use bevy_plume::{PlumeEffect, PlumePlugin};

/// The repository's ports of hanabi's examples.
const EFFECTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../effects/hanabi");

fn main() -> AppExit {
    let headless = match Headless::from_args() {
        Ok(h) => h,
        Err(message) => {
            eprintln!(
                "error: {message}\nusage: two_d [--headless OUT.png [--frames N] [--size WxH]]"
            );
            return AppExit::from_code(2);
        }
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(headless.as_ref(), EFFECTS))
        .add_plugins(PlumePlugin)
        .insert_resource(ClearColor(Color::BLACK))
        .add_systems(Startup, setup);
    if let Some(headless) = headless {
        app.add_plugins(HeadlessPlugin(headless));
    }
    app.run()
}

fn setup(mut commands: Commands, assets: Res<AssetServer>) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scaling_mode: ScalingMode::FixedVertical {
                viewport_height: 1.0,
            },
            ..OrthographicProjection::default_2d()
        }),
    ));
    commands.spawn(PlumeEffect::new(assets.load("2d.ron")));
}
