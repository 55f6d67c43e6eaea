//! `PlumeDiagnosticsPlugin`: the render world's counts reach Bevy's `DiagnosticsStore`.

mod common;

use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy_plume::{PlumeDiagnosticsPlugin, PlumeEffect, PlumeParticleCounts};
use common::{asset_dir, dots, Harness};

#[test]
fn the_plugins_counts_are_bevy_diagnostics() {
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
    let stats = *h
        .app
        .sub_app(bevy::render::RenderApp)
        .world()
        .resource::<bevy_plume::PlumeRenderStats>();
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
    let device = h
        .app
        .sub_app(bevy::render::RenderApp)
        .world()
        .resource::<bevy::render::renderer::RenderDevice>()
        .features();
    let timed = store
        .get(&PlumeDiagnosticsPlugin::STEP_GPU_MS)
        .and_then(|d| d.value());
    match device.contains(bevy::render::render_resource::WgpuFeatures::TIMESTAMP_QUERY) {
        true => assert!(timed.is_some_and(|ms| ms > 0.0 && ms < 1000.0), "{timed:?}"),
        false => assert_eq!(timed, None),
    }
}
