//! Trails (`render.trail`) on the GPU (llvmpipe in CI): the ring the update writes holds each
//! particle's past positions as the f64 reference records them (slots reused, the ring split
//! across particle buffers), the drawn ribbon passes through those positions within a pixel
//! and nowhere the particle has not been, and matches the CPU-fed drawing (vertices in f64), an effect without a trail stores no history, and the
//! compute renderer draws the same ribbons.

mod common;

use common::*;
use glam::DVec3;
use plume::compiler::passes::layout::Role;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::oracle;
use plume::runtime::oracle::read_trails;
use plume::runtime::oracle::ReferenceRenderer;
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::outputs::Offscreen;
use plume::runtime::Camera;
use plume::runtime::Effect;
use plume::CompiledEffect;

/// Short-lived sparks under gravity and drag, spawned at a rate, so that slots are freed and
/// reused while their rings still hold the previous occupant's samples.
const RECYCLED: &str = r#"Effect(
    name: "trail-recycled",
    capacity: 48,
    seed: 9,
    dt: 0.016666666666666666,
    emitters: [Emitter(rate: 600.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.2),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 40.0, speed: (2.0, 5.0)),
                       lifetime: Some((0.1, 0.35)))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.8)],
    integrator: Euler,
    render: Render(trail: Some(Trail(points: 6, every: 3))),
)"#;

/// Compares the GPU's trails (read back from the rings) with the reference's after `steps`:
/// the same particles, the same number of points each, positions within the runtime's
/// tolerance for `steps` steps (4 roundings of 2^-24 a step for Euler, relative to 1 + |x|: a
/// sample was taken at an earlier step, so its error is no larger than the position's now).
/// Returns (particles, how many have a full trail, how many a shorter one).
fn compare_trails(gpu: &Effect, cpu: &ReferenceSim, steps: u64) -> (usize, usize, usize) {
    let (g, c) = (read_trails(gpu).unwrap(), cpu.trails());
    let ids = |t: &[(u32, Vec<DVec3>)]| t.iter().map(|(id, _)| *id).collect::<Vec<_>>();
    assert_eq!(ids(&g), ids(&c), "live ids differ after {steps} steps");
    let points = gpu.compiled().ir.render.trail.as_ref().unwrap().points as usize;
    let tol = 4.0 * steps as f64 * U32;
    let (mut full, mut short) = (0, 0);
    for ((id, gp), (_, cp)) in g.iter().zip(&c) {
        assert_eq!(
            gp.len(),
            cp.len(),
            "particle {id} after {steps} steps: {} points on the GPU, {} in the reference",
            gp.len(),
            cp.len()
        );
        for (j, (a, b)) in gp.iter().zip(cp).enumerate() {
            assert!(
                (*a - *b).length() <= tol * (1.0 + b.length()),
                "particle {id} point {j} after {steps} steps: gpu {a:?} cpu {b:?}"
            );
        }
        if gp.len() == points {
            full += 1;
        } else {
            short += 1;
        }
    }
    (g.len(), full, short)
}

#[test]
fn the_ring_holds_the_reference_positions_as_slots_are_reused() {
    let effect = compile(RECYCLED);
    let gpu = gpu();
    // One particle buffer, and the same state split into buffers of 7 slots (a ring each).
    for chunk_slots in [None, Some(7)] {
        let mut gsim = common::split(&gpu, effect.clone(), chunk_slots);
        let mut csim = ReferenceSim::new(&effect.ir);
        let (mut full, mut short) = (0, 0);
        // Steps chosen to end at every phase of the 3-step sampling.
        for (done, run) in [(1u64, 1u64), (11, 10), (35, 24), (61, 26), (90, 29)] {
            gsim.run(run, |_| {}).unwrap();
            csim.run(run);
            assert_eq!(
                gsim.totals().unwrap(),
                csim.totals(),
                "totals after {done} steps"
            );
            let (n, f, s) = compare_trails(&gsim, &csim, done);
            assert!(n > 0, "nothing alive after {done} steps");
            full += f;
            short += s;
        }
        assert!(csim.totals().died > 48, "slots were never reused");
        assert!(
            full > 0 && short > 0,
            "full {full}, short {short}: both kinds expected"
        );
    }
}

#[test]
fn the_orbit_example_keeps_its_trails_with_the_reference() {
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/orbit.ron"));
    let effect = compile_file(path);
    let gpu = gpu();
    let mut gsim = Effect::new(&gpu, effect.clone()).unwrap();
    let mut csim = ReferenceSim::new(&effect.ir);
    gsim.run(60, |_| {}).unwrap();
    csim.run(60);
    // Position Verlet: its update rounds as Euler's does, 4 roundings a step.
    let (n, full, _) = compare_trails(&gsim, &csim, 60);
    assert_eq!((n, full), (5000, 5000));
}

