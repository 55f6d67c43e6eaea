//! Only what the scene requires: a level of detail (`PlumeLod`) thins an effect by its size
//! on screen, and a particle budget (`PlumeBudget`) thins the least visible effects first; the
//! GPU spawns what each entity's `PlumeThinning` says.

use crate::common::{serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{
    read_totals, PlumeBudget, PlumeDiagnosticsPlugin, PlumeEffect, PlumeLod, PlumeThinning,
    SimulationSpace,
};

/// 300 particles a second living 1 s (300 alive unthinned), barely moving, in a declared 1 m
/// box, so Bevy sees (or culls) the effect by its bounds from the first frame.
const MIST: &str = r#"Effect(name: "mist", capacity: 400,
    emitters: [Emitter(rate: 300.0, lifetime: Some((1.0, 1.0)), shape: Point((0.0, 0.0, 0.0)),
        velocity: Radial(speed: (0.0, 0.1)))],
    forces: [Drag(k: 4.0)],
    bounds: Some((min: (-0.5, -0.5, -0.5), max: (0.5, 0.5, 0.5))),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.1)], blend: Additive),
)"#;

fn spawn(h: &mut Harness, effect: PlumeEffect, at: Vec3, extra: impl Bundle) -> Entity {
    h.app
        .world_mut()
        .spawn((effect, Transform::from_translation(at), extra))
        .id()
}

fn thinning(h: &mut Harness, entity: Entity) -> PlumeThinning {
    *h.app
        .world()
        .get::<PlumeThinning>(entity)
        .expect("every effect has one")
}

fn totals(h: &Harness, entity: Entity) -> bevy_plume::plume_compiler::reference::Totals {
    read_totals(h.app.sub_app(RenderApp).world(), entity, 0)
        .expect("the instance runs")
        .expect("read back")
}

#[test]
fn a_level_of_detail_spawns_fewer_the_fewer_pixels_an_effect_covers() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("thinning_lod", MIST);
    h.wait_for_pipelines();
    // 1 m across 10 m from the camera is about 19 of the image's 90 pixels high; 50 m away,
    // about 4.
    // In their own space, as written: stateless, so the closed form thins too.
    let lod = PlumeLod::new(18.0, 0.05);
    let mist = PlumeEffect::new(handle).with_space(SimulationSpace::Local);
    let near = spawn(&mut h, mist.clone(), Vec3::ZERO, lod);
    let far = spawn(&mut h, mist.clone(), Vec3::new(0.0, 0.0, -40.0), lod);
    let plain = spawn(&mut h, mist, Vec3::new(0.0, 0.0, -40.0), ());
    h.wait_for_effects();
    h.update(90);
    let (n, f, p) = (
        thinning(&mut h, near),
        thinning(&mut h, far),
        thinning(&mut h, plain),
    );
    assert_eq!(n.scale, 1.0, "near: {n:?}");
    assert_eq!(p.scale, 1.0, "no level of detail: {p:?}");
    assert_eq!(n.expected_alive, 300);
    assert!(
        (3.0..5.0).contains(&f.pixels) && (f.scale - f.pixels / 18.0).abs() < 1e-6,
        "far: {f:?}"
    );
    // What the GPU spawned over the last second follows the scale.
    let (near_alive, far_alive) = (totals(&h, near).alive, totals(&h, far).alive);
    let wanted = f64::from(f.scale) * near_alive as f64;
    assert!(
        (far_alive as f64 - wanted).abs() <= 2.0 + 0.05 * wanted,
        "far keeps {far_alive} alive, {wanted:.0} wanted (near {near_alive})"
    );
    // Out of every camera's view it keeps its least.
    h.app
        .world_mut()
        .entity_mut(far)
        .insert(Transform::from_xyz(40.0, 0.0, 0.0));
    h.update(3);
    let f = thinning(&mut h, far);
    assert_eq!((f.pixels, f.scale), (0.0, 0.05), "unseen: {f:?}");
}

