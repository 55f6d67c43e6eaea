//! Mesh particles (`render.mesh`) on llvmpipe: a lit cube's front face is as bright as
//! Lambert's law says (its back faces culled), and lit per pixel under a point light close to
//! it; a glTF mesh is drawn as its OBJ twin; meshes turned, stretched, sorted, lit and unlit (drawn indexed) match
//! the CPU-fed reference drawing (each mesh placed and lit in f64), and the compute renderer
//! leaves blended ones to the raster draw; the nearest of two opaque cubes shows in both
//! renderers.

mod common;

use std::path::PathBuf;

use common::*;
use glam::DVec3;
use plume::runtime::outputs::{ComputeOffscreen, Offscreen};
use plume::runtime::Effect;

/// Odd, so that the image's centre is a pixel's centre.
const SIDE: u32 = 65;

/// The unit cube's faces, front (+z) first and back (−z) last, each by its corners
/// counter-clockwise seen from outside, counted from 1 as OBJ does: corner k has x from bit 0
/// of k − 1, y from bit 1, z from bit 2.
const CUBE_FACES: [[u32; 4]; 6] = [
    [5, 6, 8, 7],
    [2, 4, 8, 6],
    [1, 3, 4, 2],
    [1, 5, 7, 3],
    [3, 7, 8, 4],
    [1, 2, 6, 5],
];

/// A directory of this test's own holding `cube.obj`: the unit cube (±0.5), wound
/// counter-clockwise seen from outside, its front face (+z) first and its back face (−z)
/// last, so that a back face drawn would cover the front one.
fn cube_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-meshes-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = String::new();
    for k in 0..8 {
        let c = |bit: u32| if k >> bit & 1 == 1 { 0.5 } else { -0.5 };
        obj += &format!("v {} {} {}\n", c(0), c(1), c(2));
    }
    for face in CUBE_FACES {
        obj += &format!("f {} {} {} {}\n", face[0], face[1], face[2], face[3]);
    }
    std::fs::write(dir.join("cube.obj"), obj).unwrap();
    dir
}

/// `cube.obj` of `dir` again as `cube.gltf` with its buffer in `cube.bin`: the same corners,
/// and each face's quad fanned into two triangles as OBJ faces are.
fn write_cube_gltf(dir: &std::path::Path) {
    let mut bin: Vec<u8> = (0..8u32)
        .flat_map(|k| [0, 1, 2].map(|bit| if k >> bit & 1 == 1 { 0.5f32 } else { -0.5 }))
        .flat_map(f32::to_le_bytes)
        .collect();
    let indices: Vec<u32> = CUBE_FACES
        .iter()
        .flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]].map(|i| i - 1))
        .collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("cube.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{"uri": "cube.bin", "byteLength": {}}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 96}}, {{"buffer": 0, "byteOffset": 96, "byteLength": 144}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                  "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}},
                {{"bufferView": 1, "componentType": 5125, "count": 36, "type": "SCALAR"}}]}}"#,
        bin.len()
    );
    std::fs::write(dir.join("cube.gltf"), json).unwrap();
}

fn compile_in(dir: &std::path::Path, src: &str) -> plume::CompiledEffect {
    let options = plume::CompileOptions {
        base_dir: Some(dir.to_path_buf()),
        ..Default::default()
    };
    plume::compile_str(src, &options).unwrap_or_else(|e| panic!("{}", e.render("mesh.ron", src)))
}

