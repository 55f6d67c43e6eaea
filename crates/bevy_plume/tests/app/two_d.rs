//! Effects in 2D views (`Camera2d`), headless on lavapipe: a particle is drawn where Bevy's
//! orthographic 2D camera puts it, and in the transparent 2D phase (where Bevy's sprites are
//! drawn) effects sort by their entity's z: a larger blue one in front (larger z) covers the
//! dot, one behind does not, whichever was spawned first; drawn by the compute renderer
//! (`PlumeDraw::Compute`), the same picture; and an opaque 2D mesh in front of an effect's z
//! hides it in both renderers, one behind it does not.
//! `BEVY_PLUME_TEST_IMAGES=DIR` keeps the images.

use crate::common::{asset_dir, lit_pixels, serial, Harness, HEIGHT, WIDTH};
use bevy::prelude::*;
use bevy_plume::{PlumeDraw, PlumeEffect, PlumeRenderStats};

/// One orange particle at (20, 10), 16 units across, that never dies.
const DOT: &str = r#"Effect(
    name: "dot",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((20.0, 10.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (1.0, 0.5, 0.2, 1.0))], size: [(0.0, 16.0)], background: (0.0, 0.0, 0.0)),
)"#;

/// A blue particle at the same place, 40 units across, that never dies.
const DISC: &str = r#"Effect(
    name: "disc",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((20.0, 10.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (0.0, 0.0, 1.0, 1.0))], size: [(0.0, 40.0)], background: (0.0, 0.0, 0.0)),
)"#;

/// The particle's centre in the image: the 2D camera puts the origin at the centre, y up.
fn centre() -> (f32, f32) {
    (WIDTH as f32 / 2.0 + 20.0, HEIGHT as f32 / 2.0 - 10.0)
}

/// A 2D app with the dot at z = 0 and, when `disc_z` is given, the blue disc at that z
/// (spawned before the dot when `disc_first`), both drawn by `renderer`, and where `card_z`
/// is given an opaque green 2D mesh 30 units square over the dot at that z; the image after a
/// few frames, and how many draws the compute renderer made in the last.
fn draw_by(
    name: &str,
    (disc_z, disc_first): (Option<f32>, bool),
    renderer: PlumeDraw,
    card_z: Option<f32>,
) -> (image::RgbaImage, usize) {
    let dir = asset_dir(name);
    std::fs::write(dir.join("dot.plume.ron"), DOT).unwrap();
    std::fs::write(dir.join("disc.plume.ron"), DISC).unwrap();
    let mut h = Harness::new(&dir);
    h.use_2d();
    h.wait_for_pipelines();
    let dot = h.load("dot.plume.ron");
    let disc = h.load("disc.plume.ron");
    let spawn_disc = |h: &mut Harness| {
        if let Some(z) = disc_z {
            h.app.world_mut().spawn((
                PlumeEffect::new(disc.clone()).with_draw(renderer),
                Transform::from_xyz(0.0, 0.0, z),
            ));
        }
    };
    if let Some(z) = card_z {
        let mesh = h
            .app
            .world_mut()
            .resource_mut::<Assets<Mesh>>()
            .add(Rectangle::new(30.0, 30.0));
        let green = h
            .app
            .world_mut()
            .resource_mut::<Assets<ColorMaterial>>()
            .add(ColorMaterial::from_color(Color::srgb(0.0, 1.0, 0.0)));
        h.app.world_mut().spawn((
            Mesh2d(mesh),
            MeshMaterial2d(green),
            Transform::from_xyz(20.0, 10.0, z),
        ));
    }
    if disc_first {
        spawn_disc(&mut h);
    }
    h.app.world_mut().spawn((
        PlumeEffect::new(dot).with_draw(renderer),
        Transform::IDENTITY,
    ));
    if !disc_first {
        spawn_disc(&mut h);
    }
    h.update(5);
    let image = h.capture_running();
    if let Ok(out) = std::env::var("BEVY_PLUME_TEST_IMAGES") {
        image
            .save(std::path::Path::new(&out).join(format!("{name}.png")))
            .unwrap();
    }
    let stats = *h
        .app
        .sub_app(bevy::render::RenderApp)
        .world()
        .resource::<PlumeRenderStats>();
    (image, stats.compute_draws)
}

