//! Colliders: swept contacts never tunnel (1,000 m/s against a 0.5 m sphere, a 1 cm box and a
//! height field's ridge, under every integrator), containers keep everything in, contacts on
//! the GPU match the f64 reference, and particles at rest on a collider stay at rest.

mod common;

use common::*;
use plume::compiler::colliders::Surface;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;

const INTEGRATORS: &[&str] = &["Euler", "SemiImplicitEuler", "Verlet", "Midpoint", "Rk4"];

/// A height field over x, z in [-10, 10] whose middle column of samples is a 5 m ridge along z.
const RIDGE: &str = "HeightField(min: (-10.0, -10.0), max: (10.0, 10.0), heights: [[0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0]], restitution: 1.0, friction: 0.0)";

fn shot(collider: &str, integrator: &str, from: (f64, f64, f64), velocity: &str) -> String {
    format!(
        r#"Effect(
    name: "shot",
    capacity: 500,
    seed: 3,
    dt: 0.016666667,
    emitters: [Emitter(burst: 500, shape: Disc(center: {from:?}, normal: (1.0, 0.0, 0.0), radius: 0.3),
                       velocity: {velocity})],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: {integrator},
    collide: [{collider}],
)"#
    )
}

/// Runs the GPU and the reference step by step and checks `ok` on every particle after every
/// step; returns both final record sets.
fn every_step(
    src: &str,
    steps: u32,
    ok: impl Fn(&plume::compiler::reference::ParticleRecord) -> Result<(), String>,
) {
    let e = compile(src);
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e.clone()).unwrap();
    let mut cpu = ReferenceSim::new(&e.ir);
    for step in 1..=steps {
        sim.run(1, |_| {}).unwrap();
        cpu.step();
        for (side, records) in [("gpu", sim.records().unwrap()), ("cpu", cpu.records())] {
            assert_eq!(records.len(), 500, "{side}: particles were lost");
            for r in &records {
                if let Err(why) = ok(r) {
                    panic!("{side}, step {step}: particle {}: {why}\n{src}", r.id);
                }
            }
        }
    }
}

#[test]
fn particles_at_1000_m_s_bounce_off_thin_colliders_under_every_integrator() {
    // 16.7 m per step: every target is crossed within one step if sampled at step ends.
    let targets = [
        (
            "a sphere of radius 0.5 m",
            "Sphere(center: (0.0, 0.0, 0.0), radius: 0.5, restitution: 1.0, friction: 0.0)",
            (-20.0, 0.0, 0.0),
        ),
        (
            "a box 1 cm thick",
            "Box(min: (-0.005, -1.0, -1.0), max: (0.005, 1.0, 1.0), restitution: 1.0, friction: 0.0)",
            (-20.0, 0.0, 0.0),
        ),
        ("a height field's ridge", RIDGE, (-9.0, 2.0, 0.0)),
    ];
    for (what, collider, from) in targets {
        for integrator in INTEGRATORS {
            let src = shot(collider, integrator, from, "Constant((1000.0, 0.0, 0.0))");
            let surface = compile(&src).ir.colliders[0].surface.clone();
            every_step(&src, 6, |r| {
                if !surface.allows(r.position) {
                    return Err(format!("inside {what} at {:?}", r.position));
                }
                // Past the target means it went through.
                if r.position.x > 0.0 {
                    return Err(format!("passed through {what}: at {:?}", r.position));
                }
                Ok(())
            });
        }
    }
}

#[test]
fn containers_keep_every_particle_in_at_1000_m_s() {
    for (what, collider) in [
        (
            "a sphere",
            "Sphere(center: (0.0, 0.0, 0.0), radius: 2.0, restitution: 0.9, friction: 0.1, inside: true)",
        ),
        (
            "a box",
            "Box(min: (-2.0, -1.0, -1.5), max: (2.0, 1.0, 1.5), restitution: 0.9, friction: 0.1, inside: true)",
        ),
    ] {
        for integrator in INTEGRATORS {
            let src = shot(collider, integrator, (0.0, 0.0, 0.0), "Radial(speed: (500.0, 1000.0))")
                .replace("Disc(center: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0), radius: 0.3)", "Sphere(center: (0.0, 0.0, 0.0), radius: 0.5)");
            let surface = compile(&src).ir.colliders[0].surface.clone();
            every_step(&src, 8, |r| {
                if surface.allows(r.position) {
                    Ok(())
                } else {
                    Err(format!("escaped {what}: at {:?}", r.position))
                }
            });
        }
    }
}

