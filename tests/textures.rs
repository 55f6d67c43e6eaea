//! Sprite textures and flipbooks (`render.texture`), drawn on the GPU (llvmpipe in CI): a
//! textured sprite shows its texture's pattern the right way up (and along the velocity when
//! it is velocity-aligned), a flipbook shows frame k at the documented time (over life and at
//! a rate, stateful and stateless), each image matches the CPU-fed reference drawing (frame
//! chosen in f64), and the compute renderer samples them as the raster draw does.

mod common;

use std::path::{Path, PathBuf};

use common::*;
use plume::compiler::schema::State;
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::{Effect, Gpu};
use plume::{compile_str, CompileOptions};

/// Image side (square).
const SIDE: u32 = 200;

/// A directory of its own for this test's texture files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-textures-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes a PNG of `columns` x `rows` solid blocks of `block` texels, block k (left to right,
/// top to bottom) of colour `colours[k]`, opaque.
fn write_blocks(path: &Path, columns: u32, rows: u32, block: u32, colours: &[[u8; 3]]) {
    let image = image::RgbaImage::from_fn(columns * block, rows * block, |x, y| {
        let [r, g, b] = colours[((y / block) * columns + x / block) as usize];
        image::Rgba([r, g, b, 255])
    });
    image.save(path).unwrap();
}

/// One white opaque particle at the origin moving at `velocity` (with `lifetime`, seconds),
/// seen from (0, 0, 10), drawn with `render_extra` (texture, orientation) in `state`.
fn probe(
    gpu: &Gpu,
    dir: &Path,
    velocity: (f64, f64, f64),
    lifetime: Option<f64>,
    render_extra: &str,
    state: State,
) -> Effect {
    let lifetime = match lifetime {
        Some(l) => format!("Some(({l}, {l}))"),
        None => "None".into(),
    };
    let src = format!(
        r#"Effect(
    name: "texture-probe",
    capacity: 1,
    dt: 0.016666666666666666,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant({velocity:?}),
                       lifetime: {lifetime})],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 2.0)],
                   background: (0.0, 0.0, 0.0), {render_extra}),
)"#
    );
    let options = CompileOptions {
        state: Some(state),
        base_dir: Some(dir.to_path_buf()),
        ..Default::default()
    };
    let effect =
        compile_str(&src, &options).unwrap_or_else(|e| panic!("{}", e.render("probe.ron", &src)));
    assert_eq!(effect.ir.stateless.is_some(), state == State::Stateless);
    Effect::new(gpu, effect).unwrap()
}

/// The GPU draw of `sim` and the CPU-fed reference drawing, `SIDE` pixels square.
fn draw_both(sim: &Effect) -> (Vec<u8>, Vec<u8>) {
    draw_and_reference(sim, SIDE)
}

fn pixel(img: &[u8], x: u32, y: u32) -> [u8; 3] {
    let k = 4 * (y * SIDE + x) as usize;
    [img[k], img[k + 1], img[k + 2]]
}

/// The colour at `(fx, fy)` of the drawn square sprite (fractions of its bounding box, from the
/// top left), and the box's width and height in pixels.
fn sample(img: &[u8], points: &[(f64, f64)]) -> (Vec<[u8; 3]>, (u32, u32)) {
    let (mut x0, mut y0, mut x1, mut y1) = (SIDE, SIDE, 0, 0);
    for y in 0..SIDE {
        for x in 0..SIDE {
            if pixel(img, x, y) != [0, 0, 0] {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
            }
        }
    }
    assert!(x1 > x0 && y1 > y0, "nothing drawn");
    let at = |(fx, fy): (f64, f64)| {
        let x = x0 as f64 + fx * f64::from(x1 - x0);
        let y = y0 as f64 + fy * f64::from(y1 - y0);
        pixel(img, x.round() as u32, y.round() as u32)
    };
    (
        points.iter().map(|&p| at(p)).collect(),
        (x1 - x0 + 1, y1 - y0 + 1),
    )
}

fn assert_close(got: [u8; 3], want: [u8; 3], what: &str) {
    assert!(
        got.iter().zip(want).all(|(g, w)| g.abs_diff(w) <= 1),
        "{what}: got {got:?}, want {want:?}"
    );
}