/// [`draw_by`] with the default renderer (in 2D, the raster one).
fn draw(name: &str, disc_z: Option<f32>, disc_first: bool) -> image::RgbaImage {
    let (image, compute_draws) = draw_by(name, (disc_z, disc_first), PlumeDraw::Auto, None);
    assert_eq!(
        compute_draws, 0,
        "Auto draws 2D effects with the raster renderer"
    );
    image
}

#[test]
fn a_camera2d_draws_a_particle_where_its_projection_puts_it() {
    let _one = serial();
    let image = draw("2d-dot", None, false);
    let (n, x, y) = lit_pixels(&image, 40);
    let (cx, cy) = centre();
    // The soft dot fades to nothing at its rim: the pixels over 40 lie within its 8 units.
    assert!(
        (40..=201).contains(&n),
        "{n} pixels lit, the dot covers at most 201"
    );
    assert!(
        (x - cx).abs() < 0.5 && (y - cy).abs() < 0.5,
        "the dot's pixels centre on ({x}, {y}), its projection on ({cx}, {cy})"
    );
    // (1, 0.5, 0.2) written to an sRGB image: (255, 188, 124).
    let p = image.get_pixel(cx as u32, cy as u32).0;
    assert!(
        p[0] > 240 && (170..200).contains(&p[1]) && (110..140).contains(&p[2]),
        "the dot's centre is {p:?}, not orange"
    );
}

#[test]
fn in_2d_effects_sort_by_z_whatever_their_spawn_order() {
    let _one = serial();
    let (cx, cy) = centre();
    for disc_first in [true, false] {
        let behind = draw(&format!("2d-behind-{disc_first}"), Some(-1.0), disc_first);
        let p = behind.get_pixel(cx as u32, cy as u32).0;
        assert!(
            p[0] > 200,
            "disc behind (z -1), spawned first: {disc_first}: the dot's centre is {p:?}, not orange"
        );
        let front = draw(&format!("2d-front-{disc_first}"), Some(1.0), disc_first);
        let p = front.get_pixel(cx as u32, cy as u32).0;
        assert!(
            p[0] < 20 && p[2] > 200,
            "disc in front (z 1), spawned first: {disc_first}: the dot's centre is {p:?}, not blue"
        );
    }
}

#[test]
fn in_2d_the_compute_renderer_draws_and_sorts_as_the_raster_one() {
    let _one = serial();
    for (disc_z, what) in [
        (None, "the dot"),
        (Some(-1.0), "disc behind"),
        (Some(1.0), "disc in front"),
    ] {
        let name = format!("2d-compute-{what}").replace(' ', "-");
        let raster = draw(&format!("{name}-raster"), disc_z, false);
        let (compute, compute_draws) = draw_by(&name, (disc_z, false), PlumeDraw::Compute, None);
        let effects = if disc_z.is_some() { 2 } else { 1 };
        assert_eq!(
            compute_draws, effects,
            "{what}: every effect drawn by the compute renderer"
        );
        // The same picture but for the rounding of a soft edge (the compute renderer
        // composites in f32 and rounds once).
        let differing = raster
            .pixels()
            .zip(compute.pixels())
            .filter(|(a, b)| (0..3).any(|k| a.0[k].abs_diff(b.0[k]) > 3))
            .count();
        assert!(
            differing <= 20,
            "{what}: {differing} pixels differ by more than 3 steps"
        );
        let (n, _, _) = lit_pixels(&compute, 40);
        assert!(n >= 40, "{what}: only {n} pixels lit");
    }
}

#[test]
fn an_opaque_2d_mesh_in_front_hides_the_effect_in_both_renderers() {
    let _one = serial();
    let (cx, cy) = centre();
    for renderer in [PlumeDraw::Raster, PlumeDraw::Compute] {
        for (card_z, dot_shows) in [(1.0, false), (-1.0, true)] {
            let name = format!("2d-card-{renderer:?}-{card_z}");
            let (image, _) = draw_by(&name, (None, false), renderer, Some(card_z));
            let p = image.get_pixel(cx as u32, cy as u32).0;
            let orange = p[0] > 200;
            let green = p[0] < 20 && p[1] > 200;
            assert!(
                if dot_shows { orange } else { green },
                "{renderer:?}, an opaque card at z {card_z}: the dot's centre is {p:?}"
            );
        }
    }
}
