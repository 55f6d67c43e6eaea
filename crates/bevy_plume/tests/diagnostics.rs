//! `PlumeDiagnosticsPlugin`: the render world's counts reach Bevy's `DiagnosticsStore`.

mod common;

use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy_plume::{PlumeDiagnosticsPlugin, PlumeEffect};
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
    for _ in 0..3 {
        h.app
            .world_mut()
            .spawn((PlumeEffect::new(dots.clone()), Transform::IDENTITY));
    }
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
}
