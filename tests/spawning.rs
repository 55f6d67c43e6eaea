//! Spawning: the shapes on a sphere's surface, a box's faces, a circle and in or on a cone, the
//! Tangent velocity, and emitters that start late, stop, and repeat their bursts. Every shape
//! is drawn on the GPU and in the f64 reference from the same integer hashes, and the two
//! agree to a few f32 roundings (`common::spawn_states`); the f64 positions are then tested
//! against the distribution the docs promise.
//!
//! Statistical bounds: a fraction p estimated from n independent draws has standard deviation
//! sqrt(p (1 − p) / n); each check allows 5 of them, which a correct sampler misses with
//! probability below 1e-6, while the wrong distributions these shapes could be confused with
//! (a volume for a surface, uniform height in a cone, angle-uniform faces) miss by tens of
//! deviations at n = 20,000. The draws are fixed by the seed, so a pass is repeatable.

mod common;

use common::compare::roundings_per_step;
use common::meshes::{box_obj, write};
use common::*;
use glam::DVec3;
use plume::compiler::graph::{compile_graph_str, ReferenceGraph};
use plume::runtime::Effect;
use plume::CompileOptions;

const DT: f64 = 0.001;
const N: u32 = 20_000;

/// How far the GPU's spawns that take a sine or a cosine may lie from the f64 reference's,
/// relative to 1 + their size: WGSL leaves trigonometry's f32 accuracy to the driver (2^-11
/// absolute on [−π, π] is all it requires), and llvmpipe's sine was measured 2.5e-5 off where
/// the rest of a spawn's arithmetic is a few ulps. A wrong formula moves a point by its whole
/// scale, far past this.
const TRIG: f64 = 1e-4;

/// An effect of one burst of `N` particles from `shape`, moving by `velocity`.
fn burst(shape: &str, velocity: &str) -> String {
    format!(
        r#"Effect(
    name: "shape",
    capacity: {N},
    seed: 5,
    dt: {DT},
    emitters: [Emitter(burst: {N}, shape: {shape}, velocity: {velocity})],
    integrator: SemiImplicitEuler,
)"#
    )
}

/// The spawn positions of a burst from `shape`, at rest, GPU and reference agreeing.
fn positions(shape: &str) -> Vec<DVec3> {
    spawn_states_within(&burst(shape, "Constant((0.0, 0.0, 0.0))"), DT, TRIG)
        .into_iter()
        .map(|(x, _)| x)
        .collect()
}

/// Asserts that `hits` of `n` is within 5 standard deviations of the fraction `p`.
fn assert_fraction(what: &str, hits: usize, n: usize, p: f64) {
    let got = hits as f64 / n as f64;
    let sigma = (p * (1.0 - p) / n as f64).sqrt();
    assert!(
        (got - p).abs() <= 5.0 * sigma,
        "{what}: {got:.4} of the particles, expected {p:.4} ± {:.4}",
        5.0 * sigma
    );
}

#[test]
fn a_sphere_surface_spawns_on_the_sphere_with_every_coordinate_uniform() {
    let c = DVec3::new(1.0, 2.0, 3.0);
    let xs = positions("Sphere(center: (1.0, 2.0, 3.0), radius: 0.5, surface: true)");
    assert_eq!(xs.len(), N as usize);
    for x in &xs {
        assert!(
            ((*x - c).length() - 0.5).abs() < 1e-12,
            "{x:?} is off the sphere"
        );
    }
    // Archimedes: on a sphere every coordinate is uniform over the diameter.
    for axis in [0, 2] {
        for q in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let below = xs
                .iter()
                .filter(|x| x[axis] - c[axis] < 0.5 * (2.0 * q - 1.0))
                .count();
            assert_fraction(
                &format!("axis {axis} below quantile {q}"),
                below,
                xs.len(),
                q,
            );
        }
    }
}