/// One particle thrown up and to the right under gravity, seen side on; its sprite has no size,
/// so only its white ribbon (0.15 m wide, 16 points, a sample every 2 steps) is drawn.
fn thrown(gpu: &plume::runtime::Gpu) -> (CompiledEffect, Effect) {
    let effect = compile(THROWN);
    let sim = Effect::new(gpu, effect.clone()).unwrap();
    (effect, sim)
}

/// One particle thrown up and across the view under gravity, its trail 16 points long.
const THROWN: &str = r#"Effect(
    name: "trail-thrown",
    capacity: 1,
    dt: 0.016666666666666666,
    emitters: [Emitter(burst: 1, shape: Point((-2.5, -1.0, 0.0)), velocity: Constant((4.0, 6.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: Euler,
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.0)], background: (0.0, 0.0, 0.0),
                   trail: Some(Trail(points: 16, every: 2, width: [(0.0, 0.15)],
                                     color: [(0.0, (1.0, 1.0, 1.0, 1.0))]))),
)"#;

const SIDE: u32 = 240;

/// The brightest red value within one pixel of (x, y).
fn near(img: &[u8], (x, y): (f32, f32)) -> u8 {
    let (cx, cy) = (x.floor() as i64, y.floor() as i64);
    let mut best = 0;
    for py in cy - 1..=cy + 1 {
        for px in cx - 1..=cx + 1 {
            if (0..SIDE as i64).contains(&px) && (0..SIDE as i64).contains(&py) {
                best = best.max(img[4 * (py as usize * SIDE as usize + px as usize)]);
            }
        }
    }
    best
}

#[test]
fn a_ribbon_passes_through_the_particles_previous_positions() {
    let gpu = gpu();
    let (effect, mut sim) = thrown(&gpu);
    let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
    let camera = target.effect_camera(&sim);
    let renderer = sim.renderer(&target.target()).unwrap();
    // Nothing behind a particle that has not moved yet: an empty image.
    let first = target.render(&sim, &renderer, &camera).unwrap();
    assert!(
        first.chunks_exact(4).all(|p| p[0] == 0),
        "a trail before any step"
    );
    let mut csim = ReferenceSim::new(&effect.ir);
    sim.run(51, |_| {}).unwrap();
    csim.run(51);
    let img = target.render(&sim, &renderer, &camera).unwrap();
    let (_, ribbon) = csim.trails().remove(0);
    assert_eq!(ribbon.len(), 16, "a full trail after 51 steps");
    // The ribbon is ~3.6 px wide, full alpha on its centre line: every point it joins lies on
    // it, the particle's own and its oldest sample (26 steps back) included.
    for (j, p) in ribbon.iter().enumerate() {
        let at = camera.project(SIDE, SIDE, *p).unwrap();
        let v = near(&img, at);
        assert!(v >= 200, "point {j} {p:?} at pixel {at:?}: {v}");
    }
    // Where the particle has been before the trail's tail (the oldest sample is its position
    // after 22 steps; after 15 steps it was 7 steps, ~19 px, back along the arc) and where it
    // will be (after 60 to 70 steps), nothing is drawn.
    let mut path = ReferenceSim::new(&effect.ir);
    for step in 1..=70u64 {
        path.run(1);
        let x = path.records()[0].position;
        if step <= 15 || step >= 60 {
            let at = camera.project(SIDE, SIDE, x).unwrap();
            assert!(
                near(&img, at) == 0,
                "the position after {step} steps {x:?} is lit"
            );
        }
    }
    // A pixel off the path, 10 px beside the ribbon's middle, stays dark.
    let (x, y) = camera.project(SIDE, SIDE, ribbon[8]).unwrap();
    assert_eq!(near(&img, (x, y + 10.0)), 0);
    // The CPU-fed drawing of the same points (vertices placed in f64) draws the same ribbon:
    // corners that differ by f32 roundings move an edge pixel's coverage by a step or two.
    let reference = ReferenceRenderer::new(&gpu, SIDE, SIDE, &effect.ir).unwrap();
    let records = sim.records().unwrap();
    let ribbons = oracle::trail_strips(
        &records,
        &read_trails(&sim).unwrap(),
        &effect.ir,
        camera.view,
    );
    assert_eq!(ribbons.len(), 15 * 6, "15 segments of two triangles");
    let cpu = reference.draw_with_strips(&ribbons, &[], &camera).unwrap();
    let (mean, max, _) = differences(&img, &cpu, 4);
    assert!(
        mean < 0.01 && max <= 4,
        "GPU and CPU-fed ribbons differ: mean {mean}, max {max}"
    );
}

