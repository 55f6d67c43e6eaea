//! Variants (a seed of an entity's own) compile off the render thread: the entity does not run
//! in the frame it is spawned, and once its variant is ready it has caught up the time it
//! waited, step for step with a copy spawned in the same frame that needed no variant.

use crate::common::{dots, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{read_totals, PlumeEffect, SimulationSpace};

fn steps(h: &Harness, entity: Entity) -> Option<u64> {
    read_totals(h.app.sub_app(RenderApp).world(), entity, 0).map(|t| t.expect("read back").steps)
}

#[test]
fn a_seeded_copy_starts_late_but_runs_in_step_with_the_file_as_written() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("variants", &dots(50, 100.0, (1.0, 1.0, 1.0)));
    h.camera();
    h.wait_for_pipelines();
    let as_written = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle.clone()).with_space(SimulationSpace::Local),
            Transform::IDENTITY,
        ))
        .id();
    let seeded = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle)
                .with_space(SimulationSpace::Local)
                .with_seed(99),
            Transform::IDENTITY,
        ))
        .id();
    h.update(1);
    assert!(
        steps(&h, as_written).is_some(),
        "the file as written runs at once"
    );
    assert_eq!(
        steps(&h, seeded),
        None,
        "the seeded copy waits for its variant"
    );
    h.update(20);
    let (a, b) = (steps(&h, as_written).unwrap(), steps(&h, seeded));
    assert!(a >= 20, "{a} steps in 21 frames of 1/60 s");
    assert_eq!(b, Some(a), "the seeded copy caught up");
}