#[test]
fn a_box_surface_spawns_on_its_faces_by_area() {
    // Faces of 0.5, 1 and 2 m² (two each): 1/14, 1/7 and 2/7 of the particles each.
    let (min, max) = (DVec3::new(-1.0, 0.0, 1.0), DVec3::new(1.0, 1.0, 1.5));
    let xs = positions("Box(min: (-1.0, 0.0, 1.0), max: (1.0, 1.0, 1.5), surface: true)");
    let mut on_face = [0usize; 6];
    for x in &xs {
        assert!(
            x.cmpge(min).all() && x.cmple(max).all(),
            "{x:?} is off the box"
        );
        let face = (0..6)
            .find(|f| {
                let at = if f % 2 == 0 { min } else { max };
                (x[f / 2] - at[f / 2]).abs() < 1e-12
            })
            .unwrap_or_else(|| panic!("{x:?} is inside the box, on no face"));
        on_face[face] += 1;
    }
    for (face, p) in [1.0, 1.0, 2.0, 2.0, 4.0, 4.0]
        .iter()
        .map(|a| a / 14.0)
        .enumerate()
    {
        assert_fraction(&format!("face {face}"), on_face[face], xs.len(), p);
    }
    // A flat box's surface is its two sides: every point in the plane.
    for x in positions("Box(min: (0.0, 0.0, 0.0), max: (1.0, 2.0, 0.0), surface: true)") {
        assert_eq!(x.z, 0.0);
        assert!(
            x.x >= 0.0 && x.x <= 1.0 && x.y >= 0.0 && x.y <= 2.0,
            "{x:?}"
        );
    }
}

#[test]
fn a_circle_spawns_on_its_edge_uniformly_by_angle() {
    let c = DVec3::new(0.0, 1.0, 0.0);
    let n = DVec3::new(1.0, 1.0, 0.0).normalize();
    let xs = positions("Circle(center: (0.0, 1.0, 0.0), normal: (1.0, 1.0, 0.0), radius: 2.0)");
    let (e1, e2) = (DVec3::Z, n.cross(DVec3::Z));
    let mut bins = [0usize; 8];
    for x in &xs {
        let r = *x - c;
        assert!((r.length() - 2.0).abs() < 1e-12, "{x:?} is off the circle");
        assert!(r.dot(n).abs() < 1e-12, "{x:?} is off the circle's plane");
        let angle = r.dot(e2).atan2(r.dot(e1)) + std::f64::consts::PI;
        bins[((angle / std::f64::consts::TAU * 8.0) as usize).min(7)] += 1;
    }
    for (i, &b) in bins.iter().enumerate() {
        assert_fraction(&format!("angle bin {i}"), b, xs.len(), 1.0 / 8.0);
    }
}

/// Heights along the cone's axis (a fraction of its height) and distances from the axis of a
/// cone along +Y from the origin, `height` 2.
fn cone(base_radius: f64, top_radius: f64, surface: bool) -> Vec<(f64, f64)> {
    positions(&format!(
        "Cone(base: (0.0, 0.0, 0.0), axis: (0.0, 3.0, 0.0), height: 2.0, base_radius: {base_radius:?}, top_radius: {top_radius:?}, surface: {surface})"
    ))
    .into_iter()
    .map(|x| (x.y / 2.0, x.x.hypot(x.z)))
    .collect()
}

#[test]
fn a_cone_fills_its_frustum_by_volume_and_its_side_by_area() {
    let (r0, r1) = (1.0, 0.25);
    let radius = |h: f64| r0 + (r1 - r0) * h;
    // In the volume: within the radius at each height; the volume below height s is
    // (r0³ − r(s)³) / (r0³ − r1³) of the whole; at each height, uniform in the disc.
    let volume = cone(r0, r1, false);
    for &(h, d) in &volume {
        assert!(
            (0.0..=1.0).contains(&h) && d <= radius(h) + 1e-12,
            "height {h}, distance {d}"
        );
    }
    for s in [0.1f64, 0.3, 0.5, 0.7, 0.9] {
        let below = volume.iter().filter(|(h, _)| *h < s).count();
        let p = (r0.powi(3) - radius(s).powi(3)) / (r0.powi(3) - r1.powi(3));
        assert_fraction(&format!("volume below {s}"), below, volume.len(), p);
    }
    let inner = volume
        .iter()
        .filter(|(h, d)| d * d < 0.5 * radius(*h).powi(2))
        .count();
    assert_fraction("inner half of each disc's area", inner, volume.len(), 0.5);
    // On the side: at the radius of its height; the area below s is (r0² − r(s)²)/(r0² − r1²).
    let side = cone(r0, r1, true);
    for &(h, d) in &side {
        assert!(
            (d - radius(h)).abs() < 1e-12,
            "height {h}, distance {d}, off the side"
        );
    }
    for s in [0.1f64, 0.3, 0.5, 0.7, 0.9] {
        let below = side.iter().filter(|(h, _)| *h < s).count();
        let p = (r0 * r0 - radius(s).powi(2)) / (r0 * r0 - r1 * r1);
        assert_fraction(&format!("side below {s}"), below, side.len(), p);
    }
}