#[test]
fn a_budget_thins_the_unseen_effects_first_then_the_smallest() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("thinning_budget", MIST);
    h.wait_for_pipelines();
    // 450 of the 3,000 that ten effects keep alive: the eight out of view spawn nothing, the
    // far one in view half, the near one all.
    h.app
        .world_mut()
        .insert_resource(PlumeBudget::live_particles(450));
    // In the world (the default): stateful, and ten of one file run as a batch.
    let mist = PlumeEffect::new(handle);
    let near = spawn(&mut h, mist.clone(), Vec3::ZERO, ());
    let far = spawn(&mut h, mist.clone(), Vec3::new(0.0, 0.0, -10.0), ());
    let unseen: Vec<Entity> = (0..8)
        .map(|i| {
            let side = if i % 2 == 0 { 30.0 } else { -30.0 };
            spawn(&mut h, mist.clone(), Vec3::new(side, i as f32, 0.0), ())
        })
        .collect();
    h.wait_for_effects();
    h.update(90);
    assert_eq!(thinning(&mut h, near).scale, 1.0);
    let f = thinning(&mut h, far);
    assert!((f.scale - 0.5).abs() < 1e-6, "far: {f:?}");
    for &e in &unseen {
        assert_eq!(thinning(&mut h, e).scale, 0.0);
    }
    // On the GPU: after a lifetime at these scales, 300 and 150 alive, the unseen none.
    let alive: Vec<u64> = std::iter::once(near)
        .chain([far])
        .chain(unseen.iter().copied())
        .map(|e| totals(&h, e).alive)
        .collect();
    let sum: u64 = alive.iter().sum();
    assert!(
        (440..=452).contains(&sum) && alive[2..].iter().all(|&a| a == 0),
        "alive per effect: {alive:?}"
    );
    // The stats say the ten ran as a batch: thinning reaches batched entities too.
    let stats = h
        .app
        .sub_app(RenderApp)
        .world()
        .resource::<bevy_plume::PlumeRenderStats>();
    assert!(stats.batches >= 1, "{stats:?}");
    // Budget lifted: everything spawns again.
    h.app.world_mut().remove_resource::<PlumeBudget>();
    h.update(2);
    assert!(unseen.iter().all(|&e| thinning(&mut h, e).scale == 1.0));
}

#[test]
fn a_budget_of_gpu_time_pauses_the_steps_of_unseen_effects() {
    let _one = serial();
    let dir = crate::common::asset_dir("thinning_gpu_budget");
    // Stateful, so that every step runs a kernel over its slots.
    let mist = MIST.replacen("capacity: 400,", "capacity: 400, state: Stateful,", 1);
    std::fs::write(dir.join("mist.plume.ron"), mist).unwrap();
    let mut h = Harness::with_app(&dir, |app| {
        app.add_plugins(PlumeDiagnosticsPlugin);
    });
    let handle = h.load("mist.plume.ron");
    h.wait_for_pipelines();
    let mist = PlumeEffect::new(handle);
    let seen = spawn(&mut h, mist.clone(), Vec3::ZERO, ());
    // Behind the camera (at z = 10, looking at the origin): culled by their bounds.
    let unseen: Vec<Entity> = (0..4)
        .map(|i| {
            spawn(
                &mut h,
                mist.clone(),
                Vec3::new(2.0 * i as f32, 0.0, 30.0),
                (),
            )
        })
        .collect();
    h.wait_for_effects();
    let steps = |h: &Harness, e: Entity| totals(h, e).steps;
    let timed = h.has_timestamps();
    // A budget no step fits: every unseen effect stops stepping, the one in view goes on.
    h.app.insert_resource(PlumeBudget::step_gpu_ms(1e-6));
    h.update(10);
    let before: Vec<u64> = unseen.iter().map(|&e| steps(&h, e)).collect();
    let seen_before = steps(&h, seen);
    h.update(20);
    assert!(!thinning(&mut h, seen).paused);
    assert!(
        steps(&h, seen) >= seen_before + 19,
        "the effect in view steps on"
    );
    for (&e, &was) in unseen.iter().zip(&before) {
        match timed {
            // lavapipe has timestamp queries.
            true => {
                assert!(thinning(&mut h, e).paused, "{e}: {:?}", thinning(&mut h, e));
                assert_eq!(steps(&h, e), was, "{e} stands still while paused");
            }
            false => assert!(!thinning(&mut h, e).paused, "no measurement, no pause"),
        }
    }
    // A budget they all fit: they step again.
    h.app.insert_resource(PlumeBudget::step_gpu_ms(1000.0));
    h.update(5);
    let resumed: Vec<u64> = unseen.iter().map(|&e| steps(&h, e)).collect();
    h.update(10);
    for (&e, &was) in unseen.iter().zip(&resumed) {
        assert!(!thinning(&mut h, e).paused);
        assert!(steps(&h, e) >= was + 9, "{e} steps again");
    }
}