#[test]
fn contacts_on_the_gpu_match_the_reference() {
    // Two steps of a fast shot at each collider: where the contact puts the particle and its
    // outgoing velocity. f32 positions differ from f64 by a few ulps of |x| per operation
    // (measured: at most 23 ulps of 1 + |x|, 5 away from spheres), so 32 ulps bound the
    // position. The outgoing velocity turns with the contact normal; on a sphere of radius r
    // the normal turns by (position error) / r, so the velocity bound is 32 ulps of 1 + |v|
    // times 1 + (1 + |x|) / r there (measured: at most 126 ulps on a 0.5 m sphere at 2 m).
    let targets = [
        ("Sphere(center: (0.0, 0.0, 0.0), radius: 0.5, restitution: 0.7, friction: 0.2)", (-2.0, 1.0, 0.0), Some(0.5)),
        ("Box(min: (-0.005, -1.0, -1.0), max: (0.005, 1.0, 1.0), restitution: 0.7, friction: 0.2)", (-2.0, 1.0, 0.0), None),
        (RIDGE, (-4.5, 1.5, 0.0), None),
        ("Plane(point: (0.0, 0.0, 0.0), normal: (-1.0, 0.3, 0.1), restitution: 0.7, friction: 0.2)", (-2.0, 1.0, 0.0), None),
    ];
    for (collider, from, radius) in targets {
        for integrator in INTEGRATORS {
            let src = shot(
                collider,
                integrator,
                from,
                "Cone(axis: (1.0, -0.2, 0.0), angle: 10.0, speed: (50.0, 80.0))",
            );
            let e = compile(&src);
            let (_, gpu) = run_gpu(&e, 2);
            let (_, cpu) = run_cpu(&e, 2);
            let mut bounced = 0;
            for (g, c) in gpu.iter().zip(&cpu) {
                assert_eq!(g.id, c.id);
                let dx = (g.position - c.position).length();
                let dv = (g.velocity - c.velocity).length();
                let turn = radius.map_or(1.0, |r| 1.0 + (1.0 + c.position.length()) / r);
                assert!(
                    dx <= 32.0 * U32 * (1.0 + c.position.length()),
                    "{collider} {integrator}: particle {} at {:?} on the GPU, {:?} in f64",
                    g.id,
                    g.position,
                    c.position
                );
                assert!(
                    dv <= 32.0 * U32 * (1.0 + c.velocity.length()) * turn,
                    "{collider} {integrator}: particle {} moves at {:?} on the GPU, {:?} in f64",
                    g.id,
                    g.velocity,
                    c.velocity
                );
                bounced += usize::from(c.velocity.x < 0.0 || c.velocity.y > 10.0);
            }
            assert!(
                bounced > 100,
                "{collider} {integrator}: only {bounced} bounced"
            );
        }
    }
}