#[test]
fn pointed_cones_and_cylinders_are_cones_too() {
    // Narrow at the base, pointed: the volume below s is s³.
    let pointed = cone(0.0, 1.0, false);
    for s in [0.2f64, 0.5, 0.8] {
        let below = pointed.iter().filter(|(h, _)| *h < s).count();
        assert_fraction(
            &format!("pointed, below {s}"),
            below,
            pointed.len(),
            s.powi(3),
        );
    }
    // Equal radii: uniform in height, at the radius on the side.
    let cylinder = cone(0.5, 0.5, true);
    for s in [0.2f64, 0.5, 0.8] {
        let below = cylinder.iter().filter(|(h, _)| *h < s).count();
        assert_fraction(&format!("cylinder, below {s}"), below, cylinder.len(), s);
    }
    assert!(cylinder.iter().all(|(_, d)| (d - 0.5).abs() < 1e-12));
    // No radius at all: a segment of the axis.
    assert!(cone(0.0, 0.0, false)
        .iter()
        .all(|&(h, d)| d == 0.0 && (0.0..=1.0).contains(&h)));
}

#[test]
fn tangent_velocities_turn_about_the_axis_and_rest_on_it() {
    let axis = DVec3::new(0.0, 2.0, 0.0);
    let c = DVec3::new(0.0, 1.0, 0.0);
    // A ring about the axis. (Near the axis the direction is only as precise as the position
    // over its distance from the axis, as Radial's is near the centre: the ring keeps the
    // GPU's f32 direction within the bound.)
    let states = spawn_states_within(
        &burst(
            "Circle(center: (0.0, 1.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 2.0)",
            "Tangent(axis: (0.0, 2.0, 0.0), speed: (1.0, 3.0))",
        ),
        DT,
        TRIG,
    );
    for (x, v) in &states {
        let around = axis.normalize().cross(*x - c);
        let speed = v.length();
        assert!(
            (1.0 - 1e-12..=3.0 + 1e-12).contains(&speed),
            "speed {speed}"
        );
        // Along axis × (x − c): counter-clockwise seen from the axis's tip.
        assert!(
            (v.normalize() - around.normalize()).length() < 1e-9,
            "{x:?} moves {v:?}"
        );
    }
    // On the axis itself there is no tangent: at rest, never NaN.
    let on_axis = spawn_states(
        &burst(
            "Point((0.0, 4.0, 0.0))",
            "Tangent(axis: (0.0, 1.0, 0.0), speed: (1.0, 3.0))",
        ),
        DT,
    );
    assert!(on_axis.iter().all(|(_, v)| *v == DVec3::ZERO));
}

/// Live particles' counts after each of `steps` steps, on the GPU and in the reference.
fn spawned_by_step(src: &str, steps: u64) -> Vec<u64> {
    let effect = compile(src);
    let gpu = gpu();
    let mut gsim = Effect::new(&gpu, effect.clone()).expect("GPU sim");
    let mut csim = plume::compiler::reference::ReferenceSim::new(&effect.ir);
    let mut out = Vec::new();
    for step in 1..=steps {
        gsim.run(1, |_| {}).unwrap();
        csim.run(1);
        let (g, c) = (gsim.totals().unwrap(), csim.totals());
        assert_eq!(g, c, "totals differ after step {step}");
        out.push(c.spawned);
    }
    let (g, c) = (gsim.records().unwrap(), csim.records());
    let ids = |r: &[plume::compiler::reference::ParticleRecord]| {
        r.iter().map(|p| p.id).collect::<Vec<_>>()
    };
    assert_eq!(ids(&g), ids(&c));
    out
}

