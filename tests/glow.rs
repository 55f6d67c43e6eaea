//! Glow (`render.glow`) in `plume render`'s images, on llvmpipe: light above the threshold
//! spreads into a halo that fades with distance and stops where the blur's kernel ends, an
//! image with nothing above the threshold is the plain image, and the compute renderer blooms
//! the same image.

mod common;

use common::*;
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::outputs::Offscreen;
use plume::runtime::{Effect, Gpu};

const W: u32 = 160;
const H: u32 = 100;

/// `count` additive white particles stacked at the origin (each of alpha `alpha`), a 1 m
/// sprite 10 m away, with the glow `glow` (RON, or "None").
fn stack(gpu: &Gpu, count: u32, alpha: f64, glow: &str) -> Effect {
    stack_of(gpu, count, 1.0, alpha, glow)
}

/// [`stack`] of particles whose colour is `white` in every channel (above 1: HDR light).
fn stack_of(gpu: &Gpu, count: u32, white: f64, alpha: f64, glow: &str) -> Effect {
    let src = format!(
        r#"Effect(
    name: "glow-probe",
    capacity: {count},
    emitters: [Emitter(burst: {count}, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, ({white:?}, {white:?}, {white:?}, {alpha}))], size: [(0.0, 1.0)], blend: Additive,
                   background: (0.0, 0.0, 0.0), glow: {glow}),
)"#
    );
    let mut sim = Effect::new(gpu, compile(&src)).unwrap();
    sim.run(1, |_| {}).unwrap();
    sim
}

/// The image of `sim` as `plume render` draws it (with its glow), and without the glow.
fn draw(sim: &Effect) -> (Vec<u8>, Vec<u8>) {
    let gpu = sim.gpu();
    let glow = sim.compiled().ir.render.glow;
    let glowing = Offscreen::with_glow(gpu, W, H, glow.as_ref()).unwrap();
    let plain = Offscreen::new(gpu, W, H).unwrap();
    let camera = plain.effect_camera(sim);
    let a = glowing
        .render(sim, &sim.renderer(&glowing.target()).unwrap(), &camera)
        .unwrap();
    let b = plain
        .render(sim, &sim.renderer(&plain.target()).unwrap(), &camera)
        .unwrap();
    (a, b)
}

/// The image of `sim` from the compute renderer, checked to come out the same in a second frame:
/// each pixel's light is summed exactly (and stopped at the glow's clamp), whatever the order
/// of its tile's list.
fn splat_twice(sim: &Effect) -> Vec<u8> {
    let mut splat = ComputeOffscreen::new(sim, W, H).unwrap();
    let camera = sim.camera(W as f32 / H as f32);
    let img = splat.render(sim, &camera).unwrap();
    assert!(
        img == splat.render(sim, &camera).unwrap(),
        "a second frame differs"
    );
    img
}

/// The red value at `dx` pixels right of the image centre, on its middle row.
fn red(img: &[u8], dx: u32) -> u8 {
    img[4 * ((H / 2) * W + W / 2 + dx) as usize]
}

#[test]
fn bright_light_spreads_into_a_halo_that_fades_and_ends_with_the_kernel() {
    let gpu = gpu();
    // 40 sprites of alpha 0.1 add up to 4 at the centre: far above the threshold 0.5.
    let sim = stack(
        &gpu,
        40,
        0.1,
        "Some(Glow(threshold: 0.5, strength: 1.0, radius: 0.03))",
    );
    let (glowing, plain) = draw(&sim);
    // The 1 m sprite is 1 / (2 · 10 · tan 20°) of the 100-pixel height across: a 13.7-pixel
    // disc, radius 6.9. Outside it the plain image is background.
    let rim = 7;
    for dx in rim..W / 2 {
        assert_eq!(red(&plain, dx), 0, "plain image outside the disc at +{dx}");
    }
    // With glow, the halo lights the pixels past the rim, less and less further out...
    let halo: Vec<u8> = (rim..rim + 8).map(|dx| red(&glowing, dx)).collect();
    assert!(halo[0] > 20, "the halo starts bright at the rim: {halo:?}");
    assert!(
        halo.windows(2).all(|w| w[1] <= w[0]) && halo[7] < halo[0],
        "and fades with distance: {halo:?}"
    );
    // ... and stops where the kernel does: sigma 3 pixels (0.03 of 100), 9 taps, so nothing
    // lights past the rim's 6.9 pixels plus 9 pixels of blur.
    for dx in rim + 10..W / 2 {
        assert_eq!(red(&glowing, dx), 0, "past the kernel at +{dx}");
    }
    // Inside the disc both are saturated.
    assert_eq!((red(&glowing, 0), red(&plain, 0)), (255, 255));
}

