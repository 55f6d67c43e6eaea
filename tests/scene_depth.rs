//! `SceneDepth`: particles collide with a depth image the host draws (here a floor and a box,
//! drawn by the runtime's scene pass into a Depth32Float buffer, as a host's renderer would),
//! through `Effect::set_scene_depth`; the f64 reference collides with the same image read back.

mod common;

use std::sync::Arc;

use common::*;
use glam::DVec3;
use plume::compiler::colliders::scene_depth::{DepthCamera, DepthImage};
use plume::compiler::reference::{ParticleRecord, ReferenceSim};
use plume::runtime::outputs::{Offscreen, Scene};
use plume::runtime::{Camera, Effect};

const SIDE: u32 = 192;
const BOX_MIN: [f64; 3] = [-0.5, 0.0, -0.5];
const BOX_MAX: [f64; 3] = [0.5, 1.0, 0.5];
const EYE: DVec3 = DVec3::new(0.0, 4.0, 5.0);
const STEPS: u64 = 150;

/// The triangles of an axis-aligned box.
fn cuboid(min: [f64; 3], max: [f64; 3]) -> Vec<[DVec3; 3]> {
    let c = |k: usize| {
        DVec3::new(
            if k & 1 == 1 { max[0] } else { min[0] },
            if k & 2 == 2 { max[1] } else { min[1] },
            if k & 4 == 4 { max[2] } else { min[2] },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
    ];
    quads
        .iter()
        .flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]])
        .collect()
}

/// 64 particles dropped from 2.5 m on an 8 x 8 grid over the floor, four of them over the box.
fn effect(restitution: f64) -> String {
    effect_at_speed(restitution, 0.0)
}