#[test]
fn emitters_start_late_stop_and_repeat_their_bursts_on_whole_steps() {
    // dt 0.05: bursts of 10 at 0.25, 0.75 and 1.25 s (steps 5, 15, 25); a rate of 40/s (two
    // a step) from 0.1 s for 0.3 s (steps 2 to 7).
    let src = r#"Effect(
    name: "timing",
    capacity: 100,
    dt: 0.05,
    emitters: [
        Emitter(burst: 10, every: Some(0.5), cycles: Some(3), start: 0.25, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0))),
        Emitter(rate: 40.0, start: 0.1, duration: Some(0.3), shape: Point((1.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0))),
    ],
)"#;
    let spawned = spawned_by_step(src, 30);
    let expected: Vec<u64> = (0..30u64)
        .map(|k| {
            let bursts = [5, 15, 25].iter().filter(|&&s| s <= k).count() as u64 * 10;
            let rate = 2 * (k.min(7) + 1).saturating_sub(2);
            bursts + rate
        })
        .collect();
    assert_eq!(spawned, expected);
}

#[test]
fn a_burst_repeating_for_ever_runs_stateless_as_its_stateful_twin_does() {
    let src = |state: &str| {
        format!(
            r#"Effect(
    name: "pulses",
    capacity: 1000,
    dt: 0.02,
    emitters: [Emitter(burst: 50, every: Some(0.3), start: 0.1, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, surface: true), velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.5, 0.7)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: Exact,
    state: {state},
)"#
        )
    };
    let stateless = compile(&src("Stateless"));
    assert!(stateless.ir.stateless.is_some());
    let stateful = compile(&src("Stateful"));
    for steps in [7u64, 40, 333] {
        let (ta, a) = run_gpu(&stateless, steps);
        let (tb, b) = run_gpu(&stateful, steps);
        let (tc, c) = run_cpu(&stateful, steps);
        assert_eq!(
            (ta.alive, ta.spawned),
            (tc.alive, tc.spawned),
            "after {steps} steps"
        );
        assert_eq!(tb, tc, "after {steps} steps");
        assert!(tc.alive > 0, "pulses are alive at step {steps}");
        for ((p, q), r) in a.iter().zip(&b).zip(&c) {
            assert_eq!((p.id, q.id), (r.id, r.id));
            assert!((p.position - r.position).length() < 1e-4 * (1.0 + r.position.length()));
        }
    }
}

#[test]
fn an_event_spawns_its_children_on_a_mesh_around_the_parent() {
    let file = write(
        "event-crate.obj",
        &box_obj([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]),
    );
    let src = format!(
        r#"Effect(
    name: "crates",
    capacity: 4,
    dt: 0.02,
    emitters: [Emitter(burst: 4, shape: Points([(0.0, 0.0, 0.0), (3.0, 0.0, 0.0), (0.0, 3.0, 0.0), (0.0, 0.0, 3.0)]), velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((0.1, 0.1)))],
    events: [Event(on: Death, target: "shards", count: 200, shape: Mesh(file: {file:?}), velocity: Normal(speed: (1.0, 1.0)))],
    groups: [Group(name: "shards", capacity: 800)],
)"#
    );
    let graph = compile_graph_str(&src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("crates.ron", &src)));
    let gpu = gpu();
    let mut gsim = Effect::from_graph(&gpu, graph.clone()).unwrap();
    let mut csim = ReferenceGraph::new(&graph);
    gsim.run(6, |_| {}).unwrap();
    csim.run(6);
    assert_eq!(gsim.group_totals(1).unwrap(), csim.totals(1));
    let (g, c) = (gsim.group_records(1).unwrap(), csim.records(1));
    assert_eq!(c.len(), 800, "every crate broke into 200 shards");
    for (p, q) in g.iter().zip(&c) {
        assert_eq!(p.id, q.id);
        assert!((p.position - q.position).length() < 1e-5 * (1.0 + q.position.length()));
        // On a face of the unit box around one of the parents, moving out of it at 1 m/s.
        assert!((q.velocity.length() - 1.0).abs() < 1e-9);
    }
}

