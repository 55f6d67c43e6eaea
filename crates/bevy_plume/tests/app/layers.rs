//! `RenderLayers`, headless on lavapipe: a camera draws the effects on its layers and no other,
//! in 3D and in 2D, as Bevy's visibility decides for its own meshes and sprites.

use crate::common::{dots, lit_pixels, serial, Harness};
use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;
use bevy_plume::{PlumeEffect, SimulationSpace};

/// The lit pixels of a frame where the camera sees layer 1 and a red effect sits on
/// `layer` (None: no `RenderLayers`, which is layer 0), in 2D when `two_d`.
fn lit_with(name: &str, layer: Option<usize>, two_d: bool) -> u32 {
    // In 2D a world unit is a pixel: dots 8 units across.
    let text = match two_d {
        true => dots(200, 100.0, (1.0, 0.1, 0.1)).replace("0.15", "8.0"),
        false => dots(200, 100.0, (1.0, 0.1, 0.1)),
    };
    let (mut h, dots) = Harness::with_effect(name, &text);
    if two_d {
        h.use_2d();
    }
    let camera = match two_d {
        true => h
            .app
            .world_mut()
            .query_filtered::<Entity, With<Camera2d>>()
            .single(h.app.world())
            .unwrap(),
        false => h.camera(),
    };
    h.app
        .world_mut()
        .entity_mut(camera)
        .insert(RenderLayers::layer(1));
    h.wait_for_pipelines();
    // In 3D, spread ten times wider (local space) to cover a few dozen pixels 10 m away.
    let scale = if two_d { 1.0 } else { 10.0 };
    let mut effect = h.app.world_mut().spawn((
        PlumeEffect::new(dots).with_space(SimulationSpace::Local),
        Transform::from_scale(Vec3::splat(scale)),
    ));
    if let Some(layer) = layer {
        effect.insert(RenderLayers::layer(layer));
    }
    h.update(5);
    lit_pixels(&h.capture(), 40).0
}

#[test]
fn a_camera_draws_the_effects_on_its_render_layers_alone() {
    let _one = serial();
    for two_d in [false, true] {
        let on = lit_with(&format!("layers-on-{two_d}"), Some(1), two_d);
        assert!(
            on > 20,
            "2D {two_d}: an effect on the camera's layer lit {on} pixels"
        );
        for (what, layer) in [("layer 2", Some(2)), ("no RenderLayers (layer 0)", None)] {
            let off = lit_with(&format!("layers-off-{two_d}-{layer:?}"), layer, two_d);
            assert_eq!(off, 0, "2D {two_d}: an effect on {what} drew {off} pixels");
        }
    }
}