/// [`effect`] with the particles thrown down at `speed` (m/s).
fn effect_at_speed(restitution: f64, speed: f64) -> String {
    format!(
        r#"Effect(
    name: "drop",
    capacity: 64,
    seed: 3,
    emitters: [Emitter(burst: 64, shape: Grid(min: (-1.75, 2.5, -1.75), max: (1.75, 2.5, 1.75), counts: (8, 1, 8)), velocity: Constant((0.0, -{speed}, 0.0)), lifetime: Some((100.0, 100.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    collide: [SceneDepth(thickness: 0.3, restitution: {restitution}, friction: 0.5)],
    camera: Camera(eye: (0.0, 4.0, 5.0), target: (0.0, 0.0, 0.0), fov_y: 45.0),
)"#
    )
}

/// Where the segment from `eye` to `p` enters the box, if it does before reaching `p`.
fn box_hides(p: DVec3) -> bool {
    let d = p - EYE;
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64 - 1e-9);
    for axis in 0..3 {
        let (lo, hi) = (BOX_MIN[axis] - EYE[axis], BOX_MAX[axis] - EYE[axis]);
        if d[axis].abs() < 1e-12 {
            if lo > 0.0 || hi < 0.0 {
                return false;
            }
            continue;
        }
        let (a, b) = (lo / d[axis], hi / d[axis]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    t0 < t1
}

/// The scene drawn from the effect's camera, the GPU run after `STEPS` steps against it, and
/// the image and camera the reference needs.
fn run(restitution: f64) -> (Vec<ParticleRecord>, Arc<DepthImage>, plume::CompiledEffect) {
    run_source(&effect(restitution), true)
}

/// [`run`] of `source`, with or without giving the effect the scene's depth.
fn run_source(
    source: &str,
    give_depth: bool,
) -> (Vec<ParticleRecord>, Arc<DepthImage>, plume::CompiledEffect) {
    let compiled = compile(source);
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, compiled.clone()).unwrap();
    assert!(sim.collides_with_scene_depth());
    let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
    let camera: Camera = target.effect_camera(&sim);
    let mut triangles = cuboid([-4.0, -0.2, -4.0], [4.0, 0.0, 4.0]);
    triangles.extend(cuboid(BOX_MIN, BOX_MAX));
    let scene = Scene::new(&gpu, &triangles, target.target().color_format, (SIDE, SIDE))
        .unwrap()
        .unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    scene.record(&mut encoder, target.attachment(DVec3::ZERO), &camera);
    if give_depth {
        sim.set_scene_depth(
            &mut encoder,
            scene.depth_texture(),
            camera.view,
            camera.proj,
        )
        .unwrap();
    }
    gpu.queue.submit([encoder.finish()]);
    sim.run(STEPS, |_| {}).unwrap();
    let image = Arc::new(DepthImage {
        width: SIDE,
        height: SIDE,
        depth: scene.read_depth().unwrap(),
        camera: DepthCamera::new(camera.view, camera.proj).unwrap(),
    });
    (sim.records().unwrap(), image, compiled)
}

/// How far above a surface a particle may rest. The surface on a particle's ray is the depth
/// interpolated between the four nearest pixel centres, exact for a plane but for the depth's
/// f32 rounding: at the farthest landing point (8.1 m, depth 1 - 0.05 / 8.1) one ulp of depth is
/// 7.8e-5 m of distance. The collider takes the surface 8 ulps nearer (its tolerance) and the
/// contact adds 16 f32 ulps of the position, so a resting particle sits about 10 ulps of depth
/// (7.8e-4 m) in front of it, along the view ray; the bound is twice that. (Measured on
/// llvmpipe: at most 6.0e-4 m.)
const REST_TOLERANCE: f64 = 1.6e-3;

/// How far the GPU and the reference may part with bounces (restitution 0.4). They read the
/// same image but round a point that projects near a pixel's edge onto different pixels, and
/// the depth's rounding tilts the normal they take from neighbouring pixels (7.8e-5 m over the
/// 3.3 cm between pixel centres: 2.4 mrad), which over a few bounces at up to 7 m/s moves a
/// particle sideways by millimetres. (Measured on llvmpipe: at most 5.8e-3 m.)
const BOUNCE_TOLERANCE: f64 = 1e-2;

#[test]
fn particles_stop_on_the_surfaces_the_camera_sees() {
    let (records, _, _) = run(0.0);
    assert_eq!(records.len(), 64, "every particle is alive");
    let (mut on_floor, mut on_box, mut hidden) = (0, 0, 0);
    let mut worst_rest: f64 = 0.0;
    for r in &records {
        let p = r.position;
        assert!(p.is_finite(), "{p}");
        // Dropped straight down with no bounce, a particle that lands stays in its column.
        let in_column = |v: f64| {
            let off = (v.abs() - 0.25).rem_euclid(0.5);
            off.min(0.5 - off) < 1e-2
        };
        let over_box = p.x.abs() < 0.5 && p.z.abs() < 0.5 && p.y > 0.5;
        if over_box {
            assert!((p.y - 1.0).abs() < REST_TOLERANCE, "on the box top: {p}");
            worst_rest = worst_rest.max((p.y - 1.0).abs());
            assert!(in_column(p.x) && in_column(p.z), "{p} left its column");
            on_box += 1;
        } else if box_hides(DVec3::new(p.x, 0.0, p.z)) {
            // The floor behind the box is not in the image: such a particle passes (or stops
            // on the box's back in the image, as seen from the camera); either way it is not
            // checked here.
            hidden += 1;
        } else {
            assert!(p.y.abs() < REST_TOLERANCE, "on the floor: {p}");
            worst_rest = worst_rest.max(p.y.abs());
            assert!(in_column(p.x) && in_column(p.z), "{p} left its column");
            on_floor += 1;
        }
    }
    eprintln!("largest distance from the surface at rest: {worst_rest:.2e} m");
    assert_eq!(on_box, 4, "the four columns over the box");
    assert!(on_floor >= 50, "{on_floor} on the floor, {hidden} hidden");
}

#[test]
fn the_reference_collides_with_the_same_image() {
    let (gpu_records, image, compiled) = run(0.4);
    let mut reference = ReferenceSim::new(&compiled.ir);
    reference.set_scene_depth(&image);
    reference.run(STEPS);
    let cpu_records = reference.records();
    assert_eq!(gpu_records.len(), cpu_records.len());
    let mut worst: f64 = 0.0;
    for (g, c) in gpu_records.iter().zip(&cpu_records) {
        assert_eq!(g.id, c.id);
        worst = worst.max((g.position - c.position).length());
    }
    eprintln!("largest GPU - reference distance: {worst:.3e} m");
    assert!(worst < BOUNCE_TOLERANCE, "{worst}");
}

/// Resting heights: how many particles rest on the floor (y within the tolerance of 0) and on
/// the box (of 1).
fn resting(records: &[ParticleRecord]) -> (usize, usize) {
    let near = |y: f64, h: f64| (y - h).abs() < REST_TOLERANCE;
    (
        records.iter().filter(|r| near(r.position.y, 0.0)).count(),
        records.iter().filter(|r| near(r.position.y, 1.0)).count(),
    )
}

#[test]
fn fast_particles_do_not_pass_through() {
    // Thrown down at 300 m/s, a particle crosses 5 m a step: from 2.5 m up to 2.5 m under the
    // floor in one step, far past the 0.3 m thickness. The sweep still stops it.
    let (slow, _, _) = run(0.0);
    let (fast, _, _) = run_source(&effect_at_speed(0.0, 300.0), true);
    assert_eq!(resting(&fast), resting(&slow));
    assert_eq!(resting(&fast).1, 4);
    assert!(resting(&fast).0 >= 50, "{:?}", resting(&fast));
}

#[test]
fn without_an_image_nothing_collides() {
    let (records, _, _) = run_source(&effect(0.0), false);
    assert!(records.iter().all(|r| r.position.y < -20.0));
}

#[test]
fn bad_scene_depth_input_is_refused() {
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, compile(&effect(0.0))).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let colour = gpu
        .device
        .create_texture(&texture(wgpu::TextureFormat::Rgba8Unorm, 1));
    let id = glam::Mat4::IDENTITY;
    let err = sim
        .set_scene_depth(&mut encoder, &colour, id, id)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a depth format"), "{err}");
    let depth = gpu
        .device
        .create_texture(&texture(wgpu::TextureFormat::Depth32Float, 1));
    let err = sim
        .set_scene_depth(&mut encoder, &depth, id, glam::Mat4::ZERO)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not invertible"), "{err}");
    let nan = glam::Mat4::from_cols_array(&[f32::NAN; 16]);
    let err = sim
        .set_scene_depth(&mut encoder, &depth, nan, id)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not finite"), "{err}");
    sim.set_scene_depth(&mut encoder, &depth, id, id).unwrap();
    gpu.queue.submit([encoder.finish()]);
}

use plume::runtime::wgpu;

/// A 64 x 64 texture of `format` and `samples` that can be drawn into and read.
fn texture(format: wgpu::TextureFormat, samples: u32) -> wgpu::TextureDescriptor<'static> {
    wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 64,
            height: 64,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    }
}

