//! `PlumeDiagnosticsPlugin`: the render world's counts reach Bevy's `DiagnosticsStore`.

use crate::common::{asset_dir, dots, serial, Harness};
use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy_plume::{
    PlumeDiagnosticsPlugin, PlumeEffect, PlumeGpuTime, PlumeParticleCounts, BATCH_FROM,
};

#[test]
fn the_plugins_counts_are_bevy_diagnostics() {
    let _one = serial();
    let dir = asset_dir("diagnostics");
    std::fs::write(
        dir.join("dots.plume.ron"),
        dots(500, 100.0, (1.0, 0.5, 0.2)),
    )
    .unwrap();
    let mut h = Harness::with_app(&dir, |app| {
        app.add_plugins(PlumeDiagnosticsPlugin);
    });
    let dots = h.load("dots.plume.ron");
    h.camera();
    h.wait_for_pipelines();
    let entities: Vec<Entity> = (0..3)
        .map(|_| {
            h.app
                .world_mut()
                .spawn((PlumeEffect::new(dots.clone()), Transform::IDENTITY))
                .id()
        })
        .collect();
    // Built once the file has compiled (on Bevy's task pool, shared with the other tests),
    // then frames for the counts to come back.
    let built = h.update_until(2_000, std::time::Duration::from_millis(5), |h| {
        render_stats(h).instances == 3
    });
    assert!(built, "{:?}", render_stats(&h));
    h.update(10);
    let store = h.app.world().resource::<DiagnosticsStore>();
    let value = |path: bevy::diagnostic::DiagnosticPath| {
        store
            .get(&path)
            .and_then(|d| d.value())
            .unwrap_or_else(|| panic!("no measurement of {path:?}"))
    };
    assert_eq!(value(PlumeDiagnosticsPlugin::INSTANCES), 3.0);
    assert_eq!(value(PlumeDiagnosticsPlugin::BATCHES), 0.0);
    // One camera sees each of the three.
    assert_eq!(value(PlumeDiagnosticsPlugin::DRAWS), 3.0);
    assert_eq!(value(PlumeDiagnosticsPlugin::COMPUTE_DRAWS), 0.0);
    let mib = value(PlumeDiagnosticsPlugin::PARTICLE_MIB);
    let stats = render_stats(&h);
    assert!(
        mib > 0.0 && (mib - stats.particle_bytes as f64 / 1048576.0).abs() < 1e-9,
        "{mib} MiB against {stats:?}"
    );
    // Each effect's 500 dots, read back from the GPU a frame or two after their burst.
    assert_eq!(value(PlumeDiagnosticsPlugin::LIVE_PARTICLES), 1500.0);
    for entity in entities {
        let counts = h
            .app
            .world()
            .get::<PlumeParticleCounts>(entity)
            .expect("each effect entity has its counts");
        assert_eq!((counts.alive, counts.spawned, counts.died), (500, 500, 0));
        assert!(counts.steps >= 1);
    }
    // The steps' GPU time, where the device has timestamp queries (lavapipe has).
    let timed = store
        .get(&PlumeDiagnosticsPlugin::STEP_GPU_MS)
        .and_then(|d| d.value());
    match h.has_timestamps() {
        true => assert!(timed.is_some_and(|ms| ms > 0.0 && ms < 1000.0), "{timed:?}"),
        false => assert_eq!(timed, None),
    }
}

/// The render world's counts of the last frame.
fn render_stats(h: &Harness) -> bevy_plume::PlumeRenderStats {
    *h.app
        .sub_app(bevy::render::RenderApp)
        .world()
        .resource::<bevy_plume::PlumeRenderStats>()
}

/// A stateful burst of `count` dots that live long, so that every frame steps them all.
fn stateful_dots(count: u32) -> String {
    dots(count, 100.0, (0.3, 0.6, 1.0)).replacen("seed: 7,", "seed: 7, state: Stateful,", 1)
}

#[test]
fn a_timed_effect_has_its_own_steps_and_draw_gpu_times() {
    let _one = serial();
    let dir = asset_dir("gpu_time");
    std::fs::write(dir.join("many.plume.ron"), stateful_dots(20_000)).unwrap();
    std::fs::write(dir.join("few.plume.ron"), stateful_dots(16)).unwrap();
    let mut h = Harness::with_app(&dir, |app| {
        app.add_plugins(PlumeDiagnosticsPlugin);
    });
    let many = h.load("many.plume.ron");
    let few_file = h.load("few.plume.ron");
    h.camera();
    h.wait_for_pipelines();
    let timed = |h: &mut Harness, handle: &Handle<bevy_plume::PlumeEffectAsset>| {
        h.app
            .world_mut()
            .spawn((
                PlumeEffect::new(handle.clone()),
                PlumeGpuTime::default(),
                Transform::IDENTITY,
            ))
            .id()
    };
    let many = timed(&mut h, &many);
    // Enough copies of the small one to be batched, were they not timed.
    let few: Vec<Entity> = (0..BATCH_FROM + 1)
        .map(|_| timed(&mut h, &few_file))
        .collect();
    let untimed = h
        .app
        .world_mut()
        .spawn((PlumeEffect::new(few_file), Transform::IDENTITY))
        .id();
    // Built once their files have compiled (on Bevy's task pool), then a few frames
    // for the readings to come back.
    let built = h.update_until(2_000, std::time::Duration::from_millis(5), |h| {
        render_stats(h).instances == BATCH_FROM + 3
    });
    assert!(built, "{:?}", render_stats(&h));
    h.update(8);
    let stats = render_stats(&h);
    // Timed effects run alone, so the time is each one's own; the untimed copy joins no batch
    // either (the timed ones do not count towards a batch).
    assert_eq!((stats.instances, stats.batches), (BATCH_FROM + 3, 0));
    let world = h.app.world();
    assert!(world.get::<PlumeGpuTime>(untimed).is_none());
    let time = |entity| *world.get::<PlumeGpuTime>(entity).expect("still timed");
    if !h.has_timestamps() {
        assert_eq!(time(many), PlumeGpuTime::default());
        return;
    }
    // lavapipe has timestamp queries, inside passes too: every timed entity has a time for
    // its steps and one for its draw by the camera. (Which is larger is not asserted:
    // lavapipe runs the GPU's work on the CPU's two cores beside Bevy's threads, and a
    // 16-particle step was seen to take 3 ms there.)
    for &entity in std::iter::once(&many).chain(&few) {
        let PlumeGpuTime { steps_ms, draw_ms } = time(entity);
        for ms in [steps_ms, draw_ms] {
            let ms = ms.expect("a time for each timed effect's steps and draw");
            assert!((0.0..1000.0).contains(&ms), "{ms} ms");
        }
    }
}
