//! Lit sprites (`render.lit`) on llvmpipe: single pixels of a sprite whose normal and lights
//! are known, against the f64 lighting (`Lit::normal`, `Lights::received`, `Lit::shade`):
//! Lambert's law for a flat card, a half sphere's normal across the sprite, a point light's
//! fall-off and range, wrap and the emissive part, a host's lights. Each in the raster draw,
//! the compute renderer, `plume render`'s splat and the reference drawing. Then turned,
//! textured and lit sprites of many particles, where the draws must agree with the reference
//! drawing.

mod common;

use common::*;
use glam::{DVec3, DVec4};
use plume::compiler::lights::{LightSource, Lights};
use plume::compiler::lit::Lit;
use plume::runtime::oracle::{sprites, ReferenceRenderer};
use plume::runtime::outputs::{ComputeOffscreen, Offscreen};
use plume::runtime::{Camera, Effect, Gpu};

/// Odd, so that the sprite's centre (the image's) is a pixel's centre.
const SIDE: u32 = 65;
/// The sprite's radius (m), 10 m from the camera.
const RADIUS: f64 = 2.5;
const FOV_Y: f64 = 40.0;
const COLOR: [f64; 4] = [0.8, 0.6, 0.4, 1.0];

/// One opaque sprite of radius [`RADIUS`] at the origin facing the camera 10 m away along +z,
/// over black, with `lit` (the `Lit(...)` text) and `lights` (the list's entries).
fn probe(gpu: &Gpu, lit: &str, lights: &str) -> Effect {
    probe_with(gpu, lit, lights, "", None)
}

/// [`probe`] with `render` (more of the render section's fields) and files read from `dir`.
fn probe_with(
    gpu: &Gpu,
    lit: &str,
    lights: &str,
    render: &str,
    dir: Option<&std::path::Path>,
) -> Effect {
    let [r, g, b, a] = COLOR;
    let src = format!(
        r#"Effect(
    name: "lit-probe",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: {FOV_Y:.1}),
    lights: [{lights}],
    render: Render(color: [(0.0, ({r}, {g}, {b}, {a}))], size: [(0.0, {size:.1})],
                   background: (0.0, 0.0, 0.0), lit: Some({lit}){render}),
)"#,
        size = 2.0 * RADIUS
    );
    let options = plume::CompileOptions {
        base_dir: dir.map(std::path::Path::to_path_buf),
        ..Default::default()
    };
    let effect = plume::compile_str(&src, &options)
        .unwrap_or_else(|e| panic!("{}", e.render("probe.ron", &src)));
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    sim
}

/// The sprite's radius in pixels: 10 m away, the image's half height spans 10 tan(fov / 2).
fn radius_pixels() -> f64 {
    RADIUS / (10.0 * (FOV_Y.to_radians() / 2.0).tan()) * f64::from(SIDE) / 2.0
}

/// The f64 colour (0 to 255) of the pixel `right` pixels right of and `up` pixels above the
/// centre: corner coordinates uv exact (the sprite lies parallel to the image plane), the
/// colour lit there, blended over black. Its alpha is the soft disc's (1 − r²)², or for a
/// textured sprite whose texel is `texel` (RGBA in [0, 1]) and whose lit maps' texels there
/// are beside it, the texel's, the colour times the texel.
fn expected(
    sim: &Effect,
    lights: &Lights,
    right: i32,
    up: i32,
    texel: Option<([f64; 4], [DVec4; 2])>,
) -> [f64; 3] {
    let ir = &sim.compiled().ir;
    let lit: &Lit = ir.render.lit.as_ref().expect("a lit probe");
    let uv = (
        f64::from(right) / radius_pixels(),
        f64::from(up) / radius_pixels(),
    );
    let (half_x, half_y) = (DVec3::X * RADIUS, DVec3::Y * RADIUS);
    let p = uv.0 * half_x + uv.1 * half_y;
    let maps = texel.map_or([DVec4::ZERO; 2], |t| t.1);
    let eye = DVec3::new(0.0, 0.0, 10.0);
    let light = lit.light(lights, (uv, (half_x, half_y), eye, p), maps);
    let (rgba, alpha) = match texel {
        Some((t, _)) => (
            [COLOR[0] * t[0], COLOR[1] * t[1], COLOR[2] * t[2]],
            COLOR[3] * t[3],
        ),
        None => {
            let r2 = uv.0 * uv.0 + uv.1 * uv.1;
            (
                [COLOR[0], COLOR[1], COLOR[2]],
                COLOR[3] * (1.0 - r2).max(0.0).powi(2),
            )
        }
    };
    let rgb = lit.shade(DVec3::from_array(rgba), light);
    (rgb * alpha)
        .clamp(DVec3::ZERO, DVec3::ONE)
        .to_array()
        .map(|x| x * 255.0)
}