#[test]
fn a_ribbon_reads_the_same_from_split_buffers() {
    let gpu = gpu();
    let (effect, mut one) = thrown(&gpu);
    let mut split = common::split(&gpu, effect, Some(1));
    assert_eq!(
        oracle::chunk_count(&split, 0).unwrap(),
        1,
        "one particle, one buffer"
    );
    // A capacity of several chunks with the particle in the last: the recycled effect.
    let recycled = compile(RECYCLED);
    let mut chunked = common::split(&gpu, recycled.clone(), Some(16));
    let mut whole = Effect::new(&gpu, recycled).unwrap();
    assert!(oracle::chunk_count(&chunked, 0).unwrap() > 1);
    for sim in [&mut one, &mut split, &mut chunked, &mut whole] {
        sim.run(40, |_| {}).unwrap();
    }
    let draw = |sim: &Effect| {
        let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
        let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
        target
            .render(sim, &sim.renderer(&target.target()).unwrap(), &camera)
            .unwrap()
    };
    assert_eq!(draw(&one), draw(&split));
    let (a, b) = (draw(&whole), draw(&chunked));
    assert!(a.chunks_exact(4).any(|p| p[0] > 0), "nothing drawn");
    assert_eq!(a, b, "the chunked trail module draws other ribbons");
}

#[test]
fn only_an_effect_with_a_trail_stores_history() {
    let with = compile(RECYCLED);
    let without = compile(&RECYCLED.replace(
        "render: Render(trail: Some(Trail(points: 6, every: 3))),",
        "",
    ));
    assert_eq!(
        with.layout.bytes_per_particle,
        without.layout.bytes_per_particle
    );
    assert_eq!(with.layout.trail_bytes_per_particle, 5 * 16);
    assert_eq!(without.layout.trail_bytes_per_particle, 0);
    assert!(with.layout.binds(Role::Trail) && !without.layout.binds(Role::Trail));
    assert!(with.wgsl.contains("trail[") && !without.wgsl.contains("trail["));
    assert!(with.trail_wgsl.is_some() && without.trail_wgsl.is_none());
    assert!(with.layout.to_string().contains("trail history: 80 bytes"));
    // A trail keeps state: an Exact effect that would be stateless is not.
    let exact = compile(
        &RECYCLED
            .replace("Euler", "Exact")
            .replace("rate: 600.0", "burst: 40"),
    );
    assert!(exact.ir.stateless.is_none());
    assert!(
        exact.ir.state_reason.contains("render.trail"),
        "{}",
        exact.ir.state_reason
    );
}

#[test]
fn the_compute_renderer_draws_the_ribbons_the_raster_draw_draws() {
    // The thrown particle's ribbon (15 segments, two triangles each) and the recycled slots'
    // ribbons, drawn by the compute renderer (each triangle's pixels given perspective-correct
    // barycentric weights from the inverse of its homogeneous pixel coordinates) and by the
    // raster pipeline: the same ribbons, shaded as fs_trail does. The rasteriser snaps
    // vertices to 1/256 pixel and the compute renderer does not, so a pixel centre on a strip's edge may
    // flip; across the strip the alpha falls to 0 at that edge, so a flipped pixel differs by
    // little. A ribbon offset, missing or widened would differ by tens of steps.
    // Additive ribbons composite in tiles as alpha ones do (the sum in list order), so a
    // second frame is the same image.
    let gpu = gpu();
    let (_, mut thrown) = thrown(&gpu);
    thrown.run(51, |_| {}).unwrap();
    let mut recycled = Effect::new(&gpu, compile(RECYCLED)).unwrap();
    recycled.run(40, |_| {}).unwrap();
    let additive_source = RECYCLED.replace("render: Render(", "render: Render(blend: Additive, ");
    let mut additive = Effect::new(&gpu, compile(&additive_source)).unwrap();
    additive.run(40, |_| {}).unwrap();
    for (name, sim) in [
        ("thrown", &thrown),
        ("recycled", &recycled),
        ("recycled, additive", &additive),
    ] {
        assert!(ComputeOffscreen::draws(&sim.compiled().ir));
        let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
        let camera = target.effect_camera(sim);
        let raster = target
            .render(sim, &sim.renderer(&target.target()).unwrap(), &camera)
            .unwrap();
        let mut splat = ComputeOffscreen::new(sim, SIDE, SIDE).unwrap();
        let img = splat.render(sim, &camera).unwrap();
        assert!(splat.entries_are_complete().unwrap());
        assert!(
            img == splat.render(sim, &camera).unwrap(),
            "{name}: a second frame differs"
        );
        let lit = raster.chunks(4).filter(|p| p[0] > 100).count();
        assert!(lit > 50, "{name}: the raster draw shows {lit} pixels");
        let (mean, max, over) = differences(&raster, &img, 3);
        let local = local_difference(&raster, &img, SIDE, 4);
        eprintln!(
            "{name}: splat vs raster: mean {mean:.4}, max {max}, {over} over 3, 4x4 {local:.2}"
        );
        assert!(
            mean < 0.05 && local < 4.0 && over * 2000 < img.len(),
            "{name}: splat and raster ribbons differ: mean {mean}, max {max}, {over} over 3, 4x4 {local}"
        );
    }
}

