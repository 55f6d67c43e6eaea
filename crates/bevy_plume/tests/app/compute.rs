//! The compute renderer in Bevy's view (`PlumeDraw::Compute`), headless on lavapipe: it draws
//! what the raster renderer draws, with and without MSAA, and the scene Bevy draws hides the
//! particles behind it (the compute renderer tests each pixel against the camera's depth after the
//! opaque pass). `BEVY_PLUME_TEST_IMAGES=DIR` keeps the images.

use crate::common::{asset_dir, dots, lit_pixels, project, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeRenderStats};

/// Dots 0.6 m across (about 6 pixels here), so that edges and blending show.
fn big_dots(rgb: (f64, f64, f64)) -> String {
    dots(300, 100.0, rgb).replace("0.15", "0.6")
}

/// An app with `msaa` on its camera and (with `wall`) an opaque black wall Bevy draws,
/// covering x < 0 at z = 2 (between the camera at z = 10 and the origin), its pipelines
/// ready; and two dot effects drawn by `draw`, red at (-2, 1, 0) behind the wall and green at
/// (2, 1, 0) in the open. Returns the image of the frame after the dots have settled.
fn wall_and_dots(draw: PlumeDraw, msaa: Msaa, wall: bool) -> image::RgbaImage {
    let dir = asset_dir("compute");
    std::fs::write(dir.join("red.plume.ron"), big_dots((1.0, 0.2, 0.1))).unwrap();
    std::fs::write(dir.join("green.plume.ron"), big_dots((0.1, 1.0, 0.2))).unwrap();
    let mut h = Harness::new(&dir);
    let camera = h.camera();
    h.app.world_mut().entity_mut(camera).insert(msaa);
    if wall {
        h.spawn_wall(10.0, Color::BLACK, Vec3::new(-5.0, 0.0, 2.0));
    }
    h.wait_for_pipelines();
    let red = h.load("red.plume.ron");
    let green = h.load("green.plume.ron");
    for (handle, x) in [(red, -2.0), (green, 2.0)] {
        h.app.world_mut().spawn((
            PlumeEffect::new(handle).with_draw(draw),
            Transform::from_xyz(x, 1.0, 0.0),
        ));
    }
    h.update(10);
    let image = h.capture_running();
    let stats = *h
        .app
        .sub_app(RenderApp)
        .world()
        .resource::<PlumeRenderStats>();
    let want = if draw == PlumeDraw::Compute { 2 } else { 0 };
    assert_eq!(
        stats.compute_draws, want,
        "{draw:?}: draws by the compute renderer"
    );
    if let Ok(dir) = std::env::var("BEVY_PLUME_TEST_IMAGES") {
        let path = std::path::Path::new(&dir).join(format!("compute-{draw:?}-{msaa:?}-{wall}.png"));
        image.save(path).expect("the image saved");
    }
    image
}

#[test]
fn the_compute_renderer_draws_what_the_raster_one_draws_and_the_scene_hides() {
    let _one = serial();
    for msaa in [Msaa::Off, Msaa::Sample4] {
        let raster = wall_and_dots(PlumeDraw::Raster, msaa, true);
        let compute = wall_and_dots(PlumeDraw::Compute, msaa, true);
        // Without the wall, the red dots show.
        let open = wall_and_dots(PlumeDraw::Compute, msaa, false);
        let reds = open
            .pixels()
            .filter(|p| p.0[0] > 40 && p.0[0] > p.0[1])
            .count();
        assert!(
            reds >= 4,
            "{msaa:?}: only {reds} red pixels without the wall"
        );
        for (name, image) in [("raster", &raster), ("compute", &compute)] {
            // Only green is seen: the red dots are behind the wall. (Where many green dots add
            // up, red passes 40 too, but never green.)
            let reds = image
                .pixels()
                .filter(|p| p.0[0] > 40 && p.0[0] > p.0[1])
                .count();
            let (n, x, y) = lit_pixels(image, 40);
            let (ex, ey) = project(2.0, 1.0);
            assert_eq!(
                reds, 0,
                "{name}, {msaa:?}: {reds} red pixels show through the wall"
            );
            assert!(n >= 4, "{name}, {msaa:?}: only {n} lit pixels");
            assert!(
                (x - ex).abs() < 4.0 && (y - ey).abs() < 4.0,
                "{name}, {msaa:?}: the dots are centred at ({x:.1}, {y:.1}), not ({ex:.1}, {ey:.1})"
            );
        }
        // The two renderers' images: the same sprites, the compute one tested at pixel
        // centres and blended once in f32 (an 8-bit sRGB target rounds the raster draw after
        // each blend); with MSAA the raster draw's edges are resolved from 4 samples and the
        // compute one's are not. Green channel totals within 10%, lit pixels within 25%.
        let green = |img: &image::RgbaImage| img.pixels().map(|p| f64::from(p.0[1])).sum::<f64>();
        let (g_raster, g_compute) = (green(&raster), green(&compute));
        assert!(
            (g_compute - g_raster).abs() <= 0.1 * g_raster,
            "{msaa:?}: green totals {g_compute} (compute) against {g_raster} (raster)"
        );
        let (n_raster, n_compute) = (lit_pixels(&raster, 40).0, lit_pixels(&compute, 40).0);
        assert!(
            f64::from(n_compute.abs_diff(n_raster)) <= 0.25 * f64::from(n_raster),
            "{msaa:?}: {n_compute} lit pixels (compute) against {n_raster} (raster)"
        );
    }
}
