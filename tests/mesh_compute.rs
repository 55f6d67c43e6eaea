//! Solid mesh particles (`blend: Opaque` or `Mask`) drawn by the compute renderer give the
//! raster draw's image, as `plume render` draws them (depth written, the nearest showing):
//! lit and unlit, turned and stretched, sorted and not, cut out below a `Mask` cutoff, with
//! the camera among them (triangles crossing the near plane), large (triangles of hundreds of
//! pixels, each covered by a workgroup), and over sprites drawn first (tests/meshes.rs draws
//! its nearest-cube test with it too); a glowing effect's meshes bloom as the raster draw's
//! do; and what the compute renderer leaves to the raster draw, it refuses with the reason.

mod common;

use std::path::PathBuf;

use common::*;
use plume::runtime::outputs::{ComputeOffscreen, Offscreen};
use plume::runtime::{Camera, Effect};

const SIDE: u32 = 96;

/// A directory of this test's own holding `cube.obj`, the unit cube (±0.5) wound
/// counter-clockwise seen from outside.
fn cube_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("plume-mesh-compute-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cube = common::meshes::box_obj([-0.5; 3], [0.5; 3]);
    std::fs::write(dir.join("cube.obj"), cube).unwrap();
    dir
}

fn compile_in(dir: &std::path::Path, src: &str) -> plume::CompiledEffect {
    let options = plume::CompileOptions {
        base_dir: Some(dir.to_path_buf()),
        ..Default::default()
    };
    plume::compile_str(src, &options).unwrap_or_else(|e| panic!("{}", e.render("mesh.ron", src)))
}

/// (The raster draw into a target whose solid meshes write depth, as `plume render` draws
/// them; the compute renderer's image), from the effect's camera.
fn both_draws(sim: &Effect, side: u32) -> (Vec<u8>, Vec<u8>) {
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let target = Offscreen::new(sim.gpu(), side, side).unwrap();
    let renderer = sim.renderer(&target.target_for(sim)).unwrap();
    assert!(renderer.writes_depth());
    let raster = target.render(sim, &renderer, &camera).unwrap();
    let mut compute =
        ComputeOffscreen::new(sim, side, side).expect("the compute renderer draws it");
    (raster, compute.render(sim, &camera).unwrap())
}

/// The compute renderer's image of `sim` against the raster draw's. The two cover a pixel
/// where its centre is inside a triangle, but the raster pipeline tests it in fixed point
/// (8 bits below the pixel) and the compute one in f32, so a centre within a rounding of an
/// edge may go to the triangle on the other side, or to the background: at most 1 pixel in
/// 200 may differ by more than 2 steps. Elsewhere the same triangle is shaded by the same
/// sums in f32 (its view-space point and face normal found another way, `dpdx` against the
/// edge weights), so a pixel may differ by a step of rounding: the mean difference stays
/// under 0.1 of a step. Returns the compute image and how many pixels it drew.
fn assert_agree(sim: &Effect, background: [u8; 3], what: &str) -> (Vec<u8>, usize) {
    let (raster, compute) = both_draws(sim, SIDE);
    let (mean, max, over) = differences(&raster, &compute, 2);
    let pixels = (SIDE * SIDE) as usize;
    assert!(
        mean < 0.1 && over * 200 < pixels,
        "{what}: compute vs raster: mean {mean:.4}, largest {max}, {over} channels over 2"
    );
    let drawn = compute.chunks(4).filter(|p| p[..3] != background).count();
    (compute, drawn)
}