/// A lit trail (`render.lit`) is lit as a flat card whose normal faces the eye, square to the
/// trail: a straight ribbon across the view (normal +z) under a light at 60° to that normal
/// is half as bright as the same ribbon unlit (Lambert's law, within an 8-bit step), and an
/// arc under a point light with wrap, emissive and ambient light matches the reference drawing
/// (each point lit in f64) and the compute renderer's image.
#[test]
fn a_lit_trail_follows_lamberts_law_and_the_reference_drawing() {
    let gpu = gpu();
    let straight = |lit: &str| {
        format!(
            r#"Effect(
    name: "trail-lit",
    capacity: 1,
    dt: 0.016666666666666666,
    emitters: [Emitter(burst: 1, shape: Point((-2.5, 0.0, 0.0)), velocity: Constant((4.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    lights: [Directional(direction: (0.0, -0.8660254037844386, -0.5))],
    render: Render(color: [(0.0, (0.8, 0.6, 1.0, 1.0))], size: [(0.0, 0.0)], background: (0.0, 0.0, 0.0),
                   trail: Some(Trail(points: 16, every: 2, width: [(0.0, 0.5)],
                                     color: [(0.0, (1.0, 1.0, 1.0, 1.0))])){lit}),
)"#
        )
    };
    let draw = |source: &str| {
        let mut sim = Effect::new(&gpu, compile(source)).unwrap();
        sim.run(40, |_| {}).unwrap();
        let target = Offscreen::new(&gpu, SIDE, SIDE).unwrap();
        let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
        let img = target
            .render(&sim, &sim.renderer(&target.target()).unwrap(), &camera)
            .unwrap();
        (img, camera, sim)
    };
    let (unlit, camera, _) = draw(&straight(""));
    let (lit, _, sim) = draw(&straight(", lit: Some(Lit())"));
    assert!(ComputeOffscreen::draws(&sim.compiled().ir));
    // Pixels on the ribbon's centre line, along its middle (it runs from x = -1.8 to 0.2).
    for x in [-1.4, -1.0, -0.6, -0.2] {
        let (px, py) = camera.project(SIDE, SIDE, DVec3::new(x, 0.0, 0.0)).unwrap();
        let at = 4 * (py as usize * SIDE as usize + px as usize);
        for c in 0..3 {
            let (u, l) = (f64::from(unlit[at + c]), f64::from(lit[at + c]));
            assert!(
                u > 150.0 || c == 1 && u > 110.0,
                "x {x}: unlit {u} in channel {c}"
            );
            assert!(
                (l - 0.5 * u).abs() <= 1.0,
                "x {x}, channel {c}: lit {l}, unlit {u}"
            );
        }
    }
    // The thrown arc: its normal turns along the trail; a point light, wrap and emissive.
    let arc = compile(
        &THROWN
            .replace(
                "integrator: Euler,",
                "integrator: Euler,\n    lights: [Point(position: (0.5, 2.0, 1.5), color: (1.0, 0.8, 0.6), intensity: 3.0, range: 6.0), Ambient(intensity: 0.1)],",
            )
            .replace(
                "color: [(0.0, (1.0, 1.0, 1.0, 1.0))]))),",
                "color: [(0.0, (1.0, 1.0, 1.0, 1.0))])), lit: Some(Lit(wrap: 0.3, emissive: 0.2))),",
            ),
    );
    assert!(arc.ir.render.lit.is_some());
    let mut sim = Effect::new(&gpu, arc).unwrap();
    sim.run(40, |_| {}).unwrap();
    let img = assert_draws_agree(&sim, SIDE, true, "lit arc");
    assert!(
        img.chunks(4).filter(|p| p[0] > 20).count() > 300,
        "the arc is drawn"
    );
}
