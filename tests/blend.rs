//! `Multiply`, `Mask` and `Premultiplied` blending (`render.blend`) in the raster draw
//! (llvmpipe in CI): a sprite multiplies what lies behind by its colour as far as its opacity
//! goes, a cut-out is its colour, opaque, where its opacity reaches the cutoff and nothing
//! elsewhere, a premultiplied colour adds its light and dims what is behind by its opacity,
//! an opaque one covers its whole disc;
//! all draw what the CPU-fed reference drawing draws; the compute renderer leaves them to the
//! raster draw.

mod common;

use common::*;
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::Effect;

/// One sprite 2 m across at the origin, seen from 5 m, over a grey background.
fn one(blend: &str, color: &str) -> String {
    format!(
        r#"Effect(
    name: "one",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 5.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, {color})], size: [(0.0, 2.0)], blend: {blend},
                   background: (0.8, 0.8, 0.8)),
)"#
    )
}

const SIDE: u32 = 200;

fn pixel(img: &[u8], x: u32, y: u32) -> [u8; 4] {
    let at = 4 * (y * SIDE + x) as usize;
    [img[at], img[at + 1], img[at + 2], img[at + 3]]
}

/// The 8-bit value of `x` in [0, 1].
fn byte(x: f64) -> i32 {
    (x * 255.0).round() as i32
}

fn near(got: [u8; 4], want: [i32; 3], what: &str) {
    for c in 0..3 {
        assert!(
            (i32::from(got[c]) - want[c]).abs() <= 1,
            "{what}: {got:?}, want {want:?} within one step"
        );
    }
}

fn drawn(source: &str) -> (Vec<u8>, Vec<u8>) {
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, compile(source)).unwrap();
    sim.run(1, |_| {}).unwrap();
    draw_and_reference(&sim, SIDE)
}

/// Draws one sprite of `color` (RON) blended by `blend` and checks its centre (where the
/// round dot's falloff is 1) against `want` (0 to 1) in the GPU's image and the reference's,
/// a corner against the background, and the two images against each other.
fn assert_centre(blend: &str, color: &str, want: [f64; 3]) {
    let (img, reference) = drawn(&one(blend, color));
    let want = want.map(byte);
    let what = format!("{blend} {color}");
    near(
        pixel(&img, SIDE / 2, SIDE / 2),
        want,
        &format!("{what} at the centre"),
    );
    near(
        pixel(&reference, SIDE / 2, SIDE / 2),
        want,
        &format!("{what}, the reference"),
    );
    near(
        pixel(&img, 5, 5),
        [byte(0.8); 3],
        &format!("{what}, a corner"),
    );
    let (mean, max, _) = differences(&img, &reference, 1);
    assert!(
        mean < 0.01 && max <= 2,
        "{what}: GPU and reference differ: {mean} {max}"
    );
}

#[test]
fn multiply_darkens_what_lies_behind_by_the_colour_as_far_as_the_opacity_goes() {
    // behind · (1 − a + a · rgb).
    for alpha in [1.0, 0.5] {
        let want = [0.5, 0.25, 1.0].map(|c| 0.8 * (1.0 - alpha + alpha * c));
        assert_centre("Multiply", &format!("(0.5, 0.25, 1.0, {alpha})"), want);
    }
}

#[test]
fn a_premultiplied_colour_adds_its_light_and_dims_behind_by_its_opacity() {
    // rgb + behind · (1 − a). Opacity 0 is light alone, which an alpha blend would not draw.
    let light = [0.8 + 0.6, 0.8 + 0.3, 0.8].map(|x: f64| x.min(1.0));
    assert_centre("Premultiplied", "(0.6, 0.3, 0.0, 0.0)", light);
    assert_centre(
        "Premultiplied",
        "(0.3, 0.1, 0.0, 0.5)",
        [0.3 + 0.4, 0.1 + 0.4, 0.4],
    );
}

#[test]
fn a_mask_draws_its_colour_opaque_where_the_opacity_reaches_the_cutoff() {
    // The dot's opacity (1 − r²)² reaches 0.5 out to r = 0.54 of its radius: there the colour,
    // opaque; from there out, nothing (the background). The radius on screen: 1 m at 5 m
    // with a 50-degree view, 0.429 of the image's half height, 42.9 pixels.
    let (img, reference) = drawn(&one("Mask(0.5)", "(1.0, 0.2, 0.2, 1.0)"));
    let radius = 0.5 * SIDE as f64 * (1.0 / (5.0 * (25f64).to_radians().tan()));
    let at = |r: f64| pixel(&img, SIDE / 2 + (r * radius) as u32, SIDE / 2);
    for r in [0.0, 0.2, 0.45] {
        near(at(r), [255, 51, 51], &format!("r = {r}"));
    }
    for r in [0.65, 0.8, 0.95] {
        near(at(r), [byte(0.8); 3], &format!("r = {r}"));
    }
    let (mean, max, over) = differences(&img, &reference, 2);
    // A pixel on the cut edge can fall either way (f32 falloff against the cutoff).
    assert!(
        mean < 0.05 && over < 40,
        "GPU and reference differ: {mean} {max} {over}"
    );
}