#[test]
fn solid_meshes_drawn_by_the_compute_renderer_match_the_raster_draw() {
    let gpu = gpu();
    let dir = cube_dir("many");
    let ico = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects/meshes/ico.obj");
    let lit = "Some(Lit(wrap: 0.2, emissive: 0.1))";
    let cases = [
        // Lit cubes, turned and spinning, sorted: the nearest face shows.
        (
            "cube.obj".to_string(),
            "Fixed((0.3, 1.0, 0.2))",
            "Opaque",
            ", rotation: Some(Rotation(angle: (0.0, 360.0), spin: (-90.0, 90.0)))",
            lit,
            true,
            8.0,
        ),
        // Unlit spheres facing the camera, stretched, in slot order.
        (
            ico.display().to_string(),
            "Camera",
            "Opaque",
            ", size_y: Some([(0.0, 0.2), (1.0, 0.6)])",
            "None",
            false,
            8.0,
        ),
        // Lit spheres along their velocity, cut out as their alpha falls below 0.75.
        (
            ico.display().to_string(),
            "Velocity(stretch: 0.3, max_length: 2.0)",
            "Mask(0.75)",
            "",
            lit,
            true,
            8.0,
        ),
        // The camera among the cubes: some cross the near plane, some are behind it.
        (
            "cube.obj".to_string(),
            "Fixed((0.3, 1.0, 0.2))",
            "Opaque",
            "",
            lit,
            false,
            1.2,
        ),
        // Cubes 8 times as large: faces of hundreds of pixels, each covered by a workgroup,
        // more than the compute renderer's first list of big triangles holds (it grows and
        // draws again).
        (
            "cube.obj".to_string(),
            "Fixed((0.3, 1.0, 0.2))",
            "Opaque",
            ", size_by: Some(\"8.0\")",
            lit,
            true,
            8.0,
        ),
    ];
    for (mesh, orient, blend, extra, lit, sort, eye) in cases {
        let src = format!(
            r#"Effect(
    name: "meshes",
    capacity: 300,
    seed: 9,
    sort: {sort},
    emitters: [Emitter(burst: 300, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.5, 2.0)), lifetime: Some((4.0, 6.0)))],
    camera: Camera(eye: ({x:?}, {y:?}, {eye:?}), target: (0.0, 0.0, 0.0), fov_y: 60.0),
    lights: [Directional(direction: (1.0, -1.0, 0.3), color: (1.0, 0.9, 0.8)),
             Point(position: (-1.0, 1.0, 2.0), color: (0.3, 0.5, 1.0), intensity: 2.0, range: 6.0),
             Ambient(intensity: 0.15)],
    render: Render(color: [(0.0, (0.7, 0.7, 0.7, 0.9)), (1.0, (0.5, 0.4, 0.3, 0.6))],
                   size: [(0.0, 0.4), (1.0, 0.2)], orient: {orient}, blend: {blend},
                   background: (0.05, 0.05, 0.05), mesh: Some(ParticleMesh(file: "{mesh}")),
                   lit: {lit}{extra}),
)"#,
            x = eye * 0.75,
            y = eye * 0.375,
        );
        let mut sim = Effect::new(&gpu, compile_in(&dir, &src)).unwrap();
        sim.run(30, |_| {}).unwrap();
        let what = format!("{mesh} {orient} {blend} lit {lit} sort {sort} eye {eye}");
        assert!(ComputeOffscreen::draws(&sim.compiled().ir), "{what}");
        let (_, drawn) = assert_agree(&sim, [13, 13, 13], &what);
        assert!(drawn > 500, "{what}: only {drawn} pixels drawn");
    }
}

