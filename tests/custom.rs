//! Custom forces: expressions equal to built-in forces give the built-ins' trajectories (the
//! f64 reference exactly, the GPU within f32 rounding), the particle context (t, age, life,
//! rand) reaches the GPU as the reference sees it, and the passes treat custom terms honestly.

mod common;

use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::compiler::{compile_str, CompileError, CompileOptions};

/// An effect with `forces` and the given integrator, a spray of particles with lifetimes.
fn effect(forces: &str, integrator: &str, extra: &str) -> String {
    format!(
        r#"Effect(
    name: "custom",
    capacity: 4000,
    seed: 5,
    dt: 0.016666667,
    substeps: 2,
    params: {{"k": 0.8, "g": 9.81, "R": 3.0, "S": 4.0, "c": 0.5}},
    emitters: [Emitter(burst: 300, rate: 600.0, shape: Sphere(center: (0.5, 1.0, 0.0), radius: 1.0),
                       velocity: Radial(speed: (0.5, 2.0)), lifetime: Some((1.0, 3.0)))],
    forces: [{forces}],
    integrator: {integrator},
    {extra}
)"#
    )
}

/// Pairs of force lists that mean the same: built-ins, and custom expressions written to
/// compute the same f64 operations in the same order.
const SAME: &[(&str, &str, &str)] = &[
    (
        "gravity",
        "Gravity((0.0, -9.81, 0.0))",
        r#"Custom(accel: "vec3(0.0, -g, 0.0)")"#,
    ),
    (
        "drag",
        "Drag(k: 0.8, fluid: (1.0, 0.0, -0.5))",
        r#"Custom(accel: "k * (vec3(1.0, 0.0, -0.5) - v)")"#,
    ),
    (
        "attractor with its core",
        "Attractor(center: (0.0, 1.0, 0.0), range: 3.0, strength: 4.0, core: 0.5)",
        r#"Custom(accel: "S * clamp((R - length(vec3(0.0, 1.0, 0.0) - x)) / R, 0.0, 1.0) * ((vec3(0.0, 1.0, 0.0) - x) / max(length(vec3(0.0, 1.0, 0.0) - x), c))")"#,
    ),
];

#[test]
fn expressions_equal_to_built_ins_give_their_trajectories() {
    for integrator in ["SemiImplicitEuler", "Verlet", "Rk4"] {
        for (name, builtin, custom) in SAME {
            let a = compile(&effect(builtin, integrator, ""));
            let b = compile(&effect(custom, integrator, ""));
            // The reference runs the very same f64 operations: equal bit for bit.
            let (ca, cb) = (run_cpu(&a, 90), run_cpu(&b, 90));
            assert_eq!(ca.0, cb.0, "{name} {integrator}: totals");
            assert!(!ca.1.is_empty());
            for (p, q) in ca.1.iter().zip(&cb.1) {
                assert_eq!(p, q, "{name} {integrator}: reference differs");
            }
            // The GPU: the guards' clamps change nothing here, so only the order of f32
            // roundings differs (a few per step, the same bound as tests/gpu_vs_reference.rs).
            let (ga, gb) = (run_gpu(&a, 90), run_gpu(&b, 90));
            assert_eq!(ga.0, gb.0, "{name} {integrator}: GPU totals");
            let tol = 4.0 * 90.0 * U32;
            for (p, q) in ga.1.iter().zip(&gb.1) {
                assert_eq!(p.id, q.id);
                let d = (p.position - q.position).length();
                assert!(
                    d <= tol * (1.0 + p.position.length()),
                    "{name} {integrator}: particle {} built-in {:?} custom {:?}",
                    p.id,
                    p.position,
                    q.position
                );
            }
        }
    }
}

#[test]
fn the_particle_context_matches_the_reference_on_the_gpu() {
    // Reads t (whole seconds, not wrapped), age, life and per-particle random numbers, through
    // the update (every integrator) and Verlet's spawn.
    let force = r#"Custom(accel: "vec3(sin(2.0 * t) * rand(0), -g * smoothstep(0.0, life, age), (rand(1) - 0.5) * age)")"#;
    for integrator in ["SemiImplicitEuler", "Verlet", "Midpoint"] {
        let e = compile(&effect(force, integrator, ""));
        assert!(
            !e.ir.wraps_kernel_time(),
            "t is read, so time is not wrapped"
        );
        let worst = worst_gpu_distance(&e, 100);
        assert!(worst <= 4.0 * 100.0 * U32, "{integrator}: {worst:e}");
    }
}