#[test]
fn a_lit_cubes_front_face_follows_lamberts_law() {
    // A 2 m cube 10 m in front of the camera, its front face toward it, lit by a light 60
    // degrees off that face's normal: the face receives ambient 0.1 plus cos 60 = 0.5.
    let gpu = gpu();
    let dir = cube_dir("lambert");
    let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
    let src = format!(
        r#"Effect(
    name: "cube",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    lights: [Directional(direction: ({}, 0.0, {})), Ambient(intensity: 0.1)],
    render: Render(color: [(0.0, (0.8, 0.6, 0.4, 1.0))], size: [(0.0, 2.0)], blend: Opaque,
                   background: (0.0, 0.0, 0.0), mesh: Some(ParticleMesh(file: "cube.obj")),
                   lit: Some(Lit())),
)"#,
        -s, -c
    );
    let effect = compile_in(&dir, &src);
    let lights = effect.ir.lights.clone();
    let lit = effect.ir.render.lit.clone().unwrap();
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let want = lit.shade(
        DVec3::new(0.8, 0.6, 0.4),
        lights.received(DVec3::Z, DVec3::new(0.0, 0.0, 1.0), 0.0),
    );
    assert!(
        (want - DVec3::new(0.48, 0.36, 0.24)).length() < 1e-12,
        "{want}"
    );
    let (gpu_img, cpu_img) = draw_and_reference(&sim, SIDE);
    // The cube's front face spans 2 m of the 7.28 m the image shows at 9 m: the middle
    // eighth of the image is all front face.
    for (name, img) in [("raster", &gpu_img), ("reference", &cpu_img)] {
        for (dx, dy) in [(0i32, 0i32), (3, 0), (-3, 2), (0, -3)] {
            let (x, y) = ((SIDE / 2) as i32 + dx, (SIDE / 2) as i32 + dy);
            let k = 4 * (y as u32 * SIDE + x as u32) as usize;
            for ch in 0..3 {
                let expect = want[ch] * 255.0;
                let got = f64::from(img[k + ch]);
                assert!(
                    (got - expect).abs() <= 1.0,
                    "{name} ({dx}, {dy}) channel {ch}: got {got}, want {expect:.2}"
                );
            }
        }
    }
}

#[test]
fn a_point_light_close_to_a_face_lights_it_per_pixel() {
    // The 2 m cube's front face (z = 1) with a point light 0.5 m in front of its middle: the
    // middle receives 16 times the light its corners do, at nearly right angles. Lit per
    // pixel, the middle pixel has what Lambert's law gives there; blended from the corners it
    // would be as dark as they are.
    let gpu = gpu();
    let dir = cube_dir("point");
    let src = r#"Effect(
    name: "cube",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    lights: [Point(position: (0.0, 0.0, 1.5), intensity: 0.1, range: 20.0), Ambient(intensity: 0.1)],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 2.0)], blend: Opaque,
                   background: (0.0, 0.0, 0.0), mesh: Some(ParticleMesh(file: "cube.obj")),
                   lit: Some(Lit())),
)"#;
    let effect = compile_in(&dir, src);
    let lights = effect.ir.lights.clone();
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let light_at = |x: f64, y: f64| lights.received(DVec3::Z, DVec3::new(x, y, 1.0), 0.0).x;
    let middle = light_at(0.0, 0.0);
    let corners = light_at(1.0, 1.0);
    assert!(
        middle > 0.45 && middle < 0.95 && corners < 0.12,
        "{middle} {corners}"
    );
    let (gpu_img, cpu_img) = draw_and_reference(&sim, SIDE);
    let k = 4 * (SIDE / 2 * SIDE + SIDE / 2) as usize;
    for (name, img) in [("raster", &gpu_img), ("reference", &cpu_img)] {
        for ch in 0..3 {
            let got = f64::from(img[k + ch]);
            assert!(
                (got - middle * 255.0).abs() <= 1.0,
                "{name} channel {ch}: got {got}, want {:.2}",
                middle * 255.0
            );
        }
    }
    let (mean, max, over) = differences(&gpu_img, &cpu_img, 4);
    assert!(
        mean < 0.5 && over * 100 < gpu_img.len(),
        "mean {mean}, max {max}, {over} over 4"
    );
}

