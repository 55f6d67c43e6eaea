//! How sprites look (`render.orient`), drawn on the GPU (llvmpipe in CI): a velocity-aligned
//! sprite is elongated along its projected velocity by the documented length, a sprite in a
//! fixed plane is foreshortened as that plane is, and both match the CPU-fed reference drawing
//! (f64 half axes) for stateful (Euler and Verlet) and stateless effects alike.

mod common;

use common::*;
use plume::compiler::schema::State;
use plume::runtime::{Effect, Gpu};
use plume::{compile_str, CompileOptions, Integrator};

/// Image side (square, so a pixel is the same size in x and y).
const SIDE: u32 = 400;

/// One white opaque particle at the origin moving at `velocity`, seen from `eye`, with the
/// given orientation; compiled in `state` with `integrator`, run one step on `gpu` (the
/// caller holds the shared GPU's lock for its whole test).
fn probe(
    gpu: &Gpu,
    velocity: (f64, f64, f64),
    eye: (f64, f64, f64),
    orient: &str,
    state: State,
    integrator: Integrator,
) -> Effect {
    let src = format!(
        r#"Effect(
    name: "orient-probe",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant({velocity:?}))],
    camera: Camera(eye: {eye:?}, target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.3)],
                   background: (0.0, 0.0, 0.0), orient: {orient}),
)"#
    );
    let options = CompileOptions {
        state: Some(state),
        integrator: Some(integrator),
        ..Default::default()
    };
    let effect =
        compile_str(&src, &options).unwrap_or_else(|e| panic!("{}", e.render("probe.ron", &src)));
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    sim
}

/// The GPU draw of `sim` and the CPU-fed reference drawing, `SIDE` pixels square.
fn draw_both(sim: &Effect) -> (Vec<u8>, Vec<u8>) {
    draw_and_reference(sim, SIDE)
}

/// The red channel's second moments: (long axis / short axis, the long axis's angle in degrees
/// in the image, x right and y up, in (-90, 90]). The sprite's alpha is a function of its
/// corner coordinates' radius alone, so an affine map of the disc scales the moments' axes
/// exactly as it scales the quad's: their ratio is the quad's side ratio.
fn shape(img: &[u8]) -> (f64, f64) {
    let (mut w, mut mx, mut my) = (0.0, 0.0, 0.0);
    let mut pixels = Vec::new();
    for (k, p) in img.chunks(4).enumerate() {
        let v = f64::from(p[0]);
        if v > 0.0 {
            let (x, y) = ((k as u32 % SIDE) as f64, -((k as u32 / SIDE) as f64));
            pixels.push((x, y, v));
            w += v;
            mx += v * x;
            my += v * y;
        }
    }
    assert!(w > 0.0, "nothing drawn");
    let (mx, my) = (mx / w, my / w);
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (x, y, v) in pixels {
        a += v * (x - mx) * (x - mx);
        b += v * (x - mx) * (y - my);
        c += v * (y - my) * (y - my);
    }
    let half_gap = (((a - c) / 2.0).powi(2) + b * b).sqrt();
    let (big, small) = ((a + c) / 2.0 + half_gap, (a + c) / 2.0 - half_gap);
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    ((big / small).sqrt(), angle.to_degrees())
}

fn assert_angle(got: f64, want: f64, what: &str) {
    // Axes, not directions: 180 degrees apart is the same axis.
    let d = (got - want).rem_euclid(180.0);
    let d = d.min(180.0 - d);
    assert!(d < 0.5, "{what}: long axis at {got:.2} deg, want {want:.2}");
}

fn assert_matches_reference(gpu_img: &[u8], cpu_img: &[u8], what: &str) {
    // The same quad, its corners computed in f32 (view space) on the GPU and in f64 (world
    // space, rounded to f32) on the CPU: they differ by far less than a pixel, which moves a
    // rim pixel's coverage by a step or two.
    let (mean, max, _) = differences(gpu_img, cpu_img, 4);
    assert!(
        mean < 0.01 && max <= 4,
        "{what}: GPU and CPU-fed draws differ: mean {mean}, max {max}"
    );
}