/// The images of `sim`, `SIDE` square from its camera, lit by `lights` when given (a host's):
/// the raster draw, the compute renderer, `plume render`'s splat, the reference drawing.
fn images(gpu: &Gpu, sim: &Effect, lights: Option<&Lights>) -> Vec<(&'static str, Vec<u8>)> {
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let target = Offscreen::new(gpu, SIDE, SIDE).unwrap();
    let mut out = Vec::new();
    for (kind, compute) in [("raster", false), ("compute renderer", true)] {
        let mut renderer = match compute {
            true => sim.compute_renderer(&target.target(), SIDE, SIDE).unwrap(),
            false => sim.renderer(&target.target()).unwrap(),
        };
        if let Some(lights) = lights {
            renderer.set_lights(lights);
        }
        out.push((kind, target.render(sim, &renderer, &camera).unwrap()));
    }
    let mut splat = ComputeOffscreen::new(sim, SIDE, SIDE).unwrap();
    if let Some(lights) = lights {
        splat.set_lights(lights);
    }
    out.push(("splat", splat.render(sim, &camera).unwrap()));
    let ir = &sim.compiled().ir;
    let reference = ReferenceRenderer::new(gpu, SIDE, SIDE, ir).unwrap();
    if let Some(lights) = lights {
        reference.set_lights(lights);
    }
    let drawn = sprites(&sim.records().unwrap(), ir, &camera, false);
    out.push(("reference", reference.draw(&drawn, &camera).unwrap()));
    out
}

/// Asserts that every draw of `sim` (lit by its file's lights, or by a host's `host` set on
/// each renderer) colours the pixels at `offsets` (right, up) from the centre as the f64
/// lighting does, within one 8-bit step: each image is rounded to 8 bits once, and its f32
/// arithmetic lands far nearer than a step (the light's terms are sums of a few products of
/// numbers near 1).
fn assert_lit_like_f64(gpu: &Gpu, sim: &Effect, host: Option<&Lights>, offsets: &[(i32, i32)]) {
    assert_textured_lit_like_f64(gpu, sim, host, offsets, None);
}