fn assert_matches_reference(gpu_img: &[u8], cpu_img: &[u8], what: &str) {
    // The same quads and the same frames' texels. The corners are computed in f32 (GPU, view
    // space) and f64 (CPU, world space) and land a tiny fraction of a pixel apart: inside a
    // sprite the filtered texels then differ by a step or two, but an opaque texture has a hard
    // rim, and a pixel centre lying on it can be covered in one drawing and not the other (a
    // whole pixel's difference). Such pixels are rare: at most one in a thousand. A wrong frame
    // or a misplaced or flipped sprite changes whole blocks of pixels.
    let (mut sum, mut far) = (0u64, 0usize);
    for (a, b) in gpu_img.chunks(4).zip(cpu_img.chunks(4)) {
        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        sum += u64::from(d);
        far += usize::from(d > 8);
    }
    let pixels = gpu_img.len() / 4;
    let mean = sum as f64 / pixels as f64;
    assert!(
        mean < 0.5 && far * 1000 <= pixels,
        "{what}: GPU and CPU-fed draws differ: mean {mean}, {far} of {pixels} pixels by more than 8"
    );
}

const RED: [u8; 3] = [255, 0, 0];
const GREEN: [u8; 3] = [0, 255, 0];
const BLUE: [u8; 3] = [0, 0, 255];
const YELLOW: [u8; 3] = [255, 255, 0];

/// The four quadrants' centres, top left, top right, bottom left, bottom right.
const QUADRANTS: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

#[test]
fn a_textured_sprite_shows_its_texture_the_right_way_up() {
    let gpu = gpu();
    let dir = scratch("quadrants");
    // Top left red, top right green, bottom left blue, bottom right yellow.
    write_blocks(&dir.join("q.png"), 2, 2, 8, &[RED, GREEN, BLUE, YELLOW]);
    // A 2 m sprite 10 m away with a 40 degree field of view: 2 / (2 · 10 · tan 20°) of the
    // image's 200 pixels, 54.9 pixels a side.
    let side = 2.0 / (2.0 * 10.0 * 20f64.to_radians().tan()) * f64::from(SIDE);
    for state in [State::Stateful, State::Stateless] {
        let texture = r#"texture: Some(Texture(file: "q.png"))"#;
        let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), None, texture, state);
        sim.run(1, |_| {}).unwrap();
        let (gpu_img, cpu_img) = draw_both(&sim);
        let (got, (w, h)) = sample(&gpu_img, &QUADRANTS);
        for (g, want) in got.into_iter().zip([RED, GREEN, BLUE, YELLOW]) {
            assert_close(g, want, &format!("{state:?} upright"));
        }
        for extent in [w, h] {
            assert!(
                (f64::from(extent) - side).abs() <= 1.5,
                "{state:?}: {w}x{h} pixels, want {side:.1} a side"
            );
        }
        assert_matches_reference(&gpu_img, &cpu_img, &format!("{state:?} upright"));
    }
    // Aligned with its velocity, the texture's top points where the particle goes: moving
    // right in the image, the top row (red, green) is on the right, red (top left) at the top.
    let oriented =
        r#"texture: Some(Texture(file: "q.png")), orient: Velocity(stretch: 0.0, max_length: 2.0)"#;
    for state in [State::Stateful, State::Stateless] {
        let mut sim = probe(&gpu, &dir, (1.0, 0.0, 0.0), None, oriented, state);
        sim.run(1, |_| {}).unwrap();
        let (gpu_img, cpu_img) = draw_both(&sim);
        let (got, _) = sample(&gpu_img, &QUADRANTS);
        for (g, want) in got.into_iter().zip([BLUE, RED, YELLOW, GREEN]) {
            assert_close(g, want, &format!("{state:?} moving right"));
        }
        assert_matches_reference(&gpu_img, &cpu_img, &format!("{state:?} moving right"));
    }
}