#[test]
fn time_is_not_wrapped_when_an_expression_reads_it() {
    // dt = 1 s: after 256 s (the noise period kernels otherwise see time modulo) the force
    // switches on. A wrapped time would never reach 256 on the GPU.
    let src = r#"Effect(
    name: "late",
    capacity: 10,
    dt: 1.0,
    emitters: [Emitter(burst: 4, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0), velocity: Constant((0.0, 0.0, 0.0)))],
    forces: [Custom(accel: "vec3(step(256.0, t) * 0.01, 0.0, 0.0)")],
    integrator: SemiImplicitEuler,
)"#;
    let e = compile(src);
    let (_, cpu) = run_cpu(&e, 300);
    let (_, gpu) = run_gpu(&e, 300);
    for (g, c) in gpu.iter().zip(&cpu) {
        assert!(
            c.velocity.x > 0.4,
            "the reference switched on at 256 s: {:?}",
            c.velocity
        );
        assert!(
            (g.velocity.x - c.velocity.x).abs() < 1e-4,
            "gpu {:?} cpu {:?}",
            g.velocity,
            c.velocity
        );
    }
}

#[test]
fn a_constant_expression_is_a_constant_term_and_keeps_exact_and_stateless() {
    let e = compile(&effect(
        r#"Custom(accel: "vec3(0.0, -g * 0.5, 0.0) * 2.0")"#,
        "Auto",
        "",
    ));
    assert_eq!(e.ir.integrator, plume::Integrator::Exact);
    assert!(e.ir.stateless.is_some());
    let zero = compile(&effect(
        r#"Gravity((0.0, -1.0, 0.0)), Custom(accel: "x * (k - 0.8)")"#,
        "Rk4",
        "",
    ));
    assert!(
        zero.ir.custom_terms().next().is_none(),
        "an expression that folds to zero is pruned: {:?}",
        zero.ir.terms
    );
}