#[test]
fn turned_sorted_lit_and_unlit_meshes_agree_with_the_reference_drawing() {
    let gpu = gpu();
    let dir = cube_dir("many");
    let ico = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects/meshes/ico.obj");
    let lit = "Some(Lit(wrap: 0.2, emissive: 0.1))";
    // Unlit meshes are drawn indexed (each shared corner once): sorted through the indirect
    // indexed draw, unsorted through the direct one.
    for (mesh, orient, blend, extra, lit, sort) in [
        (
            "cube.obj".to_string(),
            "Velocity(stretch: 0.3, max_length: 2.0)",
            "Alpha",
            "",
            lit,
            true,
        ),
        (
            "cube.obj".to_string(),
            "Fixed((0.3, 1.0, 0.2))",
            "Opaque",
            ", rotation: Some(Rotation(angle: (0.0, 360.0), spin: (-90.0, 90.0)))",
            lit,
            true,
        ),
        (
            ico.display().to_string(),
            "Camera",
            "Additive",
            ", size_y: Some([(0.0, 0.2), (1.0, 0.6)])",
            lit,
            true,
        ),
        (
            ico.display().to_string(),
            "Velocity(stretch: 0.3, max_length: 2.0)",
            "Alpha",
            "",
            "None",
            true,
        ),
        (
            "cube.obj".to_string(),
            "Fixed((0.3, 1.0, 0.2))",
            "Additive",
            ", rotation: Some(Rotation(angle: (0.0, 360.0), spin: (-90.0, 90.0)))",
            "None",
            false,
        ),
    ] {
        let src = format!(
            r#"Effect(
    name: "meshes",
    capacity: 300,
    seed: 9,
    sort: {sort},
    emitters: [Emitter(burst: 300, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.5, 2.0)), lifetime: Some((4.0, 6.0)))],
    camera: Camera(eye: (6.0, 3.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 45.0),
    lights: [Directional(direction: (1.0, -1.0, 0.3), color: (1.0, 0.9, 0.8)),
             Point(position: (-1.0, 1.0, 2.0), color: (0.3, 0.5, 1.0), intensity: 2.0, range: 6.0),
             Ambient(intensity: 0.15)],
    render: Render(color: [(0.0, (0.7, 0.7, 0.7, 0.9)), (1.0, (0.5, 0.4, 0.3, 0.6))],
                   size: [(0.0, 0.4), (1.0, 0.2)], orient: {orient}, blend: {blend},
                   background: (0.05, 0.05, 0.05), mesh: Some(ParticleMesh(file: "{mesh}")),
                   lit: {lit}{extra}),
)"#
        );
        let mut sim = Effect::new(&gpu, compile_in(&dir, &src)).unwrap();
        sim.run(30, |_| {}).unwrap();
        let what = format!("{mesh} {orient} {blend} lit {lit} sort {sort}");
        // Solid meshes the compute renderer draws too (tests/mesh_compute.rs), blended ones not.
        assert_eq!(
            ComputeOffscreen::draws(&sim.compiled().ir),
            blend == "Opaque",
            "{what}: which meshes the compute renderer draws"
        );
        let raster = assert_draws_agree(&sim, 128, false, &what);
        let lit = raster.chunks(4).filter(|p| p[..3] != [13, 13, 13]).count();
        assert!(lit > 2000, "{what}: only {lit} pixels drawn");
    }
}

#[test]
fn a_gltf_mesh_is_drawn_as_its_obj_twin() {
    let gpu = gpu();
    let dir = cube_dir("gltf");
    write_cube_gltf(&dir);
    let src = |file: &str| {
        format!(
            r#"Effect(
    name: "cubes",
    capacity: 40,
    seed: 3,
    emitters: [Emitter(burst: 40, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.5, 1.0)))],
    camera: Camera(eye: (6.0, 3.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 45.0),
    lights: [Directional(direction: (1.0, -1.0, 0.3)), Ambient(intensity: 0.2)],
    render: Render(color: [(0.0, (0.8, 0.6, 0.4, 1.0))], size: [(0.0, 0.5)], blend: Opaque,
                   orient: Fixed((0.3, 1.0, 0.2)), mesh: Some(ParticleMesh(file: "{file}")),
                   lit: Some(Lit())),
)"#
        )
    };
    let obj = compile_in(&dir, &src("cube.obj"));
    let gltf = compile_in(&dir, &src("cube.gltf"));
    let buffers = |e: &plume::CompiledEffect| e.ir.render.mesh.as_ref().unwrap().buffers();
    assert_eq!(buffers(&gltf), buffers(&obj));
    let image = |effect| {
        let mut sim = Effect::new(&gpu, effect).unwrap();
        sim.run(10, |_| {}).unwrap();
        draw_and_reference(&sim, SIDE).0
    };
    let (from_obj, from_gltf) = (image(obj), image(gltf));
    assert!(from_obj.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count() > 200);
    assert_eq!(from_gltf, from_obj);
}