/// [`assert_lit_like_f64`] for a textured sprite of one texel and one texel of each lit map
/// (`texel`) everywhere, when given.
fn assert_textured_lit_like_f64(
    gpu: &Gpu,
    sim: &Effect,
    host: Option<&Lights>,
    offsets: &[(i32, i32)],
    texel: Option<([f64; 4], [DVec4; 2])>,
) {
    let lights = host.unwrap_or(&sim.compiled().ir.lights);
    let centre = (SIDE / 2) as i32;
    let mut wrong = Vec::new();
    for (kind, image) in images(gpu, sim, host) {
        for &(right, up) in offsets {
            let want = expected(sim, lights, right, up, texel);
            let (x, y) = (centre + right, centre - up);
            let at = 4 * (y as usize * SIDE as usize + x as usize);
            let got = &image[at..at + 3];
            if (0..3).any(|c| (f64::from(got[c]) - want[c]).abs() > 1.0) {
                wrong.push(format!(
                    "{kind}: pixel ({right}, {up}) is {got:?} where the f64 lighting gives {want:.2?}"
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn a_flat_card_is_lit_by_lamberts_law() {
    let gpu = gpu();
    // Light 60 degrees off the card's normal (+z): it receives cos 60 = half of it.
    let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
    let lights = format!(
        "Directional(direction: (0.0, {}, {})), Ambient(intensity: 0.1)",
        -s, -c
    );
    let sim = probe(&gpu, "Lit(normals: Flat)", &lights);
    let ir_lights = sim.compiled().ir.lights.clone();
    let received = ir_lights.received(DVec3::Z, DVec3::ZERO, 0.0);
    assert!(
        (received - DVec3::splat(0.6)).length() < 1e-12,
        "{received}"
    );
    assert_lit_like_f64(&gpu, &sim, None, &[(0, 0), (8, 0), (-8, 5), (0, -12)]);
}

#[test]
fn a_sphere_sprite_is_lit_on_the_side_the_light_comes_from() {
    let gpu = gpu();
    // Light travelling along -x: it comes from +x, lighting the right half.
    let sim = probe(
        &gpu,
        "Lit(normals: Sphere)",
        "Directional(direction: (-1.0, 0.0, 0.0))",
    );
    let across: Vec<(i32, i32)> = (-18..=18).step_by(3).map(|x| (x, 0)).collect();
    assert_lit_like_f64(&gpu, &sim, None, &across);
    assert_lit_like_f64(&gpu, &sim, None, &[(6, 6), (-6, -6), (10, -4)]);
    // The left half, facing away, is black (no ambient light in the list); the right lit.
    let image = &images(&gpu, &sim, None)[0].1;
    let red = |x: u32| image[4 * ((SIDE / 2) * SIDE + x) as usize];
    assert_eq!(red(SIDE / 2 - 10), 0);
    assert!(red(SIDE / 2 + 10) > 40);
}

#[test]
fn a_point_light_falls_off_with_distance_and_range() {
    let gpu = gpu();
    // 2 m in front of the sprite, its range 3 m: the window is well below 1 at the rim.
    let sim = probe(
        &gpu,
        "Lit(normals: Sphere)",
        "Point(position: (0.5, 0.0, 2.0), intensity: 3.0, range: 3.0)",
    );
    assert_lit_like_f64(
        &gpu,
        &sim,
        None,
        &[(0, 0), (5, 0), (-5, 0), (0, 10), (14, 3), (-14, -3)],
    );
}

#[test]
fn wrap_and_the_emissive_part_shade_as_written() {
    let gpu = gpu();
    // Light from 110 degrees off the normal: only wrap lets it reach the card.
    let (s, c) = (110f64.to_radians().sin(), 110f64.to_radians().cos());
    let lights = format!(
        "Directional(direction: ({}, 0.0, {}), intensity: 2.0)",
        -s, -c
    );
    let sim = probe(
        &gpu,
        "Lit(normals: Flat, wrap: 0.5, emissive: 0.3)",
        &lights,
    );
    let ir_lights = sim.compiled().ir.lights.clone();
    let facing = ((c + 0.5) / 1.5).max(0.0);
    let received = ir_lights.received(DVec3::Z, DVec3::ZERO, 0.5);
    assert!((received.x - 2.0 * facing).abs() < 1e-12);
    assert_lit_like_f64(&gpu, &sim, None, &[(0, 0), (7, 7)]);
}

#[test]
fn a_hosts_lights_replace_the_files() {
    let gpu = gpu();
    let sim = probe(
        &gpu,
        "Lit(normals: Sphere, wrap: 0.2)",
        "Ambient(intensity: 1.0)",
    );
    // A red lamp above and to the left, and a dim blue sky.
    let host = Lights {
        ambient: DVec3::new(0.0, 0.0, 0.2),
        sources: vec![
            LightSource::Point {
                position: DVec3::new(-2.0, 3.0, 2.0),
                color: DVec3::new(6.0, 0.5, 0.5),
                range: 20.0,
            },
            LightSource::Directional {
                direction: DVec3::new(0.0, 0.0, -1.0),
                color: DVec3::splat(0.3),
            },
        ],
        shadow: None,
    };
    assert_lit_like_f64(
        &gpu,
        &sim,
        Some(&host),
        &[(0, 0), (-9, 9), (9, -9), (15, 0)],
    );
}

/// A fresh folder `name` under the temporary directory holding, for each (file, texel), an
/// 8 x 8 PNG of that one RGBA8 texel.
fn uniform_pngs(name: &str, files: &[(&str, [u8; 4])]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (file, texel) in files {
        let rgba: Vec<u8> = texel.repeat(64);
        image::save_buffer(dir.join(file), &rgba, 8, 8, image::ColorType::Rgba8).unwrap();
    }
    dir
}

#[test]
fn a_normal_map_turns_the_light_as_its_texels_say() {
    let gpu = gpu();
    // An 8 x 8 texture of one tint and a normal map of one normal, leaning right: (0.6, 0, 0.8)
    // as 8-bit texels, (r, g, b) = (n + 1) / 2.
    let tint = [230u8, 204, 255, 255];
    let leaning = [204u8, 128, 230, 255];
    let dir = uniform_pngs("plume-lit", &[("tint.png", tint), ("normals.png", leaning)]);
    let decode = |t: [u8; 4]| t.map(|c| f64::from(c) / 255.0);
    let texel = Some((
        decode(tint),
        [DVec4::from_array(decode(leaning)), DVec4::ZERO],
    ));
    let texture = r#", texture: Some(Texture(file: "tint.png"))"#;
    let lit = r#"Lit(normals: Map(file: "normals.png"))"#;
    let offsets = [(0, 0), (12, 0), (-12, 7), (5, -15)];
    // Light from the right, which the normal leans toward; then from the left, away from it.
    for lights in [
        "Directional(direction: (-1.0, 0.0, 0.0)), Ambient(intensity: 0.1)",
        "Directional(direction: (1.0, 0.0, -0.3)), Ambient(intensity: 0.1)",
    ] {
        let sim = probe_with(&gpu, lit, lights, texture, Some(&dir));
        assert_textured_lit_like_f64(&gpu, &sim, None, &offsets, texel);
    }
    // The sphere's own normals would light the centre from the right not at all.
    let sim = probe_with(
        &gpu,
        lit,
        "Directional(direction: (-1.0, 0.0, 0.0))",
        texture,
        Some(&dir),
    );
    let centre = expected(&sim, &sim.compiled().ir.lights, 0, 0, texel);
    assert!(centre[0] > 100.0, "{centre:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn six_way_lightmaps_weigh_each_light_by_its_direction() {
    let gpu = gpu();
    // Six different responses, so a light read from the wrong map or axis shows: right 0.9,
    // top 0.7, back 0.3 in the first map; left 0.2, bottom 0.5, front 0.6 in the second.
    let tint = [255u8, 255, 255, 255];
    let right_top_back = [230u8, 179, 77, 255];
    let left_bottom_front = [51u8, 128, 153, 255];
    let dir = uniform_pngs(
        "plume-six-way",
        &[
            ("tint.png", tint),
            ("rtb.png", right_top_back),
            ("lbf.png", left_bottom_front),
        ],
    );
    let decode = |t: [u8; 4]| t.map(|c| f64::from(c) / 255.0);
    let maps = [
        DVec4::from_array(decode(right_top_back)),
        DVec4::from_array(decode(left_bottom_front)),
    ];
    let texel = Some((decode(tint), maps));
    let texture = r#", texture: Some(Texture(file: "tint.png"))"#;
    let lit = r#"Lit(normals: SixWay(right_top_back: "rtb.png", left_bottom_front: "lbf.png"))"#;
    // From the right and a little above and behind; from the lower left and in front; a lamp
    // in front to the left; ambient light alone.
    for lights in [
        "Directional(direction: (-0.8, -0.3, 0.52))",
        "Directional(direction: (0.6, 0.5, -0.62)), Ambient(intensity: 0.2)",
        "Point(position: (-2.0, 0.5, 3.0), intensity: 6.0, range: 12.0)",
        "Ambient(color: (1.0, 0.5, 0.25), intensity: 0.8)",
    ] {
        let sim = probe_with(&gpu, lit, lights, texture, Some(&dir));
        assert_textured_lit_like_f64(&gpu, &sim, None, &[(0, 0), (10, -6)], texel);
    }
    // Light straight from the right reads the right map alone: 0.9 of it.
    let sim = probe_with(
        &gpu,
        lit,
        "Directional(direction: (-1.0, 0.0, 0.0))",
        texture,
        Some(&dir),
    );
    let centre = expected(&sim, &sim.compiled().ir.lights, 0, 0, texel);
    assert!(
        (centre[0] / 255.0 - COLOR[0] * 230.0 / 255.0).abs() < 1e-9,
        "{centre:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Many particles, turned, textured and lit by every kind of light, from a camera off to the
/// side: the raster draw agrees with the reference drawing, which builds each sprite's frame
/// on the CPU and lights it in world space, and the compute renderer with the raster draw.
#[test]
fn turned_textured_lit_sprites_agree_with_the_reference_drawing() {
    let gpu = gpu();
    let textures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects");
    for (orient, normals) in [
        ("Fixed((0.3, 1.0, 0.2))", "Sphere"),
        ("Camera", "Flat"),
        ("Velocity(stretch: 0.2, max_length: 2.0)", "Sphere"),
        (
            "Fixed((0.3, 1.0, 0.2))",
            r#"Map(file: "textures/smoke_normals.png")"#,
        ),
        ("Camera", r#"Map(file: "textures/smoke_normals.png")"#),
        (
            "Fixed((0.3, 1.0, 0.2))",
            r#"SixWay(right_top_back: "textures/smoke_rtb.png", left_bottom_front: "textures/smoke_lbf.png")"#,
        ),
    ] {
        let src = format!(
            r#"Effect(
    name: "lit-many",
    capacity: 400,
    seed: 5,
    emitters: [Emitter(burst: 400, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.5, 2.0)), lifetime: Some((4.0, 6.0)))],
    camera: Camera(eye: (6.0, 3.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 45.0),
    lights: [Directional(direction: (1.0, -1.0, 0.3), color: (1.0, 0.9, 0.8)),
             Point(position: (-1.0, 1.0, 2.0), color: (0.3, 0.5, 1.0), intensity: 2.0, range: 6.0),
             Ambient(intensity: 0.15)],
    render: Render(color: [(0.0, (0.7, 0.7, 0.7, 0.9)), (1.0, (0.5, 0.5, 0.5, 0.6))],
                   size: [(0.0, 0.5)], orient: {orient}, background: (0.05, 0.05, 0.05),
                   rotation: {rotation},
                   texture: Some(Texture(file: "textures/smoke.png", frames: (4, 4), play: OverLife)),
                   lit: Some(Lit(normals: {normals}, wrap: 0.2, emissive: 0.1))),
)"#,
            rotation = match orient.starts_with("Velocity") {
                true => "None",
                false => "Some(Rotation(angle: (0.0, 360.0), spin: (-90.0, 90.0)))",
            }
        );
        let options = plume::CompileOptions {
            base_dir: Some(textures.clone()),
            ..Default::default()
        };
        let effect = plume::compile_str(&src, &options)
            .unwrap_or_else(|e| panic!("{}", e.render("lit-many.ron", &src)));
        let mut sim = Effect::new(&gpu, effect).unwrap();
        sim.run(30, |_| {}).unwrap();
        let what = format!("lit {orient} {normals}");
        let raster = assert_draws_agree(&sim, 96, false, &what);
        // A textured quad may be opaque to its edge, where a pixel centre within the
        // rasteriser's vertex snapping is covered by one draw and not the other (the whole
        // texel apart): the compute renderer is held to 4 x 4 squares, as tests/render.rs holds it.
        let splat = splat_image(&sim, 96);
        let (mean, max, _) = differences(&raster, &splat, 2);
        let local = local_difference(&raster, &splat, 96, 4);
        assert!(
            mean < 0.3 && local < 4.0,
            "{what}: splat and raster differ: mean {mean}, max {max}, 4x4 {local}"
        );
    }
}