#[test]
fn a_depth_buffer_cleared_to_5_m_is_a_wall_5_m_away_single_or_multisampled() {
    // A camera at the origin looking down −z; a depth buffer cleared to the depth of a point 5
    // m ahead is a plane there, whatever the sample count (a multisampled one is read by its
    // sample 0). Particles flying away from the camera at 10 m/s stop on it.
    let source = r#"Effect(
    name: "wall",
    capacity: 25,
    emitters: [Emitter(burst: 25, shape: Grid(min: (-0.4, -0.4, -1.0), max: (0.4, 0.4, -1.0), counts: (5, 5, 1)), velocity: Constant((0.0, 0.0, -10.0)), lifetime: Some((100.0, 100.0)))],
    collide: [SceneDepth(thickness: 0.5, restitution: 0.0, friction: 1.0)],
)"#;
    let view = glam::Mat4::look_at_rh(glam::Vec3::ZERO, -glam::Vec3::Z, glam::Vec3::Y);
    let projection = glam::Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
    let ahead = projection * glam::Vec4::new(0.0, 0.0, -5.0, 1.0);
    let cleared = ahead.z / ahead.w;
    let gpu = gpu();
    for samples in [1, 4] {
        let depth = gpu
            .device
            .create_texture(&texture(wgpu::TextureFormat::Depth32Float, samples));
        let mut sim = Effect::new(&gpu, compile(source)).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let attachment = depth.create_view(&Default::default());
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &attachment,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(cleared),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        sim.set_scene_depth(&mut encoder, &depth, view, projection)
            .unwrap();
        gpu.queue.submit([encoder.finish()]);
        sim.run(60, |_| {}).unwrap();
        let records = sim.records().unwrap();
        assert_eq!(records.len(), 25);
        for r in &records {
            // In front of the wall by the depth's rounding there (8 ulps of a depth near 1 at
            // 5 m with a 0.1 m near plane: 2.4e-4 m along the ray) and the contact margin.
            let ahead = -r.position.z;
            assert!(
                ahead < 5.0 && ahead > 5.0 - 2e-3,
                "{samples} sample(s): a particle at {} m, not on the wall at 5 m",
                ahead
            );
        }
    }
}

#[test]
fn bad_scene_depth_colliders_are_located() {
    let two = effect(0.0).replace(
        "collide: [SceneDepth(thickness: 0.3,",
        "collide: [SceneDepth(restitution: 0.0, friction: 0.5), SceneDepth(thickness: 0.3,",
    );
    let err = plume::compile_str(&two, &Default::default()).unwrap_err();
    let text = err.render("two.ron", &two);
    assert!(text.contains("one SceneDepth collider"), "{text}");
    assert!(text.contains("collide[1]"), "{text}");
    let thin = effect(0.0).replace("thickness: 0.3", "thickness: -1.0");
    let err = plume::compile_str(&thin, &Default::default()).unwrap_err();
    let text = err.render("thin.ron", &thin);
    assert!(text.contains("thickness"), "{text}");
    assert!(text.contains("thin.ron:"), "{text}");
}
