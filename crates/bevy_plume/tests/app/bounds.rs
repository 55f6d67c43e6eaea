//! Bounds measured on the GPU for an effect whose file declares none: the live particles' box,
//! read back without waiting, becomes the entity's `Aabb` (in its own space, with the sprites'
//! reach), so Bevy culls the effect when all its particles are out of view and draws it when
//! they are in view. Headless on lavapipe.

use crate::common::{dots, serial, Harness};
use bevy::camera::primitives::Aabb;
use bevy::camera::visibility::NoFrustumCulling;
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{read_particles, PlumeEffect, PlumeRenderStats};

fn stats(h: &Harness) -> PlumeRenderStats {
    *h.app
        .sub_app(RenderApp)
        .world()
        .resource::<PlumeRenderStats>()
}

/// Runs frames until `entity` has an `Aabb` (at most 30); returns it.
fn measured_aabb(h: &mut Harness, entity: Entity) -> Aabb {
    for _ in 0..30 {
        h.update(1);
        if let Some(aabb) = h.app.world().get::<Aabb>(entity) {
            return *aabb;
        }
    }
    panic!("no Aabb measured within 30 frames");
}

#[test]
fn measured_bounds_hold_the_particles_and_cull_an_effect_out_of_view() {
    let _one = serial();
    // No `bounds:` in the file: 300 dots, 0.15 m across, spread at most 0.13 m.
    let (mut h, handle) =
        Harness::with_effect("measured_bounds", &dots(300, 100.0, (1.0, 1.0, 1.0)));
    // 30 m to the side: out of the camera's view (10 m away, 45° high, 16:9).
    let aside = Vec3::new(30.0, 0.0, 0.0);
    let entity = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle.clone()),
            Transform::from_translation(aside),
        ))
        .id();
    // Its world-space variant compiles off the render thread: it runs from a frame or so on.
    h.wait_for_effects();
    assert_eq!(stats(&h).draws, 1, "before any reading the effect is drawn");
    let aabb = measured_aabb(&mut h, entity);
    let dots = read_particles(h.app.sub_app(RenderApp).world(), entity, 0)
        .expect("the instance runs")
        .expect("read back");
    assert_eq!(dots.len(), 300);
    // In the entity's space (the world-space dots minus the entity's place), every dot lies in
    // the box, and the box is no bigger than the dots' spread, their size and the margin.
    let (lo, hi) = (aabb.min(), aabb.max());
    for d in &dots {
        let p = Vec3::new(
            d.position.x as f32,
            d.position.y as f32,
            d.position.z as f32,
        ) - aside;
        let inside = p.cmpge(Vec3::from(lo)).all() && p.cmple(Vec3::from(hi)).all();
        assert!(
            inside,
            "a dot at {p} (entity space) outside the measured box {lo:?}..{hi:?}"
        );
    }
    assert!(
        Vec3::from(aabb.half_extents).max_element() < 0.5,
        "the box is loose: {:?}",
        aabb.half_extents
    );
    // Out of view by its measured box: culled (it keeps running).
    h.update(2);
    assert_eq!(stats(&h).draws, 0, "out of view: culled");
    h.app
        .world_mut()
        .entity_mut(entity)
        .insert(NoFrustumCulling);
    h.update(1);
    assert_eq!(stats(&h).draws, 1, "without culling: drawn");
    // The same effect in view is drawn with its measured box.
    h.app.world_mut().despawn(entity);
    let in_view = h.app.world_mut().spawn(PlumeEffect::new(handle)).id();
    measured_aabb(&mut h, in_view);
    h.update(2);
    assert_eq!(stats(&h).draws, 1, "in view: drawn");
}