/// A ring that widens with the spawn time, each particle moving out of it and up by its own
/// rand(1) (times the param `up`).
const RING: &str = r#"Effect(
    name: "ring",
    capacity: 5000,
    seed: 9,
    dt: 0.02,
    params: {"up": 3.0},
    emitters: [Emitter(burst: 300, rate: 2000.0, lifetime: Some((1.0, 1.0)),
        shape: Custom("vec3(cos(6.2831853 * rand(0)), 0.0, sin(6.2831853 * rand(0))) * (1.0 + t)"),
        velocity: Custom("normalize(x) * 2.0 + vec3(0.0, up * rand(1), 0.0)"))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: SemiImplicitEuler,
)"#;

#[test]
fn spawn_expressions_set_position_and_velocity_as_the_reference_does() {
    // At step 0 (t = 0): on the unit circle, moving out at 2 m/s and up by 0 to 3 m/s (less
    // the step of gravity the records have taken).
    for (x, v) in spawn_states_within(RING, 0.02, TRIG) {
        assert!(
            (x.length() - 1.0).abs() < 1e-9 && x.y.abs() < 1e-12,
            "{x:?}"
        );
        let out = v - DVec3::new(0.0, v.y, 0.0);
        assert!(
            (out - 2.0 * x.normalize()).length() < 1e-9,
            "{x:?} moves {v:?}"
        );
        let up = v.y + 9.81 * 0.02;
        assert!((-1e-12..3.0).contains(&up), "{v:?}");
    }
    // Later spawns read their step's time: the ring has widened. Over 40 steps the GPU stays
    // within the spawn's trigonometry (TRIG) and gpu_vs_reference.rs's bound of a few f32
    // roundings a step of the f64 run.
    let effect = compile(RING);
    let worst = worst_gpu_distance(&effect, 40);
    let bound = TRIG + 4.0 * 40.0 * roundings_per_step(&effect.ir) * U32;
    assert!(worst <= bound, "{worst:e} > {bound:e}");
    let (_, records) = run_cpu(&effect, 40);
    let widest = records
        .iter()
        .map(|r| DVec3::new(r.position.x, 0.0, r.position.z).length())
        .fold(0.0, f64::max);
    assert!(
        widest > 1.5,
        "spawns late in the run start on a wider ring: {widest}"
    );
}

#[test]
fn a_constant_spawn_expression_is_the_point_or_velocity_it_folds_to() {
    let src = |shape: &str, velocity: &str| {
        format!(
            r#"Effect(name: "same", capacity: 10, params: {{"s": 2.0}},
            emitters: [Emitter(burst: 10, shape: {shape}, velocity: {velocity})])"#
        )
    };
    let written = compile(&src(
        r#"Custom("vec3(1.0, 2.0, 0.5) * s")"#,
        r#"Custom("vec3(0.0, s + 1.0, 0.0)")"#,
    ));
    let plain = compile(&src("Point((2.0, 4.0, 1.0))", "Constant((0.0, 3.0, 0.0))"));
    assert_eq!(written.wgsl, plain.wgsl);
    assert_eq!(written.ir.emitters, plain.ir.emitters);
}

#[test]
fn a_live_param_changes_later_spawns_on_the_gpu_as_in_the_reference() {
    let compiled = plume::compile_str(
        RING,
        &CompileOptions {
            live_params: true,
            ..Default::default()
        },
    )
    .unwrap();
    let gpu = gpu();
    let mut gsim = Effect::new(&gpu, compiled.clone()).unwrap();
    let mut csim = plume::compiler::reference::ReferenceSim::new(&compiled.ir);
    for (steps, up) in [(5u64, 3.0f32), (5, 10.0), (5, 0.0)] {
        gsim.set_param("up", up).unwrap();
        csim.set_param("up", up).unwrap();
        gsim.run(steps, |_| {}).unwrap();
        csim.run(steps);
    }
    let (g, c) = (gsim.records().unwrap(), csim.records());
    assert_eq!(g.len(), c.len());
    let bound = TRIG + 4.0 * 15.0 * roundings_per_step(&compiled.ir) * U32;
    for (p, q) in g.iter().zip(&c) {
        assert_eq!(p.id, q.id);
        assert!((p.position - q.position).length() <= bound * (1.0 + q.position.length()));
    }
    // Spawned while `up` was 10, some rise faster than any could at 3.
    assert!(c.iter().any(|r| r.velocity.y > 3.0));
}