#[test]
fn meshes_over_sprites_drawn_first_match_the_raster_draw() {
    let gpu = gpu();
    let dir = cube_dir("graph");
    let src = r#"Effect(
    name: "glitter",
    capacity: 400,
    seed: 5,
    emitters: [Emitter(burst: 400, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.5),
                       velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (5.0, 2.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    lights: [Directional(direction: (1.0, -1.0, -0.5)), Ambient(intensity: 0.3)],
    render: Render(color: [(0.0, (1.0, 0.8, 0.3, 0.8))], size: [(0.0, 0.3)], blend: Alpha,
                   background: (0.0, 0.0, 0.1)),
    groups: [Group(
        name: "cubes",
        capacity: 40,
        emitters: [Emitter(burst: 40, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                           velocity: Constant((0.0, 0.0, 0.0)))],
        render: Render(color: [(0.0, (0.4, 0.7, 0.9, 1.0))], size: [(0.0, 0.5)], blend: Opaque,
                       orient: Fixed((0.2, 1.0, 0.1)), mesh: Some(ParticleMesh(file: "cube.obj")),
                       lit: Some(Lit())),
    )],
)"#;
    let options = plume::CompileOptions {
        base_dir: Some(dir.clone()),
        ..Default::default()
    };
    let graph = plume::compiler::graph::compile_graph_str(src, &options)
        .unwrap_or_else(|e| panic!("{}", e.render("glitter.ron", src)));
    let mut sim = Effect::from_graph(&gpu, graph).unwrap();
    sim.run(2, |_| {}).unwrap();
    let irs: Vec<_> = (0..sim.group_names().len())
        .map(|g| &sim.group_compiled(g).unwrap().ir)
        .collect();
    assert_eq!(ComputeOffscreen::why_not(&irs), None);
    let (_, drawn) = assert_agree(&sim, [0, 0, 26], "sprites then meshes");
    assert!(drawn > 1500, "only {drawn} pixels drawn");
}

#[test]
fn the_compute_renderer_refuses_what_it_leaves_to_the_raster_draw() {
    let dir = cube_dir("refused");
    let effect = |blend: &str, glow: &str| {
        compile_in(
            &dir,
            &format!(
                r#"Effect(name: "cubes", capacity: 8,
    emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 1.0)], blend: {blend},
                   mesh: Some(ParticleMesh(file: "cube.obj")){glow}))"#
            ),
        )
    };
    for (blend, glow, why) in [("Alpha", "", "solid"), ("Additive", "", "solid")] {
        let compiled = effect(blend, glow);
        let why_not = ComputeOffscreen::why_not(&[&compiled.ir]);
        assert!(
            why_not.is_some_and(|w| w.contains(why)),
            "{blend}{glow}: {why_not:?}"
        );
    }
    let solid = effect("Opaque", "");
    assert_eq!(ComputeOffscreen::why_not(&[&solid.ir]), None);
    let glowing = effect("Opaque", GLOW);
    assert_eq!(ComputeOffscreen::why_not(&[&glowing.ir]), None);
    let sprites = plume::compile_str(
        r#"Effect(name: "dots", capacity: 8,
    emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))])"#,
        &Default::default(),
    )
    .unwrap();
    let after = ComputeOffscreen::why_not(&[&solid.ir, &sprites.ir]);
    assert!(after.is_some_and(|w| w.contains("after mesh")), "{after:?}");
}

