//! Ribbons joining particles (`render.ribbon`) in Bevy's view, headless on lavapipe: a stream
//! whose spawn point runs along x is drawn as one strip along its path, by the raster
//! renderer even where the compute one is asked for (it draws no ribbons: the effect falls
//! back, as `Auto` picks the raster one for it). `BEVY_PLUME_TEST_IMAGES=DIR` keeps the image.

use crate::common::{asset_dir, project, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeRenderStats};

/// 60 particles a second spawned at x = -3 + 4 t on a slight wave, living 3 s, joined into one
/// ribbon 0.3 m wide.
const STREAM: &str = r#"Effect(
    name: "stream",
    capacity: 256,
    emitters: [Emitter(rate: 60.0, shape: Custom("vec3(-3.0 + 4.0 * t, 0.3 * sin(6.0 * t), 0.0)"),
                       velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((3.0, 3.0)))],
    render: Render(color: [(0.0, (1.0, 0.9, 0.5, 1.0))], size: [(0.0, 0.3)], background: (0.0, 0.0, 0.0),
                   ribbon: Some(Ribbon(points: 256))),
)"#;

#[test]
fn a_ribbon_is_drawn_along_the_path_its_particles_were_spawned_on() {
    let _one = serial();
    let dir = asset_dir("ribbons");
    std::fs::write(dir.join("stream.plume.ron"), STREAM).unwrap();
    let mut h = Harness::new(&dir);
    h.camera();
    h.wait_for_pipelines();
    let stream = h.load("stream.plume.ron");
    h.app.world_mut().spawn((
        PlumeEffect::new(stream).with_draw(PlumeDraw::Compute),
        Transform::IDENTITY,
    ));
    // 60 frames of 1/60 s: the ribbon runs from x = -3 to about x = 1.
    h.update(60);
    let image = h.capture_running();
    if let Ok(out) = std::env::var("BEVY_PLUME_TEST_IMAGES") {
        image
            .save(std::path::Path::new(&out).join("ribbon.png"))
            .unwrap();
    }
    let lit: Vec<(u32, u32)> = image
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[0] > 60)
        .map(|(x, y, _)| (x, y))
        .collect();
    let xs = lit.iter().map(|p| p.0);
    let (left, right) = (xs.clone().min().unwrap_or(0), xs.max().unwrap_or(0));
    let (want_left, centre_y) = project(-3.0, 0.0);
    let (want_right, _) = project(0.8, 0.0);
    assert!(lit.len() > 60, "only {} pixels lit", lit.len());
    assert!(
        (left as f32 - want_left).abs() < 4.0 && right as f32 > want_right,
        "the strip spans x {left}..{right} px, the path from {want_left} to past {want_right}"
    );
    // A strip, not a cloud: every lit pixel within the wave and the half width of its line.
    let reach = project(0.0, 0.3 + 0.15).1 - centre_y;
    for (x, y) in &lit {
        assert!(
            (*y as f32 + 0.5 - centre_y).abs() <= reach.abs() + 1.5,
            "pixel ({x}, {y}) off the strip (centre {centre_y}, reach {reach})"
        );
    }
    let stats = *h
        .app
        .sub_app(RenderApp)
        .world()
        .resource::<PlumeRenderStats>();
    assert_eq!(stats.compute_draws, 0, "the raster renderer draws ribbons");
}
