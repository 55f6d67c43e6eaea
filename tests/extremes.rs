//! Numerical extremes on the GPU (llvmpipe in CI) and in the f64 reference: degenerate
//! geometry, step sizes from 1e-6 s to 1 s, coordinates up to 1e6 m, a million steps, hundreds
//! of force terms. Never a NaN or an Inf; where precision is lost, the compiler says so.

mod common;

use common::*;
use plume::compiler::reference::{ParticleRecord, ReferenceSim};
use plume::{compile_str, CompileOptions, Integrator};

fn assert_finite(what: &str, records: &[ParticleRecord]) {
    for r in records {
        assert!(
            r.position.is_finite() && r.velocity.is_finite(),
            "{what}: particle {} is not finite: {:?} {:?}",
            r.id,
            r.position,
            r.velocity
        );
    }
}

/// Runs `src` with every integrator allowed (Exact only where it compiles) on GPU and CPU.
fn all_integrators_finite(what: &str, src: &str, steps: u64) {
    for integrator in Integrator::CONCRETE {
        let options = CompileOptions {
            integrator: Some(integrator),
            ..Default::default()
        };
        let Ok(e) = compile_str(src, &options) else {
            assert_eq!(
                integrator,
                Integrator::Exact,
                "{what}: {integrator:?} does not compile"
            );
            continue;
        };
        let (_, gpu) = run_gpu(&e, steps);
        let (_, cpu) = run_cpu(&e, steps);
        assert!(!gpu.is_empty(), "{what}: nothing alive");
        assert_finite(&format!("{what}, {integrator:?}, gpu"), &gpu);
        assert_finite(&format!("{what}, {integrator:?}, cpu"), &cpu);
    }
}

#[test]
fn degenerate_geometry_stays_finite() {
    // Particles exactly at an attractor's centre, on a vortex axis, on a plane; tiny ranges and
    // heights; a vortex with no spin; radial velocity from a point; zero-radius shapes; cones
    // of 0 and 180 degrees.
    let src = r#"Effect(name: "degenerate", capacity: 64,
    emitters: [
        Emitter(burst: 8, shape: Point((0.0, 4.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(burst: 8, shape: Point((0.0, 1.0, 0.0)), velocity: Radial(speed: (0.0, 0.0))),
        Emitter(burst: 8, shape: Sphere(center: (5.0, 0.0, 5.0), radius: 0.0), velocity: Radial(speed: (1.0, 2.0))),
        Emitter(burst: 8, shape: Disc(center: (2.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 0.0),
                velocity: Cone(axis: (0.0, -1.0, 0.0), angle: 0.0, speed: (3.0, 3.0))),
        Emitter(burst: 8, shape: Box(min: (1.0, 1.0, 1.0), max: (1.0, 1.0, 1.0)),
                velocity: Cone(axis: (1.0, 0.0, 0.0), angle: 180.0, speed: (1.0, 1.0))),
        Emitter(burst: 8, shape: Grid(min: (0.0, 0.0, 0.0), max: (0.0, 0.0, 0.0), counts: (1, 1, 1)),
                velocity: Constant((1.0, 0.0, 0.0))),
    ],
    forces: [
        Attractor(center: (0.0, 4.0, 0.0), range: 3.0, strength: 8.0),
        Attractor(center: (1.0, 1.0, 1.0), range: 1e-6, strength: 100.0),
        Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 2.0, height: 6.0, spin: 5.0, pull: 1.0),
        Vortex(center: (5.0, 0.0, 5.0), axis: (0.0, 1.0, 0.0), range: 1e-6, height: 1e-6, spin: 5.0),
        Vortex(center: (0.0, 0.0, 0.0), axis: (1.0, 1.0, 0.0), range: 2.0, height: 6.0, spin: 0.0, pull: 2.0, curve: 3.0),
        Wind(direction: (0.0, 0.0, 1.0), strength: 0.0, noise: 2.0),
    ],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 1.0, friction: 1.0)],
)"#;
    all_integrators_finite("degenerate", src, 60);
}

#[test]
fn step_sizes_from_a_microsecond_to_a_second_stay_finite() {
    for dt in [1e-6, 1e-4, 1e-2, 0.1, 1.0] {
        let src = format!(
            r#"Effect(name: "dt", capacity: 256, dt: {dt:?},
    emitters: [Emitter(burst: 200, shape: Sphere(center: (0.0, 3.0, 0.0), radius: 1.0), velocity: Radial(speed: (0.0, 20.0)))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.4), Attractor(center: (0.0, 3.0, 0.0), range: 3.0, strength: 2.0),
             Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 2.0, height: 6.0, spin: 1.0),
             Wind(direction: (1.0, 0.0, 0.0), strength: 0.5, noise: 0.5)],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.1)],
)"#
        );
        all_integrators_finite(&format!("dt = {dt}"), &src, 40);
    }
}