/// The spawn velocities of a burst from the origin whose velocity is `expression`.
fn drawn(expression: &str) -> Vec<DVec3> {
    spawn_states_within(
        &burst(
            "Point((0.0, 0.0, 0.0))",
            &format!("Custom(\"{expression}\")"),
        ),
        DT,
        TRIG,
    )
    .into_iter()
    .map(|(_, v)| v)
    .collect()
}

#[test]
fn random_draws_have_their_distributions_on_the_gpu_as_in_the_reference() {
    let fraction = |vs: &[DVec3], f: &dyn Fn(&DVec3) -> bool| vs.iter().filter(|v| f(v)).count();
    // On the sphere: unit length, every coordinate uniform over [-1, 1].
    let sphere = drawn("rand_sphere(0)");
    assert!(sphere.iter().all(|v| (v.length() - 1.0).abs() < 1e-9));
    for axis in [0, 2] {
        let below = fraction(&sphere, &|v| v[axis] < 0.2);
        assert_fraction(
            &format!("sphere axis {axis} below 0.2"),
            below,
            sphere.len(),
            0.6,
        );
    }
    // In the ball: the share within radius r is r³.
    let ball = drawn("rand_ball(3)");
    assert!(ball.iter().all(|v| v.length() <= 1.0 + 1e-9));
    for r in [0.5f64, 0.8] {
        let inside = fraction(&ball, &|v| v.length() < r);
        assert_fraction(&format!("ball within {r}"), inside, ball.len(), r.powi(3));
    }
    // On the circle and in the disc, in the xy plane: the disc's share within r is r².
    let circle = drawn("rand_circle(7)");
    assert!(circle
        .iter()
        .all(|v| v.z == 0.0 && (v.length() - 1.0).abs() < 1e-9));
    let right = fraction(&circle, &|v| v.x > 0.5);
    assert_fraction("circle at x > 0.5", right, circle.len(), 1.0 / 3.0);
    let disc = drawn("rand_disc(9)");
    assert!(disc.iter().all(|v| v.z == 0.0 && v.length() <= 1.0 + 1e-9));
    let inside = fraction(&disc, &|v| v.length() < 0.5);
    assert_fraction("disc within 0.5", inside, disc.len(), 0.25);
    // Normal: mean 0 and variance 1 (within 5 standard errors: 1/√n and √(2/n)), 68.27%
    // within one deviation; two draws from different streams are uncorrelated.
    let normal = drawn("vec3(rand_normal(20), rand_normal(22), 0.0)");
    let n = normal.len() as f64;
    for axis in [0, 1] {
        let mean = normal.iter().map(|v| v[axis]).sum::<f64>() / n;
        let var = normal.iter().map(|v| (v[axis] - mean).powi(2)).sum::<f64>() / n;
        assert!(mean.abs() < 5.0 / n.sqrt(), "axis {axis}: mean {mean}");
        assert!(
            (var - 1.0).abs() < 5.0 * (2.0 / n).sqrt(),
            "axis {axis}: variance {var}"
        );
        let within = fraction(&normal, &|v| v[axis].abs() < 1.0);
        assert_fraction(
            &format!("normal axis {axis} within 1"),
            within,
            normal.len(),
            0.6827,
        );
    }
    let covariance = normal.iter().map(|v| v.x * v.y).sum::<f64>() / n;
    assert!(covariance.abs() < 5.0 / n.sqrt(), "covariance {covariance}");
}

