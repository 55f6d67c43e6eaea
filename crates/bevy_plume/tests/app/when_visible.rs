//! `PlumeSimulate::WhenVisible`: an effect out of every camera's view (its declared bounds
//! culled) takes no steps, while a copy that always simulates goes on; brought into view, it
//! takes up where it stopped, one step a frame again.

use crate::common::{asset_dir, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{read_totals, PlumeEffect, PlumeSimulate, SimulationSpace};

/// 100 dots that never die and barely move, in a declared 1 m box, so Bevy culls the effect
/// by its bounds from the first frame.
const BOXED: &str = r#"Effect(name: "boxed", capacity: 100,
    emitters: [Emitter(burst: 100, shape: Point((0.0, 0.0, 0.0)), velocity: Radial(speed: (0.0, 0.1)))],
    forces: [Drag(k: 4.0)],
    bounds: Some((min: (-0.5, -0.5, -0.5), max: (0.5, 0.5, 0.5))),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.15)], blend: Additive),
)"#;

fn steps(h: &Harness, entity: Entity) -> u64 {
    read_totals(h.app.sub_app(RenderApp).world(), entity, 0)
        .expect("the instance runs")
        .expect("read back")
        .steps
}

#[test]
fn an_unseen_effect_that_simulates_when_visible_waits_and_takes_up_where_it_stopped() {
    let _one = serial();
    let dir = asset_dir("when_visible");
    std::fs::write(dir.join("boxed.plume.ron"), BOXED).unwrap();
    let mut h = Harness::new(&dir);
    h.camera();
    h.wait_for_pipelines();
    let handle = h.load("boxed.plume.ron");
    // 30 m to the side: out of the camera's view (10 m away, 45° high, 16:9).
    let aside = Transform::from_xyz(30.0, 0.0, 0.0);
    let spawn = |h: &mut Harness, simulate| {
        h.app
            .world_mut()
            .spawn((
                PlumeEffect::new(handle.clone())
                    .with_space(SimulationSpace::Local)
                    .with_simulate(simulate),
                aside,
            ))
            .id()
    };
    let always = spawn(&mut h, PlumeSimulate::Always);
    let when_visible = spawn(&mut h, PlumeSimulate::WhenVisible);
    h.update(20);
    let (a, w) = (steps(&h, always), steps(&h, when_visible));
    assert!(
        a >= 19,
        "the one that always simulates took {a} steps in 20 frames"
    );
    assert_eq!(w, 0, "unseen, it took {w} steps");
    // Into view: it runs a step a frame from where it stopped.
    h.app
        .world_mut()
        .entity_mut(when_visible)
        .insert(Transform::IDENTITY);
    h.update(10);
    let w = steps(&h, when_visible);
    assert!(
        (8..=10).contains(&w),
        "in view for 10 frames it took {w} steps (a frame or two to be seen)"
    );
}