#[test]
fn a_velocity_aligned_sprite_is_elongated_along_its_projected_velocity() {
    // Seen along -z, the image plane is the xy plane. 5 m/s in it with stretch 0.1 s: length
    // 0.3 + 0.5 = 0.8 m, width 0.3 m: a 8/3 ratio, along (3, 4) in the image (53.13 deg).
    // Moving straight at the camera it has no image-plane speed: a round sprite.
    let gpu = gpu();
    let orient = "Velocity(stretch: 0.1, max_length: 2.0)";
    let cases = [
        ((3.0, 4.0, 0.0), 8.0 / 3.0, Some(53.130_102)),
        ((-4.0, 0.0, -3.0), (0.3 + 0.4) / 0.3, Some(0.0)),
        ((0.0, 60.0, 0.0), 2.0 / 0.3, Some(90.0)),
        ((0.0, 0.0, 5.0), 1.0, None),
    ];
    for (state, integrator) in [
        (State::Stateful, Integrator::Euler),
        (State::Stateful, Integrator::Verlet),
        (State::Stateless, Integrator::Exact),
    ] {
        for (v, ratio, angle) in cases {
            let what = format!("{state:?} {integrator:?} v {v:?}");
            let sim = probe(&gpu, v, (0.0, 0.0, 10.0), orient, state, integrator);
            assert_eq!(sim.is_stateless(), state == State::Stateless);
            let (gpu_img, cpu_img) = draw_both(&sim);
            let (got_ratio, got_angle) = shape(&gpu_img);
            eprintln!("{what}: ratio {got_ratio:.4} want {ratio:.4}, angle {got_angle:.3}");
            assert!(
                (got_ratio / ratio - 1.0).abs() < 0.01,
                "{what}: long / short {got_ratio:.3}, want {ratio:.3}"
            );
            if let Some(angle) = angle {
                assert_angle(got_angle, angle, &what);
            }
            assert_matches_reference(&gpu_img, &cpu_img, &what);
        }
    }
}

#[test]
fn a_sprite_facing_the_camera_turns_to_the_eye_away_from_the_images_centre() {
    // A sprite 3 m right of the view's axis, 4 m in front of the eye: 36.87 degrees off it.
    // Parallel to the image plane (Camera) it projects as a scaled copy: round. Turned to the
    // eye (FaceCamera) it meets the image plane's rays at that angle: 1 / cos = 1.25 times
    // wider than tall, to first order in its size over its distance (0.3 / 5: under 0.5%).
    let gpu = gpu();
    for (orient, ratio) in [("Camera", 1.0), ("FaceCamera", 1.25)] {
        let src = format!(
            r#"Effect(
    name: "facing-probe",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((3.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 4.0), target: (0.0, 0.0, 0.0), fov_y: 90.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.3)],
                   background: (0.0, 0.0, 0.0), orient: {orient}),
)"#
        );
        for state in [State::Stateful, State::Stateless] {
            let options = CompileOptions {
                state: Some(state),
                integrator: Some(Integrator::Exact),
                ..Default::default()
            };
            let effect = compile_str(&src, &options).unwrap();
            let mut sim = Effect::new(&gpu, effect).unwrap();
            sim.run(1, |_| {}).unwrap();
            let what = format!("{orient} {state:?}");
            let (gpu_img, cpu_img) = draw_both(&sim);
            let (got, angle) = shape(&gpu_img);
            assert!(
                (got / ratio - 1.0).abs() < 0.01,
                "{what}: ratio {got:.4}, want {ratio}"
            );
            if ratio > 1.0 {
                assert_angle(angle, 0.0, &what);
            }
            assert_matches_reference(&gpu_img, &cpu_img, &what);
            assert_splat_matches_raster(&sim, &gpu_img, &what);
        }
    }
}

#[test]
fn a_height_curve_of_its_own_makes_the_sprite_that_tall() {
    // Width 0.3 m (`size`), height `size_y`: for Camera and a Fixed plane facing the camera the
    // height runs up the image; for Velocity it is the length before stretching (0.6 + 0.5).
    let gpu = gpu();
    let cases = [
        (
            "Camera, size_y: Some([(0.0, 0.9)])",
            (1.0, 0.0, 0.0),
            3.0,
            90.0,
        ),
        (
            "Fixed((0.0, 0.0, 1.0)), size_y: Some([(0.0, 0.6)])",
            (1.0, 0.0, 0.0),
            2.0,
            90.0,
        ),
        (
            "Velocity(stretch: 0.1, max_length: 2.0), size_y: Some([(0.0, 0.6)])",
            (3.0, 4.0, 0.0),
            1.1 / 0.3,
            53.130_102,
        ),
    ];
    for (state, integrator) in [
        (State::Stateful, Integrator::Euler),
        (State::Stateless, Integrator::Exact),
    ] {
        for (orient, v, ratio, angle) in cases {
            let what = format!("{state:?} {orient}");
            let sim = probe(&gpu, v, (0.0, 0.0, 10.0), orient, state, integrator);
            let (gpu_img, cpu_img) = draw_both(&sim);
            let (got_ratio, got_angle) = shape(&gpu_img);
            assert!(
                (got_ratio / ratio - 1.0).abs() < 0.01,
                "{what}: long / short {got_ratio:.3}, want {ratio:.3}"
            );
            assert_angle(got_angle, angle, &what);
            assert_matches_reference(&gpu_img, &cpu_img, &what);
        }
    }
}