#[test]
fn far_coordinates_warn_about_precision_and_verlet_does_not_freeze() {
    // At 1e6 m f32 keeps positions to 0.06 m: the compiler warns.
    let far = r#"Effect(name: "far", capacity: 4,
    emitters: [Emitter(burst: 4, shape: Point((1e6, 1e6, 1e6)), velocity: Constant((1.0, 0.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))], integrator: Verlet,
)"#;
    let e = compile(far);
    assert!(
        e.warnings
            .items
            .iter()
            .any(|w| w.message.contains("kept in f32")),
        "{:?}",
        e.warnings
    );
    let (_, r) = run_gpu(&e, 60);
    assert_finite("far", &r);
    // A particle falling from y = 1e4 at dt = 1/240 with Verlet: plain position Verlet
    // (x' = 2x - x_prev) quantises velocity to ulp(1e4)/dt = 0.23 m/s and freezes; the
    // displacement form must fall 4.905 m in 1 s, to within the f32 spacing times the steps.
    let fall = r#"Effect(name: "fall", capacity: 1, dt: 0.004166666666666667,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 10000.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))], integrator: Verlet,
)"#;
    let (_, r) = run_gpu(&compile(fall), 240);
    let y = r[0].position.y;
    let expected = 10000.0 - 0.5 * 9.81;
    assert!(
        (y - expected).abs() < 0.15,
        "Verlet at y = 1e4 fell to {y}, expected {expected}"
    );
    assert!(
        (r[0].velocity.y + 9.81).abs() < 0.3,
        "velocity {:?}",
        r[0].velocity
    );
}

#[test]
fn a_million_steps_of_a_steady_effect_do_not_drift() {
    // 60/s living 0.5 s (30 steps): after each step's deaths 29 are alive (rate x lifetime less
    // the one step's spawn that has just died); a noisy wind so the time phase matters.
    let src = r#"Effect(name: "steady", capacity: 64, dt: 0.016666666666666666,
    emitters: [Emitter(rate: 60.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)),
                       lifetime: Some((0.5, 0.5)))],
    forces: [Wind(direction: (1.0, 0.0, 0.0), strength: 0.5, noise: 1.0)],
)"#;
    let e = compile(src);
    let steps = 1_000_000u64;
    let (t, gpu) = run_gpu(&e, steps);
    assert_eq!(t.spawned, steps, "one spawn a step, exactly");
    assert_eq!(t.alive, 29, "rate x lifetime less one step's spawn");
    assert_eq!(t.dropped, 0);
    // Ages are whole steps times dt, computed in f64: no drift after 1e6 steps.
    let mut ages: Vec<f64> = gpu.iter().map(|r| r.age).collect();
    ages.sort_by(f64::total_cmp);
    for (i, a) in ages.iter().enumerate() {
        assert!(
            (a - (i + 1) as f64 / 60.0).abs() < 1e-9,
            "age {a} of the {i}-th youngest"
        );
    }
    // The same particles, at the same places, as the f64 reference that ran a million steps too.
    let mut cpu = ReferenceSim::new(&e.ir);
    cpu.run(steps);
    let cpu = cpu.records();
    assert_eq!(
        gpu.iter().map(|r| r.id).collect::<Vec<_>>(),
        cpu.iter().map(|r| r.id).collect::<Vec<_>>()
    );
    for (g, c) in gpu.iter().zip(&cpu) {
        // Each particle lived at most 30 steps: the usual 4 N u bound with N = 30.
        assert!(
            (g.position - c.position).length()
                <= 4.0 * 30.0 * U32 * (1.0 + c.position.length()) + 1e-6,
            "particle {}: gpu {:?} cpu {:?}",
            g.id,
            g.position,
            c.position
        );
    }
}

#[test]
fn hundreds_of_force_terms_compile_validate_and_stay_finite() {
    let mut forces = Vec::new();
    for i in 0..300 {
        let a = i as f64 * 0.37;
        forces.push(format!(
            "Attractor(center: ({:.3}, {:.3}, {:.3}), range: 2.0, strength: 0.5)",
            5.0 * a.cos(),
            2.0 + (a * 0.5).sin(),
            5.0 * a.sin()
        ));
        if i % 3 == 0 {
            forces.push(format!(
                "Vortex(center: ({:.3}, 0.0, {:.3}), axis: (0.0, 1.0, 0.0), range: 1.5, height: 5.0, spin: 0.5, pull: 0.2)",
                4.0 * a.sin(),
                4.0 * a.cos()
            ));
        }
    }
    let src = format!(
        r#"Effect(name: "many", capacity: 512,
    emitters: [Emitter(burst: 500, shape: Box(min: (-6.0, 0.0, -6.0), max: (6.0, 4.0, 6.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    forces: [{}],
)"#,
        forces.join(",\n             ")
    );
    let e = compile(&src);
    assert_eq!(e.ir.terms.len(), 400);
    let (_, gpu) = run_gpu(&e, 30);
    assert_finite("400 terms", &gpu);
    let (_, cpu) = run_cpu(&e, 30);
    for (g, c) in gpu.iter().zip(&cpu) {
        assert!(
            (g.position - c.position).length()
                <= 4.0 * 30.0 * U32 * 400.0 * (1.0 + c.position.length())
        );
    }
}