#[test]
fn a_rotated_sprite_turns_its_texture_by_its_angle_and_spin() {
    let gpu = gpu();
    let dir = scratch("rotation");
    write_blocks(&dir.join("q.png"), 2, 2, 8, &[RED, GREEN, BLUE, YELLOW]);
    // A quarter turn counter-clockwise brings the texture's right side (green over yellow) to
    // the top and its top (red, green) to the left; a half turn puts it upside down.
    let quarter = [GREEN, YELLOW, RED, BLUE];
    let half = [YELLOW, BLUE, GREEN, RED];
    let texture = r#"texture: Some(Texture(file: "q.png"))"#;
    let cases = [
        // A fixed starting angle, facing the camera or lying in the plane facing it.
        ("Camera", "angle: (90.0, 90.0)", 1, quarter),
        ("Fixed((0.0, 0.0, 1.0))", "angle: (90.0, 90.0)", 1, quarter),
        // 90 degrees a second from 0: a quarter turn after 60 steps of 1/60 s, half after 120.
        ("Camera", "spin: (90.0, 90.0)", 60, quarter),
        ("Camera", "spin: (90.0, 90.0)", 120, half),
        (
            "Fixed((0.0, 0.0, 1.0))",
            "angle: (-90.0, -90.0), spin: (90.0, 90.0)",
            180,
            half,
        ),
    ];
    for state in [State::Stateful, State::Stateless] {
        for (orient, rotation, steps, want) in cases {
            let what = format!("{state:?} {orient} {rotation} after {steps} steps");
            let extra =
                format!("{texture}, orient: {orient}, rotation: Some(Rotation({rotation}))");
            let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), None, &extra, state);
            sim.run(steps, |_| {}).unwrap();
            let (gpu_img, cpu_img) = draw_both(&sim);
            let (got, (w, h)) = sample(&gpu_img, &QUADRANTS);
            assert!(w.abs_diff(h) <= 1, "{what}: still square, {w}x{h}");
            for (g, c) in got.into_iter().zip(want) {
                assert_close(g, c, &what);
            }
            assert_matches_reference(&gpu_img, &cpu_img, &what);
        }
    }
}

/// The colour of the drawn sprite's centre after each step of `steps`, with the particle's
/// age and lifetime (seconds) from the records.
fn centre_over_time(sim: &mut Effect, steps: u64) -> Vec<([u8; 3], f64, Option<f64>)> {
    let mut seen = Vec::new();
    for _ in 0..steps {
        sim.run(1, |_| {}).unwrap();
        let records = sim.records().unwrap();
        assert_eq!(records.len(), 1, "the particle is alive");
        let (gpu_img, cpu_img) = draw_both(sim);
        assert_matches_reference(&gpu_img, &cpu_img, "flipbook");
        let (got, _) = sample(&gpu_img, &[(0.5, 0.5)]);
        seen.push((got[0], records[0].age, records[0].lifetime));
    }
    seen
}

#[test]
fn a_flipbook_shows_frame_k_at_the_documented_time() {
    let gpu = gpu();
    let dir = scratch("flipbook");
    let frames = [RED, GREEN, BLUE, YELLOW];
    write_blocks(&dir.join("f.png"), 4, 1, 4, &frames);
    for state in [State::Stateful, State::Stateless] {
        // Over life: 24 steps of life, 4 frames: frame k from life fraction k / 4 (age / life,
        // whole steps), so 6 steps each.
        let texture = r#"texture: Some(Texture(file: "f.png", frames: (4, 1)))"#;
        let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), Some(0.4), texture, state);
        let seen = centre_over_time(&mut sim, 23);
        let mut shown = [0; 4];
        for (colour, age, life) in seen {
            let k = ((4.0 * age / life.unwrap() + 1e-9).floor() as usize).min(3);
            assert_close(
                colour,
                frames[k],
                &format!("{state:?} over life, age {age:.4}"),
            );
            shown[k] += 1;
        }
        // Ages 1..=23 steps of 24: frames of 5, 6, 6 and 6 steps.
        assert_eq!(shown, [5, 6, 6, 6], "{state:?}: steps per frame over life");

        // At 15 frames per second with 60 steps per second: 4 steps per frame, looping, for a
        // particle that never dies.
        let texture = r#"texture: Some(Texture(file: "f.png", frames: (4, 1), play: Rate(15.0)))"#;
        let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), None, texture, state);
        for (colour, age, life) in centre_over_time(&mut sim, 20) {
            assert_eq!(life, None);
            let k = ((age * 15.0 + 1e-9).floor() as usize) % 4;
            assert_close(
                colour,
                frames[k],
                &format!("{state:?} at 15 fps, age {age:.4}"),
            );
        }
    }
}

