//! Mesh particles (`render.mesh`) in Bevy's view, headless on lavapipe: a particle drawn as a
//! square plate covers the square its corners project to, drawn by the raster renderer and by
//! the compute one (an opaque mesh over Bevy's reversed depth); and a file with no mesh, given
//! a Bevy mesh in code, draws that mesh.
//! `BEVY_PLUME_TEST_IMAGES=DIR` keeps the image.

use crate::common::{asset_dir, project, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeRenderStats};

/// One particle at (0.5, 0.25, 0) drawn as `plate.obj` 2 m across.
const PLATE: &str = r#"Effect(
    name: "plate",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.5, 0.25, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (1.0, 0.4, 0.2, 1.0))], size: [(0.0, 2.0)], blend: Opaque,
                   background: (0.0, 0.0, 0.0), mesh: Some(ParticleMesh(file: "plate.obj"))),
)"#;

/// A unit square in the xy plane facing +z (toward the camera), as two triangles.
const PLATE_OBJ: &str =
    "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nf 1 2 3\nf 1 3 4\n";

#[test]
fn a_mesh_particle_covers_where_its_mesh_projects() {
    let _one = serial();
    let dir = asset_dir("meshes");
    std::fs::write(dir.join("plate.plume.ron"), PLATE).unwrap();
    std::fs::write(dir.join("plate.obj"), PLATE_OBJ).unwrap();
    for draw in [PlumeDraw::Raster, PlumeDraw::Compute] {
        let mut h = Harness::new(&dir);
        h.camera();
        h.wait_for_pipelines();
        let plate = h.load("plate.plume.ron");
        h.app
            .world_mut()
            .spawn((PlumeEffect::new(plate).with_draw(draw), Transform::IDENTITY));
        h.update(5);
        let image = h.capture_running();
        if let Ok(out) = std::env::var("BEVY_PLUME_TEST_IMAGES") {
            image
                .save(std::path::Path::new(&out).join(format!("mesh-{draw:?}.png")))
                .unwrap();
        }
        assert_covers(
            &image,
            (-0.5, 1.25),
            (1.5, -0.75),
            &format!("{draw:?} plate"),
        );
        let stats = *h
            .app
            .sub_app(RenderApp)
            .world()
            .resource::<PlumeRenderStats>();
        let want = usize::from(draw == PlumeDraw::Compute);
        assert_eq!(
            stats.compute_draws, want,
            "{draw:?}: which renderer drew the mesh"
        );
    }
}

/// The same particle with no mesh in its file, drawn as a Bevy mesh given in code
/// (`PlumeEffect::with_mesh`): a `Rectangle` 1 m wide and 0.5 m tall, so at size 2 a plate
/// 2 m by 1 m, not the 2 m square its sprite would be.
#[test]
fn a_bevy_mesh_draws_the_particles_of_a_file_without_one() {
    let _one = serial();
    let dir = asset_dir("bevy-mesh");
    let sprites = PLATE.replace(", mesh: Some(ParticleMesh(file: \"plate.obj\"))", "");
    assert!(!sprites.contains("mesh"));
    std::fs::write(dir.join("plate.plume.ron"), sprites).unwrap();
    let mut h = Harness::new(&dir);
    h.camera();
    h.wait_for_pipelines();
    let plate = h.load("plate.plume.ron");
    let rectangle = h
        .app
        .world_mut()
        .resource_mut::<Assets<Mesh>>()
        .add(Rectangle::new(1.0, 0.5));
    h.app.world_mut().spawn((
        PlumeEffect::new(plate).with_mesh(rectangle),
        Transform::IDENTITY,
    ));
    // The file is compiled again with the mesh off the main thread: a few frames.
    let drawn = h.update_until(300, std::time::Duration::from_millis(10), |h| {
        h.capture().pixels().filter(|p| p.0[0] > 128).count() > 100
    });
    assert!(drawn, "the particle was never drawn as the Bevy mesh");
    let image = h.capture_running();
    assert_covers(&image, (-0.5, 0.75), (1.5, -0.25), "rectangle");
}

/// Asserts that the pixels of `image` with red over 128 fill the rectangle between the
/// projections of the world points (x, y, 0) `top_left` and `bottom_right`, edges within
/// 1.5 px, every pixel inside lit; `what` names it.
fn assert_covers(
    image: &image::RgbaImage,
    top_left: (f32, f32),
    bottom_right: (f32, f32),
    what: &str,
) {
    let lit: Vec<(u32, u32)> = image
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[0] > 128)
        .map(|(x, y, _)| (x, y))
        .collect();
    assert!(lit.len() > 100, "only {} pixels lit", lit.len());
    let (x0, y0) = project(top_left.0, top_left.1);
    let (x1, y1) = project(bottom_right.0, bottom_right.1);
    let xs = lit.iter().map(|p| p.0 as f32 + 0.5);
    let ys = lit.iter().map(|p| p.1 as f32 + 0.5);
    let (left, right) = (xs.clone().fold(f32::MAX, f32::min), xs.fold(0.0, f32::max));
    let (top, bottom) = (ys.clone().fold(f32::MAX, f32::min), ys.fold(0.0, f32::max));
    for (got, want, edge) in [
        (left, x0, "left"),
        (right, x1, "right"),
        (top, y0, "top"),
        (bottom, y1, "bottom"),
    ] {
        assert!(
            (got - want).abs() < 1.5,
            "the {what}'s {edge} edge at {got} px, its corners project to {want}"
        );
    }
    // Filled: every pixel inside.
    let inside = ((x1 - x0 - 2.0) * (y1 - y0 - 2.0)) as usize;
    assert!(lit.len() >= inside, "{} pixels lit of {inside}", lit.len());
}