/// A stream and a repeating burst whose sizes are params.
const VALVE: &str = r#"Effect(
    name: "valve",
    capacity: 4000,
    dt: 0.02,
    params: {"flow": 100.0, "puff": 10.0},
    emitters: [
        Emitter(rate: "flow", shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((5.0, 5.0))),
        Emitter(burst: "puff", every: Some(0.1), shape: Point((1.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((5.0, 5.0))),
    ],
)"#;

#[test]
fn rates_and_bursts_read_from_params_are_their_values() {
    let written = compile(VALVE);
    let plain = compile(
        &VALVE
            .replace(r#"rate: "flow""#, "rate: 100.0")
            .replace(r#"burst: "puff""#, "burst: 10"),
    );
    assert_eq!(written.wgsl, plain.wgsl);
    assert_eq!(written.ir.emitters, plain.ir.emitters);
    assert!(written.ir.stateless.is_none() || plain.ir.stateless.is_some());
}

#[test]
fn a_live_param_opens_and_closes_an_emitter_on_the_gpu_as_in_the_reference() {
    let compiled = plume::compile_str(
        VALVE,
        &CompileOptions {
            live_params: true,
            ..Default::default()
        },
    )
    .unwrap();
    // A rate the host may change is no closed form: the effect runs stateful.
    assert!(compiled.ir.stateless.is_none());
    let gpu = gpu();
    let mut gsim = Effect::new(&gpu, compiled.clone()).unwrap();
    let mut csim = plume::compiler::reference::ReferenceSim::new(&compiled.ir);
    // Three stretches of 10 steps (0.2 s: two puffs, 0.1 s apart, each): 100/s (2 a step) and
    // puffs of 10; closed (0/s, puffs of 0); 200/s (4 a step) and puffs of 30.
    let mut expected = 0u64;
    for (flow, puff, per_step) in [(100.0f32, 10.0f32, 2), (0.0, 0.0, 0), (200.0, 30.0, 4)] {
        for (name, value) in [("flow", flow), ("puff", puff)] {
            gsim.set_param(name, value).unwrap();
            csim.set_param(name, value).unwrap();
        }
        gsim.run(10, |_| {}).unwrap();
        csim.run(10);
        expected += 10 * per_step + 2 * puff as u64;
        let (g, c) = (gsim.totals().unwrap(), csim.totals());
        assert_eq!(g, c);
        assert_eq!(c.spawned, expected, "flow {flow}, puff {puff}");
    }
}

#[test]
fn starting_ages_are_uniform_whole_steps_and_shorten_the_life() {
    // `age: Some((0.0, 0.3))` at dt = 0.01: each particle starts 0 to 30 whole steps into a
    // 0.5 s life, drawn uniformly (31 values), the same on the GPU and in the reference, its
    // colour over life starting that far along (the draw reads its stored spawn step).
    let src = r#"Effect(
    name: "ages",
    capacity: 30000,
    seed: 5,
    dt: 0.01,
    emitters: [Emitter(burst: 20000, shape: Point((0.0, 0.0, 0.0)), velocity: Radial(speed: (1.0, 1.0)),
        lifetime: Some((0.5, 0.5)), age: Some((0.0, 0.3)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0)), (1.0, (1.0, 0.0, 0.0, 0.0))]),
)"#;
    let e = compile(src);
    assert!(e.ir.stateless.is_none(), "{}", e.ir.state_reason);
    assert!(
        e.ir.state_reason.contains("emitters[0].age"),
        "{}",
        e.ir.state_reason
    );
    let (gt, gpu) = run_gpu(&e, 1);
    let (ct, cpu) = run_cpu(&e, 1);
    assert_eq!(gt, ct);
    assert_eq!(gpu.len(), 20000);
    let mut counts = [0usize; 31];
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!((g.id, g.age, g.lifetime), (c.id, c.age, c.lifetime));
        assert_eq!(g.lifetime, Some(0.5));
        // One step done: the age is the starting age and that step.
        let start = (g.age / 0.01).round() as usize - 1;
        counts[start] += 1;
    }
    // Each of the 31 starting ages holds 1/31 of the particles: binomial, 20000 draws, so
    // each count within 5 standard deviations (sqrt(n p (1 - p)) = 25) of 645.
    for (k, &n) in counts.iter().enumerate() {
        assert!(
            (n as f64 - 20000.0 / 31.0).abs() < 5.0 * 25.0,
            "{k} steps: {n} particles"
        );
    }
    // They die as their clocks run out: after 20 steps those that started 30 steps in (lived
    // 50 of 50 steps) are gone, and the totals agree step by step.
    let (gt, gpu) = run_gpu(&e, 21);
    let (ct, cpu) = run_cpu(&e, 21);
    assert_eq!(gt, ct);
    assert!(gt.died > 0 && gt.died < 20000, "{gt:?}");
    assert!(gpu
        .iter()
        .zip(&cpu)
        .all(|(g, c)| (g.id, g.age) == (c.id, c.age)));
    assert!(gpu.iter().all(|g| g.age < 0.5 + 1e-9));
    // A stateless effect cannot start particles at ages of their own.
    let bad = src.replace("capacity: 30000,", "capacity: 30000, state: Stateless,");
    let err = plume::compile_str(&bad, &CompileOptions::default()).unwrap_err();
    assert!(
        err.render("ages.ron", &bad).contains("emitters[0].age"),
        "{}",
        err.render("ages.ron", &bad)
    );
}