#[test]
fn an_opaque_sprite_covers_its_whole_disc_with_its_colour() {
    // Half opacity, unused: the colour itself out to the rim (r = 0.9 of the radius), where
    // the round dot's falloff would have faded an alpha-blended sprite to nearly nothing.
    let (img, reference) = drawn(&one("Opaque", "(0.2, 0.6, 1.0, 0.5)"));
    let radius = 0.5 * SIDE as f64 * (1.0 / (5.0 * (25f64).to_radians().tan()));
    let want = [0.2, 0.6, 1.0].map(byte);
    for r in [0.0, 0.5, 0.9] {
        let at = pixel(&img, SIDE / 2 + (r * radius) as u32, SIDE / 2);
        near(at, want, &format!("r = {r}"));
    }
    near(
        pixel(&img, SIDE / 2 + (1.1 * radius) as u32, SIDE / 2),
        [byte(0.8); 3],
        "outside",
    );
    let (mean, _, over) = differences(&img, &reference, 2);
    assert!(
        mean < 0.05 && over < 40,
        "GPU and reference differ: {mean} {over}"
    );
}

#[test]
fn many_multiplied_and_masked_sprites_draw_as_the_reference_does() {
    for blend in ["Multiply", "Mask(0.3)", "Premultiplied", "Opaque"] {
        let source = format!(
            r#"Effect(
    name: "many",
    capacity: 400,
    seed: 4,
    sort: true,
    emitters: [Emitter(burst: 300, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.5),
                       velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((2.0, 2.0)))],
    camera: Camera(eye: (0.0, 0.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (0.9, 0.5, 0.2, 1.0)), (1.0, (0.2, 0.5, 0.9, 0.6))],
                   size: [(0.0, 0.5)], blend: {blend}, background: (0.9, 0.9, 0.9),
                   color_by: Some("vec3(rand(0), 1.0, rand(1))")),
)"#
        );
        let gpu = gpu();
        let mut sim = Effect::new(&gpu, compile(&source)).unwrap();
        sim.run(30, |_| {}).unwrap();
        assert!(
            ComputeOffscreen::why_not(&[&sim.compiled().ir]).is_some(),
            "{blend}: the compute renderer refuses"
        );
        // The reference draws the particles in the GPU's depth order: a cut-out replaces what
        // is behind, so the order shows.
        let (img, _) = draw_and_reference(&sim, SIDE);
        let ir = &sim.compiled().ir;
        let camera = plume::runtime::Camera::from_effect(&ir.camera, 1.0);
        let records = sim.records_in_draw_order().unwrap();
        let reference = plume::runtime::oracle::ReferenceRenderer::new(sim.gpu(), SIDE, SIDE, ir)
            .unwrap()
            .draw(
                &plume::runtime::oracle::sprites(&records, ir, &camera, false),
                &camera,
            )
            .unwrap();
        let (mean, max, over) = differences(&img, &reference, 2);
        eprintln!("{blend}: mean {mean:.5}, max {max}, {over} over 2");
        // Many layers of 8-bit blending, each rounding the target where f32 colours a last bit
        // apart land on a rounding edge: a multiplied stack drifts a step or a few (llvmpipe:
        // mean 0.11, at most 4); a cut edge may fall either way. A sprite drawn elsewhere, in
        // another colour or order changes its pixels by tens.
        assert!(
            mean < 0.2 && max <= 6 && over * 200 < img.len(),
            "{blend}: {mean} {max} {over}"
        );
        let lit = img
            .chunks(4)
            .filter(|p| i32::from(p[0]).abs_diff(230) > 20)
            .count();
        assert!(lit > 2000, "{blend}: only {lit} pixels drawn");
    }
}

#[test]
fn trails_and_ribbons_blend_as_their_sprites_do() {
    // A trail's and a ribbon's fragments go through the same blend_out as the sprites': each
    // drawn multiplied and cut out against the CPU-fed drawing.
    for (blend, look) in [
        (
            "Multiply",
            "trail: Some(Trail(points: 12, width: [(0.0, 0.2)]))",
        ),
        (
            "Mask(0.4)",
            "trail: Some(Trail(points: 12, width: [(0.0, 0.2)]))",
        ),
        ("Multiply", "ribbon: Some(Ribbon(points: 64))"),
        ("Mask(0.4)", "ribbon: Some(Ribbon(points: 64))"),
        (
            "Premultiplied",
            "trail: Some(Trail(points: 12, width: [(0.0, 0.2)]))",
        ),
        ("Premultiplied", "ribbon: Some(Ribbon(points: 64))"),
    ] {
        let source = format!(
            r#"Effect(
    name: "strips",
    capacity: 64,
    emitters: [Emitter(rate: 60.0, shape: Custom("vec3(1.5 * cos(3.0 * t), 1.5 * sin(5.0 * t), 0.0)"),
                       velocity: Custom("vec3(0.0, 0.5, 0.0)"), lifetime: Some((0.8, 0.8)))],
    camera: Camera(eye: (0.0, 0.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (0.2, 0.6, 0.9, 1.0))], size: [(0.0, 0.15)], blend: {blend},
                   background: (0.9, 0.9, 0.9), {look}),
)"#
        );
        let gpu = gpu();
        let mut sim = Effect::new(&gpu, compile(&source)).unwrap();
        sim.run(40, |_| {}).unwrap();
        let (img, reference) = draw_and_reference(&sim, SIDE);
        let (mean, max, over) = differences(&img, &reference, 2);
        let drawn = img.chunks(4).filter(|p| p[0] < 200).count();
        eprintln!("{blend} {look}: mean {mean:.5}, max {max}, {over} over 2, {drawn} drawn");
        assert!(drawn > 300, "{blend} {look}: only {drawn} pixels drawn");
        assert!(
            mean < 0.05 && over * 200 < img.len(),
            "{blend} {look}: {mean} {max} {over}"
        );
    }
}