#[test]
fn an_alpha_curve_of_its_own_replaces_the_colour_stops_alpha() {
    // White, opaque colour stops; alpha 0.5 from its own curve: the centre of the soft disc
    // (falloff 1 there) blends half of white over black.
    let gpu = gpu();
    let sim = probe(
        &gpu,
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 10.0),
        "Camera, alpha: Some([(0.0, 0.5)])",
        State::Stateful,
        Integrator::Euler,
    );
    let (gpu_img, cpu_img) = draw_both(&sim);
    let centre = 4 * ((SIDE / 2) * SIDE + SIDE / 2) as usize;
    let v = gpu_img[centre];
    assert!((126..=129).contains(&v), "centre {v}, want 0.5 of 255");
    assert_matches_reference(&gpu_img, &cpu_img, "alpha curve");
}

#[test]
fn a_palette_tints_each_sprite_with_the_colour_its_id_picks() {
    // A white opaque dot: its centre shows its palette colour (the pixel centre sits a little
    // off the disc's, where its alpha falls short of 1 by a few steps), stateful and stateless.
    let gpu = gpu();
    for state in [State::Stateful, State::Stateless] {
        let sim = probe(
            &gpu,
            (0.0, 0.0, 0.0),
            (0.0, 0.0, 10.0),
            "Camera, palette: Some([(1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)])",
            state,
            Integrator::Exact,
        );
        let ir = &sim.compiled().ir;
        let pick =
            plume::compiler::tint::pick(ir.render.palette.as_deref().unwrap(), ir.seed_mix, 0);
        let (gpu_img, cpu_img) = draw_both(&sim);
        let centre = 4 * ((SIDE / 2) * SIDE + SIDE / 2) as usize;
        let got = &gpu_img[centre..centre + 3];
        for (c, want) in got.iter().zip([pick.x, pick.y, pick.z]) {
            assert!(
                if want == 0.0 { *c == 0 } else { *c >= 245 },
                "{state:?}: the centre {got:?} is not the palette's colour {pick:?}"
            );
        }
        assert_matches_reference(&gpu_img, &cpu_img, &format!("palette, {state:?}"));
    }
}

#[test]
fn a_sprite_in_a_fixed_plane_is_foreshortened_as_the_plane_is() {
    // A disc lying on the ground (normal +Y) seen from 36.87 deg above the horizon (eye at
    // (0, 6, 8)): its depth extent shrinks by sin 36.87 = 0.6, its width does not, so it is an
    // ellipse with axes 1 : 0.6, the long one horizontal. (Perspective changes this by under
    // 1% for a 0.3 m disc 10 m away.) Facing the camera instead (normal along the view axis),
    // it is round.
    let gpu = gpu();
    for (normal, ratio) in [("(0.0, 1.0, 0.0)", 1.0 / 0.6), ("(0.0, 0.6, 0.8)", 1.0)] {
        let orient = format!("Fixed({normal})");
        let sim = probe(
            &gpu,
            (0.0, 0.0, 0.0),
            (0.0, 6.0, 8.0),
            &orient,
            State::Stateful,
            Integrator::Euler,
        );
        let (gpu_img, cpu_img) = draw_both(&sim);
        let (got_ratio, got_angle) = shape(&gpu_img);
        assert!(
            (got_ratio / ratio - 1.0).abs() < 0.01,
            "{orient}: long / short {got_ratio:.3}, want {ratio:.3}"
        );
        if ratio > 1.0 {
            assert_angle(got_angle, 0.0, &orient);
        }
        assert_matches_reference(&gpu_img, &cpu_img, &orient);
    }
}