#[test]
fn a_random_start_gives_particles_born_together_different_frames() {
    let gpu = gpu();
    let dir = scratch("random-start");
    let frames = [RED, GREEN, BLUE, YELLOW];
    write_blocks(&dir.join("f.png"), 4, 1, 4, &frames);
    // 64 particles born in one burst on a line across the image (0.095 m apart, 0.06 m wide:
    // none overlap), a frame each from its id.
    let src = r#"Effect(
    name: "random-start",
    capacity: 64,
    emitters: [Emitter(burst: 64, shape: Grid(min: (-3.0, 0.0, 0.0), max: (3.0, 0.0, 0.0), counts: (64, 1, 1)),
                       velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.06)],
                   background: (0.0, 0.0, 0.0),
                   texture: Some(Texture(file: "f.png", frames: (4, 1), play: Rate(15.0), random_start: true))),
)"#;
    let options = CompileOptions {
        base_dir: Some(dir.clone()),
        ..Default::default()
    };
    let effect =
        compile_str(src, &options).unwrap_or_else(|e| panic!("{}", e.render("r.ron", src)));
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let (gpu_img, cpu_img) = draw_both(&sim);
    assert_matches_reference(&gpu_img, &cpu_img, "random start");
    let mut counts = [0usize; 4];
    for p in gpu_img.chunks(4) {
        if let Some(k) = frames.iter().position(|f| p[..3] == f[..]) {
            counts[k] += 1;
        }
    }
    assert!(
        counts.iter().all(|&n| n > 0),
        "every frame shows somewhere: pixels per frame {counts:?}"
    );
}

#[test]
fn the_compute_renderer_samples_textures_as_the_raster_draw_does() {
    // The compute renderer maps each pixel to the quad's texture coordinates through the quad's
    // projective map and takes their derivatives from it, where the rasteriser interpolates
    // over two triangles and differences 2 x 2 pixel blocks: for these quads (affine, or
    // projective but smooth over a pixel) both give the same coordinates and mip level to
    // well under a texel, and the same trilinear sample. A pixel whose level sits at a
    // rounding boundary, or on the quad's edge, may differ by a few steps; a wrong frame,
    // turn or level moves whole 4 x 4 squares by tens.
    let gpu = gpu();
    let dir = scratch("splat");
    // 128 x 128 texels over a sprite about 110 pixels wide: a minified sprite, so mip level 1
    // is in use over part of it.
    write_blocks(&dir.join("big.png"), 2, 2, 64, &[RED, GREEN, BLUE, YELLOW]);
    write_blocks(&dir.join("book.png"), 2, 2, 8, &[RED, GREEN, BLUE, YELLOW]);
    let cases = [
        (r#"texture: Some(Texture(file: "big.png"))"#, 1),
        (
            r#"texture: Some(Texture(file: "big.png")), orient: Fixed((0.0, 1.0, 1.0)), rotation: Some(Rotation(angle: (30.0, 30.0)))"#,
            1,
        ),
        (
            r#"texture: Some(Texture(file: "book.png", frames: (2, 2), play: Rate(6.0))), rotation: Some(Rotation(spin: (90.0, 90.0)))"#,
            25,
        ),
        (
            r#"texture: Some(Texture(file: "book.png", frames: (2, 2), play: Rate(6.0))), size_y: Some([(0.0, 1.0)])"#,
            45,
        ),
    ];
    for state in [State::Stateful, State::Stateless] {
        for (extra, steps) in cases {
            let what = format!("{state:?} {extra} after {steps} steps");
            let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), None, extra, state);
            sim.run(steps, |_| {}).unwrap();
            assert!(ComputeOffscreen::draws(&sim.compiled().ir), "{what}");
            let (raster, _) = draw_both(&sim);
            let splat = splat_image(&sim, SIDE);
            let lit = raster.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
            assert!(lit > 50, "{what}: the raster draw shows {lit} pixels");
            let (mean, max, over) = differences(&raster, &splat, 2);
            let local = local_difference(&raster, &splat, SIDE, 4);
            eprintln!("{what}: mean {mean:.4}, max {max}, {over} over 2, 4x4 {local:.2}");
            assert!(
                mean < 0.05 && local < 4.0 && over * 1000 < splat.len(),
                "{what}: the compute renderer differs from the raster draw: mean {mean}, max {max}, {over} over 2, 4x4 {local}"
            );
        }
    }
}