/// The host's depth format in [`host_draws`].
const HOST_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// `sim` drawn for a host as the embedding API draws it, over a depth buffer holding a wall
/// `wall` metres in front of the camera (None: the far plane; `camera`'s projection may be
/// reversed: `compare` is then `Greater`): by the raster renderer writing depth into it, and
/// by the compute renderer testing its copy of it, or where `composite_at` gives a distance,
/// not reading it but put over the host at that distance's depth
/// (`EffectRenderer::set_composite_depth`). (raster, compute) images.
fn host_draws(
    sim: &Effect,
    camera: &Camera,
    compare: wgpu::CompareFunction,
    (wall, composite_at): (Option<f32>, Option<f32>),
) -> (Vec<u8>, Vec<u8>) {
    let gpu = sim.gpu();
    let target = Offscreen::new(gpu, SIDE, SIDE).unwrap();
    let ndc = |d: f32| {
        let clip = camera.proj * glam::Vec4::new(0.0, 0.0, -d, 1.0);
        clip.z / clip.w
    };
    let wall_depth = match wall {
        Some(d) => ndc(d),
        None if compare == wgpu::CompareFunction::Greater => 0.0,
        None => 1.0,
    };
    let host = plume::runtime::DrawTarget::new(plume::runtime::outputs::FORMAT)
        .with_depth_compare(HOST_DEPTH, compare);
    let draw = |compute: bool| {
        let depth = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("host depth"),
            size: wgpu::Extent3d {
                width: SIDE,
                height: SIDE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: HOST_DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = depth.create_view(&Default::default());
        let mut renderer = match compute {
            true => sim.compute_renderer(&host, SIDE, SIDE).unwrap(),
            false => sim.renderer(&host.with_depth_writes(true)).unwrap(),
        };
        assert_eq!(renderer.is_compute(), compute);
        match (compute, composite_at) {
            (true, None) => renderer.set_scene_depth(&view),
            (true, Some(d)) => renderer.set_composite_depth(Some(ndc(d))),
            (false, _) => {}
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        // The host's geometry: a wall filling its depth buffer.
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("wall"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wall_depth),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        sim.prepare_draw(&mut encoder, &renderer, camera).unwrap();
        {
            // Writable for the raster draw's meshes; the compute one tested its copy already.
            let depth_ops = (!compute).then_some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("particles"),
                color_attachments: &[Some(target.attachment(glam::DVec3::splat(0.05)))],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops,
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            renderer.draw(&mut pass);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error().unwrap();
        target.read().unwrap()
    };
    (draw(false), draw(true))
}

#[test]
fn over_a_hosts_depth_the_compute_renderer_draws_meshes_as_the_raster_one() {
    let gpu = gpu();
    let dir = cube_dir("host");
    let src = r#"Effect(
    name: "cubes",
    capacity: 200,
    seed: 4,
    sort: true,
    emitters: [Emitter(burst: 200, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.2, 0.6)))],
    camera: Camera(eye: (0.0, 1.0, 7.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    lights: [Directional(direction: (1.0, -1.0, -0.4)), Ambient(intensity: 0.25)],
    render: Render(color: [(0.0, (0.9, 0.6, 0.3, 1.0))], size: [(0.0, 0.45)], blend: Opaque,
                   orient: Fixed((0.3, 1.0, 0.2)), mesh: Some(ParticleMesh(file: "cube.obj")),
                   lit: Some(Lit(wrap: 0.3))),
)"#;
    let mut sim = Effect::new(&gpu, compile_in(&dir, src)).unwrap();
    sim.run(10, |_| {}).unwrap();
    let standard = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let reversed = Camera {
        proj: glam::Mat4::perspective_infinite_reverse_rh(50f32.to_radians(), 1.0, 0.1),
        ..standard
    };
    let background = [13, 13, 13];
    for (camera, compare, what) in [
        (&standard, wgpu::CompareFunction::Less, "standard depth"),
        (&reversed, wgpu::CompareFunction::Greater, "reversed depth"),
    ] {
        // The wall 6 m away cuts through the cubes: those behind it are hidden.
        let (raster, compute) = host_draws(&sim, camera, compare, (Some(6.0), None));
        let (open_raster, open_compute) = host_draws(&sim, camera, compare, (None, None));
        let drawn = |image: &[u8]| image.chunks(4).filter(|p| p[..3] != background).count();
        assert!(
            drawn(&raster) > 500 && drawn(&raster) + 200 < drawn(&open_raster),
            "{what}: the wall hides cubes: {} pixels drawn, {} without it",
            drawn(&raster),
            drawn(&open_raster)
        );
        let (mean, max, over) = differences(&raster, &compute, 2);
        assert!(
            mean < 0.1 && over * 200 < (SIDE * SIDE) as usize,
            "{what}: compute vs raster over the host's depth: mean {mean:.4}, largest {max}, {over} channels over 2"
        );
        // Not reading the host's depth, the compute renderer's image put at one depth: behind
        // the wall (the cubes' centre, 7 m away) nothing shows; in front (5 m) all of it,
        // as with no wall.
        let (_, behind) = host_draws(&sim, camera, compare, (Some(6.0), Some(7.1)));
        assert_eq!(drawn(&behind), 0, "{what}: the image put behind the wall");
        let (_, before) = host_draws(&sim, camera, compare, (Some(6.0), Some(5.0)));
        assert_eq!(
            before, open_compute,
            "{what}: the image put before the wall"
        );
    }
}

#[test]
fn meshes_at_the_extremes_draw_as_the_raster_draw_does() {
    // Cubes at places a renderer of triangles finds hard, one effect each, seen from 5 m
    // along +z: one of size 0 (nothing drawn), one around the eye (every face a back face),
    // one whose faces cross the near plane and the eye plane, one filling the view from just
    // in front, one 200 m across (faces of thousands of pixels), one far beyond the far
    // plane, one at a coordinate f32 barely holds.
    let gpu = gpu();
    let dir = cube_dir("extremes");
    for (at, size, drawn) in [
        ((0.0, 0.0, 0.0), 0.0, false),
        ((0.0, 0.0, 5.0), 2.0, false),
        ((1.3, 0.0, 4.8), 2.0, true),
        ((0.0, 0.0, 3.0), 2.0, true),
        ((0.0, 0.0, -150.0), 200.0, true),
        ((0.0, 0.0, -1.0e7), 1.0, false),
        ((3.0e38, 0.0, 0.0), 1.0, false),
    ] {
        let src = format!(
            r#"Effect(
    name: "extreme",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point({at:?}), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 5.0), target: (0.0, 0.0, 0.0), fov_y: 60.0),
    lights: [Directional(direction: (1.0, -1.0, -0.5)), Ambient(intensity: 0.3)],
    render: Render(color: [(0.0, (0.9, 0.6, 0.3, 1.0))], size: [(0.0, {size:?})], blend: Opaque,
                   orient: Fixed((0.2, 1.0, 0.3)), background: (0.05, 0.05, 0.05),
                   mesh: Some(ParticleMesh(file: "cube.obj")), lit: Some(Lit())),
)"#
        );
        let mut sim = Effect::new(&gpu, compile_in(&dir, &src)).unwrap();
        sim.run(1, |_| {}).unwrap();
        let what = format!("a cube {size} m across at {at:?}");
        let (_, pixels) = assert_agree(&sim, [13, 13, 13], &what);
        assert_eq!(pixels > 0, drawn, "{what}: {pixels} pixels drawn");
    }
}