/// Asserts that the compute renderer's image of `sim` is the raster draw's: it places each pixel
/// on the quad through the quad's projective map where the rasteriser interpolates corner
/// coordinates over two triangles (the same values to about 1e-4 of a pixel), tests coverage
/// at pixel centres without the rasteriser's sub-pixel snapping, and rounds to 8 bits after
/// each blend as llvmpipe's blend unit does. A pixel on a steep part of the falloff may then
/// land a step or two apart and an edge pixel flip; a quad turned or stretched wrongly moves
/// whole 4 x 4 squares by tens of steps.
fn assert_splat_matches_raster(sim: &Effect, raster: &[u8], what: &str) {
    let splat = splat_image(sim, SIDE);
    let lit = raster.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    assert!(lit > 50, "{what}: the raster draw shows {lit} pixels");
    let (mean, max, over) = differences(raster, &splat, 2);
    let local = local_difference(raster, &splat, SIDE, 4);
    if std::env::var_os("PLUME_DUMP").is_some() {
        let name = what.replace(|c: char| !c.is_ascii_alphanumeric(), "_");
        for (img, kind) in [(raster, "raster"), (&splat[..], "splat")] {
            image::save_buffer(
                format!("/tmp/{name}_{kind}.png"),
                img,
                SIDE,
                SIDE,
                image::ColorType::Rgba8,
            )
            .unwrap();
        }
    }
    eprintln!("{what}: splat vs raster: mean {mean:.4}, max {max}, {over} over 2, 4x4 {local:.2}");
    assert!(
        mean < 0.02 && local < 4.0 && over * 2000 < splat.len(),
        "{what}: the compute renderer differs from the raster draw: mean {mean}, max {max}, {over} over 2, 4x4 {local}"
    );
}

#[test]
fn the_compute_renderer_draws_oriented_sprites_as_the_raster_draw_does() {
    let gpu = gpu();
    let cases = [
        // Streaked along the velocity, seen from the front and from an angle.
        (
            (1.0, 0.0, 0.0),
            (0.0, 0.0, 10.0),
            "Velocity(stretch: 0.1, max_length: 2.0)",
        ),
        (
            (1.0, 0.5, 0.0),
            (4.0, 3.0, 8.0),
            "Velocity(stretch: 0.3, max_length: 2.0)",
        ),
        // Lying on the ground seen from above at a slant: a foreshortened, perspective quad.
        ((0.0, 0.0, 0.0), (0.0, 3.0, 4.0), "Fixed((0.0, 1.0, 0.0))"),
        ((0.0, 0.0, 0.0), (2.0, 1.0, 1.5), "Fixed((1.0, 1.0, 0.0))"),
    ];
    for (velocity, eye, orient) in cases {
        for state in [State::Stateful, State::Stateless] {
            let integrator = match state {
                State::Stateless => Integrator::Exact,
                _ => Integrator::Euler,
            };
            let sim = probe(&gpu, velocity, eye, orient, state, integrator);
            let (raster, _) = draw_both(&sim);
            assert_splat_matches_raster(&sim, &raster, &format!("{orient} from {eye:?} {state:?}"));
        }
    }
}