#[test]
fn an_effect_compiled_to_step_only_runs_without_its_texture_and_its_draw_says_why_not() {
    // `CompileOptions::step_only` (plume run, plume bench without drawing): the file is
    // missing, yet the effect compiles, keeps its flipbook's 2 x 2 frames and steps; only a
    // draw needs the image, and it is refused with the field, the file and why.
    let gpu = gpu();
    let dir = scratch("step-only");
    let src = r#"Effect(
    name: "no-texture",
    capacity: 8,
    emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)),
                       lifetime: Some((1.0, 1.0)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.5)],
                   texture: Some(Texture(file: "gone.png", frames: (2, 2)))),
)"#;
    let options = CompileOptions {
        base_dir: Some(dir.clone()),
        ..Default::default()
    };
    let drawn = compile_str(src, &options)
        .unwrap_err()
        .render("no-texture.ron", src);
    assert!(
        drawn.contains("no-texture.ron:7:48: error: render.texture.file: cannot open texture"),
        "{drawn}"
    );
    let stepped = compile_str(
        src,
        &CompileOptions {
            step_only: true,
            ..options
        },
    )
    .expect("a missing texture is no error for an effect that is only stepped");
    let texture = stepped
        .ir
        .render
        .texture
        .clone()
        .expect("the texture's frames");
    assert_eq!((texture.columns, texture.rows), (2, 2));
    let why = texture.missing.clone().expect("why it is missing");
    assert!(
        why.starts_with("render.texture.file: cannot open texture") && why.contains("gone.png"),
        "{why}"
    );
    let mut sim = Effect::new(&gpu, stepped).unwrap();
    sim.run(30, |_| {}).unwrap();
    let alive = sim.records().unwrap();
    assert_eq!(alive.len(), 8, "the particles stepped");
    assert!(alive.iter().all(|p| (p.position.y - 0.5).abs() < 1e-4));
    let target = plume::runtime::outputs::Offscreen::new(&gpu, 16, 16).unwrap();
    let refused = plume::runtime::oracle::group_renderer(&sim, 0, &target.target())
        .err()
        .expect("the draw needs the texture")
        .to_string();
    assert!(
        refused.contains("render.texture.file: cannot open texture")
            && refused.contains("gone.png")
            && refused.contains("compiled to be stepped, not drawn"),
        "{refused}"
    );
}

#[test]
fn a_frame_chosen_by_an_expression_is_the_frame_shown() {
    // frame_by: hanabi circle's ping-pong over the age, |fract(age / 0.2) * 2 - 1| * 4, whole
    // part wrapped around 4 frames: frames 3, 2, 1, 0, 0, 1, 2, 3 over every 0.2 s, in both
    // states, and the reference drawing alike.
    let gpu = gpu();
    let dir = scratch("frame-by");
    let frames = [RED, GREEN, BLUE, YELLOW];
    write_blocks(&dir.join("f.png"), 4, 1, 4, &frames);
    let texture = r#"texture: Some(Texture(file: "f.png", frames: (4, 1))), frame_by: Some("abs(fract(age * 5.0) * 2.0 - 1.0) * 4.0")"#;
    for state in [State::Stateful, State::Stateless] {
        let mut sim = probe(&gpu, &dir, (0.0, 0.0, 0.0), Some(2.0), texture, state);
        let mut shown = [0; 4];
        for (colour, age, _) in centre_over_time(&mut sim, 24) {
            let v = ((age * 5.0).fract() * 2.0 - 1.0).abs() * 4.0;
            // Away from a whole number, where the GPU's f32 and the f64 could floor apart.
            if (v - v.round()).abs() < 1e-4 {
                continue;
            }
            let k = (v.floor() as usize).min(4) % 4;
            assert_close(colour, frames[k], &format!("{state:?} at age {age:.4}"));
            shown[k] += 1;
        }
        assert!(
            shown.iter().all(|&n| n > 0),
            "{state:?}: every frame shows: {shown:?}"
        );
    }
}