#[test]
fn a_colour_above_one_glows_as_that_much_stacked_light_does() {
    // One sprite of colour 40 at alpha 0.1 is 4.0 of light at its centre, as 40 stacked sprites
    // of colour 1 are: the same HDR image (to the f16 roundings of the stack's 40 blends, under
    // a 2048th of the value each), so the same bloom, in the raster draw and the compute renderer.
    let gpu = gpu();
    let glow = "Some(Glow(threshold: 0.5, strength: 1.0, radius: 0.03))";
    let stacked = stack(&gpu, 40, 0.1, glow);
    let bright = stack_of(&gpu, 1, 40.0, 0.1, glow);
    let ((stacked_glow, _), (bright_glow, bright_plain)) = (draw(&stacked), draw(&bright));
    let (mean, max, _) = differences(&stacked_glow, &bright_glow, 1);
    assert!(mean < 0.05 && max <= 2, "raster: mean {mean}, max {max}");
    let (mean, max, _) = differences(&bright_glow, &splat_twice(&bright), 1);
    assert!(
        mean < 0.05 && max <= 2,
        "splat against raster: mean {mean}, max {max}"
    );
    assert!(
        red(&bright_glow, 10) > 5,
        "a halo past the rim: {}",
        red(&bright_glow, 10)
    );
    // An 8-bit image clamps a sprite's colour to 1 before it blends: 1.0 x 0.1 at the centre.
    assert!(
        red(&bright_plain, 0).abs_diff(26) <= 1,
        "the plain image's centre: {}",
        red(&bright_plain, 0)
    );
}

#[test]
fn light_below_the_threshold_leaves_the_image_as_it_is() {
    let gpu = gpu();
    // One sprite of alpha 0.4: at most 0.4, below the threshold 0.5: nothing glows.
    let sim = stack(
        &gpu,
        1,
        0.4,
        "Some(Glow(threshold: 0.5, strength: 2.0, radius: 0.03))",
    );
    let (glowing, plain) = draw(&sim);
    // The HDR image blends in half floats, the plain one in 8 bits: a step apart at most.
    let max = glowing
        .iter()
        .zip(&plain)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(max <= 1, "images differ by up to {max}");
    assert!(
        red(&plain, 0) > 90,
        "the sprite is drawn: {}",
        red(&plain, 0)
    );
}

#[test]
fn the_compute_renderer_glows_as_the_raster_draw_does() {
    // The compute renderer sums the stack in f32 and stores the HDR image as f16 once; the raster draw
    // adds each sprite into its f16 target, rounding at every blend (each rounding under
    // 1/2048 of the value: 40 of them move a pixel by about 2% of a step at most before the
    // bloom). Both bloom the same HDR image with the same passes, so the halo and the disc
    // agree to a step; a missing halo would differ by tens of steps past the rim.
    let gpu = gpu();
    for (count, alpha) in [(40, 0.1), (1, 0.4)] {
        let sim = stack(
            &gpu,
            count,
            alpha,
            "Some(Glow(threshold: 0.5, strength: 2.0, radius: 0.03))",
        );
        assert!(ComputeOffscreen::draws(&sim.compiled().ir));
        let (raster, _) = draw(&sim);
        let img = splat_twice(&sim);
        let (mean, max, _) = differences(&raster, &img, 1);
        eprintln!("{count} x {alpha}: splat vs raster: mean {mean:.4}, max {max}");
        assert!(
            mean < 0.05 && max <= 2,
            "{count} x {alpha}: mean {mean}, max {max}"
        );
        if count > 1 {
            // The halo is there: light past the disc's rim.
            // The disc's rim is 7 pixels from the centre (see the test above).
            assert!(red(&img, 10) > 5, "no halo past the rim: {}", red(&img, 10));
        }
    }
}

#[test]
fn the_glows_clamp_bounds_the_halo_and_the_compute_renderer_stops_there() {
    // 400 opaque white sprites stacked: 400 of light at the centre. Unclamped, the halo past
    // the rim is 400 times the kernel's tail there; with `clamp: 2.0` the stack blooms as light
    // of 2 does, so a few sigma past the rim it fades out where the unclamped halo is still
    // full. The compute renderer stops adding light into a pixel at the clamp (each slice of a tile's
    // list once its own sprites reach it), the raster draw adds all 400 and the bloom clamps
    // what it reads: the same image either way, to the step the test above allows.
    // (Unclamped, the raster draw's 400
    // half-float blends round at each one, up to 1/8 of light near 400, and the far halo
    // takes that error 2 x 400 times the kernel's weight there: 15 steps apart on llvmpipe.)
    let gpu = gpu();
    let glow = |clamp: f64| {
        format!("Some(Glow(threshold: 0.5, strength: 2.0, radius: 0.03, clamp: {clamp:.1}))")
    };
    let full = stack(&gpu, 400, 1.0, &glow(65504.0));
    let clamped = stack(&gpu, 400, 1.0, &glow(2.0));
    let (full_raster, _) = draw(&full);
    let (clamped_raster, _) = draw(&clamped);
    let rim = 7;
    // Both halos start bright at the rim; 4 pixels (1.3 sigma) further the clamped one fades
    // while the unclamped one is still saturated.
    assert!(
        red(&clamped_raster, rim + 1) > 100,
        "clamped halo at the rim"
    );
    assert_eq!(
        red(&full_raster, rim + 5),
        255,
        "unclamped halo past the rim"
    );
    assert!(
        red(&clamped_raster, rim + 5) < 200,
        "the clamp bounds the halo: {}",
        red(&clamped_raster, rim + 5)
    );
    let img = splat_twice(&clamped);
    let (mean, max, _) = differences(&clamped_raster, &img, 1);
    eprintln!("clamp 2: splat vs raster: mean {mean:.4}, max {max}");
    assert!(mean < 0.05 && max <= 2, "clamp 2: mean {mean}, max {max}");
    // And the compute renderer's halo is the clamped one, not the full one.
    assert!(red(&img, rim + 5) < 200, "splat: {}", red(&img, rim + 5));
}