#[test]
fn particles_at_rest_on_a_collider_stay_there_for_10000_steps() {
    // Each particle starts on top of a collider with no velocity; gravity presses it down
    // every step. It must neither sink nor hop: after 10,000 steps it is where it started,
    // within 16 contact margins, and still at rest.
    let cases = [
        ("Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.2)", (0.0, 0.0, 0.0)),
        ("Sphere(center: (0.0, -1.0, 0.0), radius: 1.0, restitution: 0.5, friction: 0.2)", (0.0, 0.0, 0.0)),
        ("Sphere(center: (0.0, 1.0, 0.0), radius: 1.0, restitution: 0.5, friction: 0.2, inside: true)", (0.0, 0.0, 0.0)),
        ("Box(min: (-1.0, -0.01, -1.0), max: (1.0, 0.0, 1.0), restitution: 0.5, friction: 0.2)", (0.3, 0.0, 0.2)),
        ("Box(min: (-1.0, 0.0, -1.0), max: (1.0, 2.0, 1.0), restitution: 0.5, friction: 0.2, inside: true)", (0.3, 0.0, 0.2)),
        ("HeightField(min: (-2.0, -2.0), max: (2.0, 2.0), heights: [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], restitution: 0.5, friction: 0.2)", (0.5, 0.0, 0.5)),
    ];
    for (collider, at) in cases {
        for integrator in ["SemiImplicitEuler", "Verlet", "Rk4"] {
            let src = format!(
                r#"Effect(
    name: "rest",
    capacity: 1,
    dt: 0.016666667,
    emitters: [Emitter(burst: 1, shape: Point({at:?}), velocity: Constant((0.0, 0.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: {integrator},
    collide: [{collider}],
)"#
            );
            let e = compile(&src);
            let start = glam::DVec3::new(at.0, at.1, at.2);
            let tolerance = 16.0 * plume::compiler::colliders::MARGIN;
            for (side, records) in [
                ("gpu", run_gpu(&e, 10_000).1),
                ("cpu", run_cpu(&e, 10_000).1),
            ] {
                let r = &records[0];
                assert!(
                    (r.position - start).length() <= tolerance,
                    "{side} {integrator} {collider}: moved from {start:?} to {:?}",
                    r.position
                );
                assert!(
                    r.velocity.length() <= 0.2,
                    "{side} {integrator} {collider}: still moving at {:?} m/s",
                    r.velocity
                );
                assert!(e.ir.colliders[0].surface.allows(r.position), "{side}: sank");
            }
        }
    }
}

#[test]
fn the_contact_test_is_exact_inside_a_height_field_cell() {
    // A segment through a saddle cell: the swept test's contact lies on the bilinear surface
    // (to f64 rounding) and no earlier point of the segment is below it.
    let e = compile(&shot(
        "HeightField(min: (0.0, 0.0), max: (1.0, 1.0), heights: [[0.0, 1.0], [1.0, 0.0]], restitution: 0.5, friction: 0.0)",
        "SemiImplicitEuler",
        (0.0, 2.0, 0.0),
        "Constant((0.0, 0.0, 0.0))",
    ));
    let Surface::HeightField(field) = &e.ir.colliders[0].surface else {
        panic!("not a height field")
    };
    let a = glam::DVec3::new(0.1, 2.0, 0.2);
    let b = glam::DVec3::new(0.9, -1.0, 0.7);
    let hit = field.hit(a, b).expect("the segment crosses the surface");
    let p = a + (b - a) * hit.s;
    assert!(
        (p.y - field.height(p.x, p.z)).abs() < 1e-12,
        "contact {p:?} is off the surface"
    );
    for i in 0..1000 {
        let q = a + (b - a) * (hit.s * i as f64 / 1000.0);
        assert!(
            q.y >= field.height(q.x, q.z) - 1e-12,
            "{q:?} is below the surface before the contact"
        );
    }
    assert!(hit.normal.y > 0.0 && (hit.normal.length() - 1.0).abs() < 1e-12);
}

/// RIDGE as a 5 x 3 grey image (white middle column, 0 to 5 m), written to a fresh folder.
fn ridge_image(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-colliders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut grey = image::GrayImage::new(5, 3);
    for (x, _, p) in grey.enumerate_pixels_mut() {
        p.0 = [if x == 2 { 255 } else { 0 }];
    }
    let path = dir.join(name);
    grey.save(&path).unwrap();
    path
}

#[test]
fn a_height_field_read_from_an_image_is_the_field_it_draws_and_collides_as_written() {
    let path = ridge_image("ridge.png");
    let from_image = RIDGE.replace(
        "heights: [[0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0]]",
        &format!("image: Some({:?}), height: Some((0.0, 5.0))", path.display().to_string()),
    );
    let cone = "Cone(axis: (1.0, -0.2, 0.0), angle: 10.0, speed: (50.0, 80.0))";
    let by_image = compile(&shot(
        &from_image,
        "SemiImplicitEuler",
        (-4.5, 1.5, 0.0),
        cone,
    ));
    let by_hand = compile(&shot(RIDGE, "SemiImplicitEuler", (-4.5, 1.5, 0.0), cone));
    assert_eq!(by_image.ir.colliders, by_hand.ir.colliders);
    // And the GPU collides with it as the reference does, bit for bit with the hand-written
    // field's run (the same IR, the same kernels).
    let (_, gpu) = run_gpu(&by_image, 2);
    let (_, hand) = run_gpu(&by_hand, 2);
    let (_, cpu) = run_cpu(&by_image, 2);
    assert_eq!(gpu, hand);
    for (g, c) in gpu.iter().zip(&cpu) {
        assert!((g.position - c.position).length() <= 32.0 * U32 * (1.0 + c.position.length()));
    }
    assert!(
        cpu.iter().filter(|c| c.velocity.x < 0.0).count() > 100,
        "the ridge was hit"
    );
}

#[test]
fn height_field_image_errors_are_located_at_the_field() {
    let path = ridge_image("ridge-err.png").display().to_string();
    let heights = "heights: [[0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0], [0.0, 0.0, 5.0, 0.0, 0.0]]";
    let cases = [
        (
            RIDGE.replace(
                heights,
                "image: Some(\"no/such/terrain.png\"), height: Some((0.0, 5.0))",
            ),
            "collide[0] (HeightField).image: cannot open height image `no/such/terrain.png`",
        ),
        (
            RIDGE.replace(heights, &format!("image: Some({path:?})")),
            "collide[0] (HeightField).image: an image needs `height: (black, white)`",
        ),
        (
            RIDGE.replace(
                heights,
                &format!("{heights}, image: Some({path:?}), height: Some((0.0, 1.0))"),
            ),
            "not both",
        ),
        (
            RIDGE.replace(heights, "height: Some((0.0, 1.0))"),
            "collide[0] (HeightField).height: `height` gives the heights of black and white",
        ),
    ];
    for (collider, expected) in cases {
        let src = shot(
            &collider,
            "Euler",
            (0.0, 1.0, 0.0),
            "Constant((1.0, 0.0, 0.0))",
        );
        let error = plume::compile_str(&src, &Default::default()).unwrap_err();
        let text = error.render("shot.ron", &src);
        assert!(
            text.contains(expected) && text.contains("shot.ron:10:"),
            "{text}"
        );
    }
}