#[test]
fn a_texture_can_give_colour_alone_or_opacity_from_its_red_channel() {
    // A frame whose left half is (0.8, 0.2, 0.6) at alpha 0.5 and right half black at alpha
    // 1, under an orange sprite: Modulate multiplies all four; ModulateRgb only the colour
    // (the sprite stays opaque); OpacityFromRed keeps the colour and takes the opacity from
    // the red channel (0.8 on the left, none on the right). A second image laid out as the
    // first, (0.4, 1, 0.6) on the left, multiplies the colour too as its own mapping says
    // (ModulateRgb: its colour). The raster draw, the compute renderer and the reference drawing
    // alike.
    let gpu = gpu();
    let dir = scratch("sample");
    let image = image::RgbaImage::from_fn(8, 8, |x, _| match x < 4 {
        true => image::Rgba([204, 51, 153, 128]),
        false => image::Rgba([0, 0, 0, 255]),
    });
    image.save(dir.join("halves.png")).unwrap();
    let image = image::RgbaImage::from_fn(8, 8, |x, _| match x < 4 {
        true => image::Rgba([102, 255, 153, 64]),
        false => image::Rgba([128, 128, 128, 255]),
    });
    image.save(dir.join("tint.png")).unwrap();
    let colour = [1.0, 0.5, 0.25];
    for (mapping, left, right) in [
        ("Modulate", [0.8, 0.1, 0.15, 0.502], [0.0, 0.0, 0.0, 1.0]),
        ("ModulateRgb", [0.8, 0.1, 0.15, 1.0], [0.0, 0.0, 0.0, 1.0]),
        (
            "OpacityFromRed",
            [1.0, 0.5, 0.25, 0.8],
            [1.0, 0.5, 0.25, 0.0],
        ),
        (
            r#"OpacityFromRed, second: Some(SecondTexture(file: "tint.png", sample: ModulateRgb))"#,
            [0.4, 0.5, 0.15, 0.8],
            [0.5, 0.25, 0.125, 0.0],
        ),
    ] {
        let src = format!(
            r#"Effect(
    name: "sample",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, ({}, {}, {}, 1.0))], size: [(0.0, 4.0)], background: (0.0, 0.0, 0.0),
                   texture: Some(Texture(file: "halves.png", sample: {mapping}))),
)"#,
            colour[0], colour[1], colour[2]
        );
        let options = CompileOptions {
            base_dir: Some(dir.clone()),
            ..Default::default()
        };
        let effect =
            compile_str(&src, &options).unwrap_or_else(|e| panic!("{}", e.render("s.ron", &src)));
        let mut sim = Effect::new(&gpu, effect).unwrap();
        sim.run(1, |_| {}).unwrap();
        let (gpu_img, cpu_img) = draw_both(&sim);
        assert_matches_reference(&gpu_img, &cpu_img, mapping);
        // Over black the pixel is colour times alpha. The sprite, 4 m at 10 m with a 40-degree
        // view, is 110 pixels across: 1 m either side of its centre is 27.5 pixels.
        let got = [
            pixel(&gpu_img, 72, SIDE / 2),
            pixel(&gpu_img, 128, SIDE / 2),
        ];
        for (seen, want, side) in [(got[0], left, "left"), (got[1], right, "right")] {
            let expect = [0, 1, 2].map(|c| (255.0_f64 * want[c] * want[3]).round() as u8);
            assert_close(seen, expect, &format!("{mapping}, {side} half"));
        }
        let mut splat = ComputeOffscreen::new(&sim, SIDE, SIDE).unwrap();
        let camera = plume::runtime::Camera::from_effect(&sim.compiled().ir.camera, 1.0);
        let splatted = splat.render(&sim, &camera).unwrap();
        let (mean, max, _) = differences(&gpu_img, &splatted, 2);
        assert!(
            mean < 0.05 && max <= 6,
            "{mapping}: splat and raster differ: {mean} {max}"
        );
    }
}