/// The compute renderer composites camera-facing quads by an affine map (they lie parallel to the image
/// plane, so one w holds over each) only where the projection's w ignores view x and y. A
/// camera turned against the view the sprites face (the projection times a turn of 0.6 rad
/// about y: w = 0.56 x - 0.83 z) makes even a camera-facing quad projective, and the compute renderer must
/// then divide at each pixel as the rasteriser interpolates. One big sprite straight ahead of
/// the turned camera, its w ranging over a fifth of its value: with nothing overlapping, the
/// two draws differ by rounding alone (in no pixel here; the bounds allow a step in a few),
/// where the sprite composited affinely from its w at each tile's centre lands up to 5 steps
/// off, 7,467 channels more than 2, and 4 x 4 squares 3.4 steps apart.
#[test]
fn the_compute_renderer_divides_at_each_pixel_where_the_projection_tilts() {
    use plume::runtime::oracle::group_renderer;
    use plume::runtime::outputs::{ComputeOffscreen, Offscreen};
    use plume::runtime::Camera;
    let gpu = gpu();
    // At (4 sin 0.6, 0, 4 - 4 cos 0.6): 4 m straight ahead of the turned camera at (0, 0, 4).
    let src = r#"Effect(
    name: "tilted-probe",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((2.2586, 0.0, 0.6987)), velocity: Constant((1.0, 0.2, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 4.0), target: (0.0, 0.0, 0.0), fov_y: 60.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 1.5)],
                   background: (0.0, 0.0, 0.0), orient: Velocity(stretch: 0.5, max_length: 3.0)),
)"#;
    let effect = compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("tilted.ron", src)));
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let flat = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let proj = flat.proj * glam::Mat4::from_rotation_y(0.6);
    assert!(proj.x_axis.w.abs() > 0.5, "w leans on view x");
    let tilted = Camera::new(flat.view, proj);
    let target = Offscreen::new(sim.gpu(), SIDE, SIDE).unwrap();
    let renderer = group_renderer(&sim, 0, &target.target()).unwrap();
    let raster = target.render(&sim, &renderer, &tilted).unwrap();
    let mut splat = ComputeOffscreen::new(&sim, SIDE, SIDE).unwrap();
    let splat_img = splat.render(&sim, &tilted).unwrap();
    let lit = raster.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    assert!(lit > 5000, "the raster draw shows {lit} pixels");
    let (mean, max, over) = differences(&raster, &splat_img, 2);
    let local = local_difference(&raster, &splat_img, SIDE, 4);
    if std::env::var_os("PLUME_DUMP").is_some() {
        for (img, kind) in [(&raster, "raster"), (&splat_img, "splat")] {
            let path = format!("/tmp/tilted_{kind}.png");
            image::save_buffer(path, img, SIDE, SIDE, image::ColorType::Rgba8).unwrap();
        }
    }
    eprintln!("tilted: splat vs raster: mean {mean:.4}, max {max}, {over} over 2, 4x4 {local:.2}");
    assert!(
        mean < 0.01 && local < 1.0 && over == 0,
        "tilted projection: the compute renderer differs from the raster draw: mean {mean}, max {max}, {over} over 2, 4x4 {local}"
    );
}

/// A sprite of `size` drawn at `distance` metres from the eye, its size measured in metres or
/// in the image (`size_in`): the lit pixels' radius of gyration in pixels, after checking the
/// GPU draw against the CPU-fed reference drawing and the compute renderer against the raster.
fn sprite_radius(gpu: &Gpu, distance: f64, size_in: &str, size: f64) -> f64 {
    let src = format!(
        r#"Effect(
    name: "screen-size",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, {distance}), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, {size})],
                   background: (0.0, 0.0, 0.0), size_in: {size_in}),
)"#
    );
    let effect = compile_str(&src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("s.ron", &src)));
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let (gpu_img, cpu_img) = draw_both(&sim);
    assert_matches_reference(&gpu_img, &cpu_img, size_in);
    assert_splat_matches_raster(&sim, &gpu_img, size_in);
    let (mut w, mut r2) = (0.0, 0.0);
    let c = f64::from(SIDE) / 2.0 - 0.5;
    for (k, p) in gpu_img.chunks(4).enumerate() {
        let v = f64::from(p[0]);
        let (x, y) = ((k as u32 % SIDE) as f64 - c, (k as u32 / SIDE) as f64 - c);
        w += v;
        r2 += v * (x * x + y * y);
    }
    assert!(w > 0.0, "{size_in} at {distance} m: nothing drawn");
    (r2 / w).sqrt()
}

#[test]
fn a_size_in_the_image_is_the_same_at_any_distance() {
    let gpu = gpu();
    // In the image: 0.1 of its height at 5 m and at 20 m, 40 pixels across in a 400-pixel
    // image, its disc's radius of gyration the same within a pixel's rounding at the rim.
    let (near, far) = (
        sprite_radius(&gpu, 5.0, "Screen", 0.1),
        sprite_radius(&gpu, 20.0, "Screen", 0.1),
    );
    assert!(
        (near - far).abs() < 0.3,
        "near {near:.2} px, far {far:.2} px"
    );
    // The soft disc's alpha (1 - r²)² weighs a radius-R disc's pixels to a radius of gyration
    // of R / 2: R = 20 px.
    assert!((near - 10.0).abs() < 0.5, "{near:.2} px, want 10");
    // In metres the far one is four times smaller.
    let (near_m, far_m) = (
        sprite_radius(&gpu, 5.0, "World", 0.5),
        sprite_radius(&gpu, 20.0, "World", 0.5),
    );
    assert!(
        (near_m / far_m - 4.0).abs() < 0.2,
        "near {near_m:.2} px, far {far_m:.2} px"
    );
}