#[test]
fn a_mesh_effect_steps_without_its_file_and_its_draw_says_why_not() {
    let gpu = gpu();
    let src = r#"Effect(
    name: "no-mesh",
    capacity: 4,
    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))],
    render: Render(mesh: Some(ParticleMesh(file: "nowhere/gone.obj"))),
)"#;
    let options = plume::CompileOptions {
        step_only: true,
        ..Default::default()
    };
    let effect = plume::compile_str(src, &options).unwrap();
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(3, |_| {}).unwrap();
    assert_eq!(sim.records().unwrap().len(), 4);
    let target = Offscreen::new(sim.gpu(), 16, 16).unwrap();
    let error = match plume::runtime::oracle::group_renderer(&sim, 0, &target.target()) {
        Ok(_) => panic!("drew a mesh it never read"),
        Err(e) => e.to_string(),
    };
    assert!(
        error.contains("render.mesh.file") && error.contains("gone.obj"),
        "{error}"
    );
}

#[test]
fn opaque_meshes_write_depth_so_the_nearest_shows_whatever_the_draw_order() {
    // Two cubes on the camera's axis, coloured by depth: a red one 2 m nearer and a larger
    // blue one 2 m farther, the near one spawned first and then last. With written depth the
    // red one is in front either way; without, whichever is drawn last covers the other.
    let gpu = gpu();
    let dir = cube_dir("depth");
    let mut plain_centres = Vec::new();
    for zs in [(2.0, -2.0), (-2.0, 2.0)] {
        let src = format!(
            r#"Effect(
    name: "cubes",
    capacity: 2,
    emitters: [
        Emitter(burst: 1, shape: Point((0.0, 0.0, {:?})), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(burst: 1, shape: Point((0.0, 0.0, {:?})), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 2.0)], blend: Opaque,
                   background: (0.0, 0.0, 0.0), mesh: Some(ParticleMesh(file: "cube.obj")),
                   size_by: Some("1.5 - 0.25 * x.z"),
                   color_by: Some("vec3(0.25 * (x.z + 2.0), 0.0, 0.25 * (2.0 - x.z))")),
)"#,
            zs.0, zs.1
        );
        let mut sim = Effect::new(&gpu, compile_in(&dir, &src)).unwrap();
        sim.run(1, |_| {}).unwrap();
        let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
        let camera = target.effect_camera(&sim);
        let pixel = |image: &[u8], dx: u32| {
            let k = 4 * ((SIDE / 2) * SIDE + SIDE / 2 + dx) as usize;
            [image[k], image[k + 1], image[k + 2]]
        };
        let with_depth = target.target_for(&sim);
        assert!(with_depth.writes_depth && with_depth.depth.is_some());
        let renderer = sim.renderer(&with_depth).unwrap();
        assert!(renderer.writes_depth());
        let image = target.render(&sim, &renderer, &camera).unwrap();
        assert_eq!(
            pixel(&image, 0),
            [255, 0, 0],
            "{zs:?}: the near red cube in front"
        );
        // The far cube's rim, outside the near one's image, is drawn too: at 10 m the 4 m
        // cube spans ±17.8 pixels, the near 2 m one at 7 m ±12.7.
        assert_eq!(pixel(&image, 15), [0, 0, 255], "{zs:?}: the far cube's rim");
        // The compute renderer keeps the nearest triangle a pixel too.
        let computed = ComputeOffscreen::new(&sim, SIDE, SIDE)
            .unwrap()
            .render(&sim, &camera)
            .unwrap();
        assert_eq!(
            [pixel(&computed, 0), pixel(&computed, 15)],
            [[255, 0, 0], [0, 0, 255]],
            "{zs:?}: the compute renderer's near red cube in front, the far one's rim"
        );
        // Without depth writes (the plain target), in the order drawn.
        let plain = sim.renderer(&target.target()).unwrap();
        assert!(!plain.writes_depth());
        plain_centres.push(pixel(&target.render(&sim, &plain, &camera).unwrap(), 0));
    }
    assert_eq!(
        plain_centres.iter().filter(|c| **c == [0, 0, 255]).count(),
        1,
        "without depth, one order shows the far cube over the near one: {plain_centres:?}"
    );
}