/// A glow whose threshold the lit cubes' light passes.
const GLOW: &str = ", glow: Some(Glow(threshold: 0.5, strength: 2.0, radius: 0.02))";

#[test]
fn a_glowing_effects_meshes_bloom_as_the_raster_draws_do() {
    let gpu = gpu();
    let dir = cube_dir("glow");
    let src = format!(
        r#"Effect(
    name: "hot cubes",
    capacity: 60,
    seed: 2,
    emitters: [Emitter(burst: 60, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 2.0),
                       velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (4.0, 2.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    lights: [Directional(direction: (1.0, -1.0, -0.5), intensity: 1.5), Ambient(intensity: 0.3)],
    render: Render(color: [(0.0, (1.0, 0.7, 0.4, 1.0))], size: [(0.0, 0.5)], blend: Opaque,
                   orient: Fixed((0.2, 1.0, 0.1)), background: (0.0, 0.0, 0.0),
                   mesh: Some(ParticleMesh(file: "cube.obj")), lit: Some(Lit()){GLOW}),
)"#
    );
    let mut sim = Effect::new(&gpu, compile_in(&dir, &src)).unwrap();
    sim.run(2, |_| {}).unwrap();
    let glow = sim.compiled().ir.render.glow.unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let target = Offscreen::with_glow(&gpu, SIDE, SIDE, Some(&glow)).unwrap();
    let renderer = sim.renderer(&target.target_for(&sim)).unwrap();
    let raster = target.render(&sim, &renderer, &camera).unwrap();
    let mut compute = ComputeOffscreen::new(&sim, SIDE, SIDE).unwrap();
    let computed = compute.render(&sim, &camera).unwrap();
    let (mean, max, over) = differences(&raster, &computed, 2);
    assert!(
        mean < 0.1 && over * 200 < (SIDE * SIDE) as usize,
        "glowing meshes, compute vs raster: mean {mean:.4}, largest {max}, {over} channels over 2"
    );
    let lit = computed.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    assert!(lit > 1000, "only {lit} pixels lit");
}