#[test]
fn drawn_burst_counts_and_gaps_are_uniform_and_the_same_on_the_gpu() {
    // `burst: (1, 100)` and `every: Some((1.0, 4.0))` at dt = 0.01: each burst's count a
    // whole number from 1 to 100 and each gap 100 to 400 whole steps, drawn from the
    // emitter's key by the schedule that the GPU runtime and the reference share.
    let src = r#"Effect(
    name: "random",
    capacity: 20000,
    seed: 9,
    dt: 0.01,
    emitters: [Emitter(burst: (1, 100), every: Some((1.0, 4.0)), shape: Sphere(center: (0.0, 0.0, 0.0), radius: 5.0),
        velocity: Radial(speed: (2.0, 2.0)), lifetime: Some((5.0, 5.0)))],
    forces: [Gravity((0.0, 5.0, 0.0))],
)"#;
    let e = compile(src);
    let timing = e.ir.emitters[0].timing;
    // 4,000 draws of each: the counts' 100 values and the gaps' 301 each near their share
    // (binomial: within 5 standard deviations).
    let n = 4000u32;
    let mut counts = vec![0usize; 101];
    let mut gaps = vec![0usize; 401];
    for i in 0..n {
        counts[timing.burst_count(i, (1, 100)) as usize] += 1;
        let gap = timing.burst_step(i + 1).unwrap() - timing.burst_step(i).unwrap();
        gaps[gap as usize] += 1;
    }
    assert_eq!(counts[0], 0);
    for (k, &c) in counts.iter().enumerate().skip(1) {
        assert_fraction(&format!("a burst of {k}"), c, n as usize, 1.0 / 100.0);
    }
    assert!(gaps[..100].iter().all(|&g| g == 0), "a gap under 100 steps");
    let (short, long) = (
        gaps[100..250].iter().sum::<usize>(),
        gaps[250..=400].iter().sum::<usize>(),
    );
    assert_fraction("gaps under 2.5 s", short, n as usize, 150.0 / 301.0);
    assert_eq!(short + long, n as usize);
    // The GPU spawns what the reference does, step by step: same totals, same particles.
    let worst = worst_gpu_distance(&e, 1200);
    assert!(
        worst < roundings_per_step(&e.ir) * 1200.0 * U32,
        "{worst:e}"
    );
    let (totals, _) = run_cpu(&e, 1200);
    assert!(totals.spawned > 100, "{totals:?}");
}

#[test]
fn a_torus_spawns_on_its_surface_by_area_and_in_its_volume_uniformly() {
    // A ring of radius 1 and tube 0.5 about z, on the GPU as in the reference (the Newton
    // inversion of θ in f32 against f64 within TRIG). The outer half of the tube (cos θ > 0)
    // holds 1/2 + r/(π R) of the surface's area and 1/2 + 2r/(3π R) of the volume.
    let (big, tube) = (1.0, 0.5);
    for (surface, outer) in [
        (true, 0.5 + tube / (std::f64::consts::PI * big)),
        (false, 0.5 + 2.0 * tube / (3.0 * std::f64::consts::PI * big)),
    ] {
        let points = positions(&format!(
            "Torus(center: (0.0, 0.0, 0.0), axis: (0.0, 0.0, 1.0), radius: {big}, tube: {tube}, surface: {surface})"
        ));
        let mut outside = 0;
        for p in &points {
            let from_circle = (p.x.hypot(p.y) - big).hypot(p.z);
            match surface {
                true => assert!((from_circle - tube).abs() < 1e-5, "{p} is off the surface"),
                false => assert!(from_circle <= tube + 1e-5, "{p} is outside the tube"),
            }
            outside += usize::from(p.x.hypot(p.y) > big);
        }
        assert_fraction(
            &format!("outer half, surface: {surface}"),
            outside,
            points.len(),
            outer,
        );
    }
}