#[test]
fn exact_is_refused_naming_what_the_expression_reads() {
    let src = effect(
        r#"Custom(accel: "-k * v + vec3(0.0, sin(t), 0.0)")"#,
        "Exact",
        "",
    );
    let Err(CompileError::Invalid(d)) = compile_str(&src, &CompileOptions::default()) else {
        panic!("Exact with a custom force compiled");
    };
    let text = d.render("t.ron", &src);
    assert!(
        text.contains("forces[0] (Custom) is a custom expression that reads v and t"),
        "{text}"
    );
    let auto = compile(&effect(r#"Custom(accel: "-k * v")"#, "Auto", ""));
    assert!(
        auto.ir.integrator_reason.contains("reads v"),
        "{}",
        auto.ir.integrator_reason
    );
}

#[test]
fn stiff_expressions_warn_with_an_estimate() {
    // A spring toward the origin: omega = sqrt(40000) = 200 rad/s, omega h = 1.67 per substep
    // of 1/120 s: under SemiImplicitEuler's limit 2. A stiffer one (omega h = 3.3) is past it.
    let soft = compile(&effect(
        r#"Custom(accel: "-40000.0 * x")"#,
        "SemiImplicitEuler",
        "",
    ));
    assert!(soft.warnings.is_empty(), "{}", soft.warnings);
    let stiff = compile(&effect(
        r#"Custom(accel: "-160000.0 * x")"#,
        "SemiImplicitEuler",
        "",
    ));
    let text = stiff.warnings.to_string();
    assert!(
        text.contains("forces[0] (Custom).accel")
            && text.contains("estimated")
            && text.contains("ω = 400.0"),
        "{text}"
    );
    // Velocity dependence is a damping rate: k h = 300 / 120 = 2.5 is past the limit 2.
    let damped = compile(&effect(
        r#"Custom(accel: "-300.0 * v")"#,
        "SemiImplicitEuler",
        "",
    ));
    let text = damped.warnings.to_string();
    assert!(
        text.contains("k*h = 2.500") && text.contains("estimated"),
        "{text}"
    );
}

#[test]
fn a_term_that_acts_only_at_spawn_is_no_stiffness_but_one_that_acts_later_is() {
    // A kick in the first substep: k h = 300 / 120 = 2.5, past the limit, but only once.
    let kick = compile(&effect(
        r#"Custom(accel: "select(vec3(0.0, 0.0, 0.0), -300.0 * v, age < 0.5 * dt)")"#,
        "SemiImplicitEuler",
        "",
    ));
    assert!(kick.warnings.is_empty(), "{}", kick.warnings);
    // The same damping from half a second of age on acts for the rest of the particle's life.
    let later = compile(&effect(
        r#"Custom(accel: "select(vec3(0.0, 0.0, 0.0), -300.0 * v, age > 0.5)")"#,
        "SemiImplicitEuler",
        "",
    ));
    let text = later.warnings.to_string();
    assert!(
        text.contains("k*h = 2.500") && text.contains("estimated"),
        "{text}"
    );
}

#[test]
fn the_layout_keeps_the_spawn_step_only_for_age_and_life() {
    use plume::compiler::passes::layout::Attribute;
    let plain = compile(&effect(r#"Custom(accel: "-k * x * rand(2)")"#, "Rk4", ""));
    assert!(!plain.layout.has(Attribute::SpawnStep));
    assert!(plain.wgsl.contains("ctx_id = p.id;"));
    let aged = compile(&effect(r#"Custom(accel: "-k * x * age")"#, "Rk4", ""));
    assert!(aged.layout.has(Attribute::SpawnStep));
    assert!(aged.wgsl.contains("ctx_age0 = f32(params.step - p.born)"));
    let none = compile(&effect(r#"Custom(accel: "-k * x")"#, "Rk4", ""));
    assert!(
        !none.wgsl.contains("ctx_"),
        "no context unless an expression reads it"
    );
}

#[test]
fn the_example_traps_particles_and_keeps_their_speed() {
    // effects/magnetic_bottle.ron is also in gpu_vs_reference's sweep of the examples; here
    // the particles must stay trapped and finite over a longer run.
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/effects/magnetic_bottle.ron"
    ))
    .unwrap();
    let e = compile(&src);
    let mut sim = ReferenceSim::new(&e.ir);
    sim.run(240);
    let records = sim.records();
    assert!(records.len() > 10_000);
    let trapped = records
        .iter()
        .filter(|r| r.position.x.hypot(r.position.z) < 2.0 && r.position.y.abs() < 3.0)
        .count();
    assert!(
        trapped * 2 > records.len(),
        "{trapped} of {} trapped",
        records.len()
    );
    // Lorentz force does no work: speeds stay what they were at spawn (1.5 to 3 m/s) up to
    // Rk4's error. That error damps where the field is strong (37 times the centre's at the
    // kill sphere, omega h = 0.93 per substep: escaping particles lose a few percent); within
    // |y| < 3 m the field is at most 10 times the centre's (omega h = 0.25), and particles found
    // there never went farther out (escape along the axis is one way).
    for r in records.iter().filter(|r| r.position.y.abs() < 3.0) {
        let s = r.velocity.length();
        assert!((1.495..3.005).contains(&s), "particle {} speed {s}", r.id);
    }
}

#[test]
fn a_vector_param_is_read_whole_and_set_by_its_components() {
    // `wind` is written as a vector; expressions read it as a vec3, and a host sets each
    // component (`wind.x` ...) as it sets a number. Folded when params are constants; read
    // at run time, the same on the GPU as in the reference, with live params.
    let src = r#"Effect(
    name: "vector_param",
    capacity: 200,
    dt: 0.02,
    params: {"wind": (2.0, 0.0, 0.5), "k": 3.0},
    emitters: [Emitter(burst: 100, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
        velocity: Custom("wind * 0.5"))],
    forces: [Custom(accel: "k * (wind - v)")],
    integrator: SemiImplicitEuler,
)"#;
    let folded = compile(src);
    assert!(folded.ir.live_params.is_empty());
    let live = plume::compile_str(
        src,
        &plume::CompileOptions {
            live_params: true,
            ..Default::default()
        },
    )
    .unwrap();
    let names: Vec<&str> = live.ir.live_params.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(names, ["k", "wind.x", "wind.y", "wind.z"]);
    let gpu = gpu();
    let mut gsim = plume::runtime::Effect::new(&gpu, live.clone()).unwrap();
    let mut csim = plume::compiler::reference::ReferenceSim::new(&live.ir);
    gsim.run(10, |_| {}).unwrap();
    csim.run(10);
    for (name, value) in [("wind.x", -1.0f32), ("wind.y", 4.0)] {
        gsim.set_param(name, value).unwrap();
        csim.set_param(name, value).unwrap();
    }
    gsim.run(100, |_| {}).unwrap();
    csim.run(100);
    let (g, c) = (gsim.records().unwrap(), csim.records());
    assert_eq!(g.len(), 100);
    for (p, q) in g.iter().zip(&c) {
        assert_eq!(p.id, q.id);
        let bound = common::compare::roundings_per_step(&live.ir) * 110.0 * U32;
        assert!((p.position - q.position).length() <= bound * (1.0 + q.position.length()));
        // 100 steps of k = 3 at 0.02 s leave (1 - 0.06)^100 = 0.2% of the velocity's distance
        // (5 m/s) from the new wind.
        assert!(
            (q.velocity - glam::DVec3::new(-1.0, 4.0, 0.5)).length() < 0.1,
            "{:?}",
            q.velocity
        );
    }
}
