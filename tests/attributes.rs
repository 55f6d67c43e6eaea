//! Attributes an effect declares (`attributes: {...}`): their values at spawn and after each
//! step on the GPU against the f64 reference, read by custom forces and the draw; exact
//! counts and decays where f32 holds them exactly or nearly; what is pruned and folded; and
//! the refusals.

mod common;

use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::{compile_str, CompileOptions};

/// A spray whose particles carry `heat` (a number that cools at a rate), `spin` (a vec3
/// updated each step from the velocity), `steps` (counts its updates) and `unread` (read by
/// nothing), with a custom force and the draw reading them, in `integrator`.
fn spray(integrator: &str) -> String {
    format!(
        r#"Effect(
    name: "attributes",
    capacity: 800,
    seed: 11,
    dt: 0.02,
    emitters: [Emitter(burst: 200, rate: 300.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
        velocity: Radial(speed: (1.0, 4.0)), lifetime: Some((0.8, 1.6)))],
    attributes: {{
        "heat": (spawn: "1.0 + rand(0) + 0.1 * length(x)", rate: Some("-0.9 * heat + 0.05 * length(v)")),
        "spin": (spawn: "vec3(rand(1) - 0.5, rand(2) - 0.5, rand(3) - 0.5)", update: Some("spin * 0.98 + v * 0.01")),
        "steps": (spawn: "0.0", update: Some("steps + 1.0")),
        "unread": (spawn: "rand(4)"),
        "two": (spawn: "2.0"),
    }},
    forces: [Gravity((0.0, -9.8, 0.0)), Custom(accel: "spin * heat * two - 0.1 * v")],
    integrator: {integrator},
    camera: Camera(eye: (0.0, 0.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 0.9)), (1.0, (0.6, 0.6, 0.6, 0.3))],
        size: [(0.0, 0.12), (1.0, 0.06)], background: (0.0, 0.0, 0.0),
        color_by: Some("vec3(heat, 0.5 * heat, 0.2)"), size_by: Some("0.5 + steps / 100.0")),
)"#
    )
}

fn compiled(src: &str) -> plume::CompiledEffect {
    compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("attributes.ron", src)))
}

#[test]
fn only_what_is_read_is_stored() {
    let e = compiled(&spray("SemiImplicitEuler"));
    // heat (1 word), spin (3) and steps (1) are read by the force or the draw; unread is
    // read by nothing and two is the constant 2 everywhere it is read.
    let words = |name: &str| {
        e.layout
            .words()
            .iter()
            .filter(|(n, _)| n.starts_with(name))
            .count()
    };
    assert_eq!(words("u"), 5, "{:?}", e.layout.words());
    let ir = e.ir.to_string();
    assert!(
        ir.contains("unread f32: read by nothing, not stored"),
        "{ir}"
    );
    assert!(
        ir.contains("two f32: a constant, folded where it is read, not stored"),
        "{ir}"
    );
    assert!(ir.contains("spin vec3 (12 bytes)"), "{ir}");
    // An attribute read only by an attribute that nothing reads is not kept either.
    let src = spray("SemiImplicitEuler").replace(
        r#""unread": (spawn: "rand(4)"),"#,
        r#""unread": (spawn: "rand(4)"), "chain": (spawn: "0.0", update: Some("unread + chain")),"#,
    );
    assert_eq!(compiled(&src).layout.words().len(), e.layout.words().len());
    // Without the draw and the force reading them, nothing is stored, and the WGSL is the
    // same as that of the effect without attributes.
    let plain = |with: bool| {
        format!(
            r#"Effect(name: "p", capacity: 10,
    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))],
    {}
    forces: [Drag(k: 0.5)])"#,
            if with {
                r#"attributes: {"heat": (spawn: "rand(0)", rate: Some("-heat"))},"#
            } else {
                ""
            }
        )
    };
    assert_eq!(compiled(&plain(true)).wgsl, compiled(&plain(false)).wgsl);
}

/// The GPU's attributes against the reference's, word by word.
fn assert_attributes_match(e: &plume::CompiledEffect, steps: u64, tolerance: f64) {
    let (gt, gpu) = run_gpu(e, steps);
    let (ct, cpu) = run_cpu(e, steps);
    assert_eq!(gt, ct, "totals");
    assert!(gpu.len() > 100, "{} alive", gpu.len());
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!(g.id, c.id);
        for (w, (a, b)) in g.attributes.iter().zip(&c.attributes).enumerate() {
            assert!(
                (a - b).abs() <= tolerance * (1.0 + b.abs()),
                "particle {} word {w}: {a} on the GPU, {b} in f64",
                g.id
            );
        }
        assert!(
            (g.position - c.position).length() <= tolerance * (1.0 + c.position.length()),
            "particle {}: at {:?} on the GPU, {:?} in f64",
            g.id,
            g.position,
            c.position
        );
    }
}

#[test]
fn attributes_match_the_reference_on_the_gpu() {
    // 60 steps of f32 against f64: each step rounds each value a few times (a relative 6e-8
    // each), and heat's decay and the force that reads it feed those errors back into the
    // motion at most linearly over so few steps: 8 roundings a step is the same bound as
    // tests/custom.rs's for a custom force that reads the particle's context.
    for integrator in ["SemiImplicitEuler", "Verlet", "Midpoint"] {
        let e = compiled(&spray(integrator));
        assert_attributes_match(&e, 60, 8.0 * 60.0 * U32);
    }
}

#[test]
fn a_counter_counts_steps_and_a_rate_decays_as_euler_does() {
    // `steps` adds 1 each step: small integers are exact in f32, so the GPU's count is each
    // particle's age in steps exactly. A rate of -k·heat integrated once a step is
    // heat₀ (1 − k dt)ⁿ, with f32's rounding at most n roundings of the product.
    let src = r#"Effect(
    name: "count",
    capacity: 400,
    dt: 0.02,
    emitters: [Emitter(burst: 100, rate: 250.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))],
    attributes: {
        "steps": (spawn: "0.0", update: Some("steps + 1.0")),
        "heat": (spawn: "2.0", rate: Some("-0.5 * heat")),
    },
    render: Render(size_by: Some("1.0 + 0.001 * steps"), alpha_by: Some("clamp(heat, 0.0, 1.0)")),
)"#;
    let e = compiled(src);
    let (_, gpu) = run_gpu(&e, 50);
    assert!(gpu.len() > 100);
    // Words in name order: heat, then steps.
    for p in &gpu {
        let n = (p.age / 0.02).round();
        assert_eq!(p.attributes[1], n, "particle {} aged {} steps", p.id, n);
        let decayed = 2.0 * (1.0f64 - 0.5 * 0.02).powf(n);
        assert!(
            (p.attributes[0] - decayed).abs() <= 4.0 * n.max(1.0) * U32 * decayed,
            "particle {}: heat {} after {n} steps, Euler gives {decayed}",
            p.id,
            p.attributes[0]
        );
    }
    // The reference agrees to the last bit on the count and within rounding on the decay.
    let mut cpu = ReferenceSim::new(&e.ir);
    cpu.run(50);
    for (g, c) in gpu.iter().zip(cpu.records()) {
        assert_eq!(g.attributes[1], c.attributes[1]);
    }
}

#[test]
fn the_draw_reads_attributes_as_the_reference_drawing_does() {
    let e = compiled(&spray("SemiImplicitEuler"));
    let mut sim = plume::runtime::Effect::new(&gpu(), e).unwrap();
    sim.run(40, |_| {}).unwrap();
    let gpu_img = assert_draws_agree(&sim, 256, true, "attributes in the draw");
    let lit = gpu_img.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    assert!(lit > 500, "{lit} pixels drawn");
}

#[test]
fn a_stateless_effect_cannot_keep_attributes() {
    let src = r#"Effect(
    name: "s",
    capacity: 100,
    state: Stateless,
    emitters: [Emitter(rate: 10.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((1.0, 1.0)))],
    attributes: {"heat": (spawn: "rand(0)")},
    forces: [Gravity((0.0, -9.8, 0.0))],
    integrator: Exact,
    render: Render(alpha_by: Some("heat")),
)"#;
    let err = compile_str(src, &CompileOptions::default()).unwrap_err();
    let text = err.render("s.ron", src);
    assert!(
        text.contains("attributes.heat is carried by each particle"),
        "{text}"
    );
    // Auto keeps it stateful, and says why.
    let auto = compiled(&src.replace("state: Stateless,", ""));
    assert!(auto.ir.stateless.is_none());
    assert!(
        auto.ir.state_reason.contains("attributes.heat"),
        "{}",
        auto.ir.state_reason
    );
}

#[test]
fn event_children_spawn_their_attributes() {
    // A group fed by deaths gives each child its attributes as an emitter's particles get
    // them, through the same store; the GPU matches the reference.
    let src = r#"Effect(
    name: "parents",
    capacity: 200,
    dt: 0.02,
    emitters: [Emitter(burst: 50, shape: Point((0.0, 0.0, 0.0)), velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.2, 0.4)))],
    events: [Event(on: Death, target: "children", count: 4, velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((1.0, 1.0)))],
    groups: [Group(name: "children", capacity: 400,
        attributes: {"glow": (spawn: "0.5 + length(x)", rate: Some("-glow"))},
        render: Render(alpha_by: Some("clamp(glow, 0.0, 1.0)")))],
)"#;
    let graph = plume::compiler::graph::compile_graph_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("parents.ron", src)));
    let child = &graph.groups[1].effect;
    assert_eq!(
        child
            .layout
            .words()
            .iter()
            .filter(|(n, _)| *n == "u0")
            .count(),
        1
    );
    let mut sim = plume::runtime::Effect::from_graph(&gpu(), graph.clone()).unwrap();
    sim.run(20, |_| {}).unwrap();
    let mut cpu = plume::compiler::graph::ReferenceGraph::new(&graph);
    cpu.run(20);
    let (g, c) = (sim.group_records(1).unwrap(), cpu.records(1));
    assert_eq!(g.len(), c.len());
    assert!(g.len() > 50, "{} children", g.len());
    for (a, b) in g.iter().zip(&c) {
        assert_eq!(a.id, b.id);
        assert!(
            (a.attributes[0] - b.attributes[0]).abs() <= 1e-5 * (1.0 + b.attributes[0].abs()),
            "child {}: glow {} on the GPU, {} in f64",
            a.id,
            a.attributes[0],
            b.attributes[0]
        );
    }
}

#[test]
fn an_attribute_that_reads_the_time_keeps_it_whole() {
    // dt = 1 s for 300 steps: past 256 s, where the kernels' time wraps unless something reads
    // it. The attribute takes each step's start time, a whole number, exact in f32.
    let src = r#"Effect(
    name: "clock",
    capacity: 10,
    dt: 1.0,
    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    attributes: {"clock": (spawn: "t", update: Some("t"))},
    render: Render(alpha_by: Some("clamp(clock, 0.0, 1.0)")),
)"#;
    let e = compiled(src);
    assert!(!e.ir.wraps_kernel_time(), "the attribute reads t");
    let (_, gpu) = run_gpu(&e, 300);
    let (_, cpu) = run_cpu(&e, 300);
    assert_eq!(gpu.len(), 4);
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!(c.attributes[0], 299.0);
        assert_eq!(g.attributes[0], c.attributes[0]);
    }
}

#[test]
fn noise_and_curl_in_expressions_match_the_reference_on_the_gpu() {
    // A spawn velocity along the curl, an attribute set from the noise at spawn and changed
    // from it each step, a force reading the curl and the attribute, and the draw reading the
    // noise: the GPU's f32 against the reference's f64, through the same lattice hashes.
    let src = r#"Effect(
    name: "noisy",
    capacity: 2000,
    seed: 3,
    dt: 0.02,
    emitters: [Emitter(burst: 600, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 1.0),
        velocity: Custom("curl(x * 2.0)"), lifetime: Some((5.0, 5.0)))],
    attributes: {"n": (spawn: "noise(x * 3.0)", update: Some("noise(x * 3.0 + vec3(t, 0.0, 0.0))"))},
    forces: [Custom(accel: "curl(x) * 2.0 + vec3(0.0, n, 0.0)")],
    camera: Camera(eye: (0.0, 1.0, 6.0), target: (0.0, 1.0, 0.0), fov_y: 50.0),
    render: Render(blend: Additive, color: [(0.0, (0.3, 0.3, 0.3, 1.0))],
        color_by: Some("vec3(0.5 + 0.5 * noise(x * 4.0), 0.5, 1.0)"), size_by: Some("1.0 + n")),
)"#;
    // Additive light: the draw's order does not matter where 600 sprites overlap.
    let e = compiled(src);
    // At spawn: the noise of a spawn point, a few f32 roundings of each of the 8 corners'
    // fades and dot products apart (1e-5 of the noise's range of about ±1).
    let (_, on_gpu) = run_gpu(&e, 1);
    let (_, cpu) = run_cpu(&e, 1);
    for (g, c) in on_gpu.iter().zip(&cpu) {
        assert!(
            (g.attributes[0] - c.attributes[0]).abs() < 1e-5,
            "{g:?} {c:?}"
        );
        assert!((g.velocity - c.velocity).length() < 1e-4 * (1.0 + c.velocity.length()));
    }
    assert!(
        on_gpu.iter().any(|g| g.attributes[0].abs() > 0.1),
        "the noise varies"
    );
    // 40 steps: the curl's f32 error (its gradients are analytic: the same few roundings
    // per corner) compounds step by step as any force's does; 1e-4 (1 + |x|) bounds it with
    // room (measured: 2.5e-6 on llvmpipe).
    assert_attributes_match(&e, 40, 1e-4);
    let mut sim = plume::runtime::Effect::new(&gpu(), e).unwrap();
    sim.run(20, |_| {}).unwrap();
    assert_draws_agree(&sim, 256, false, "noise in the draw");
}

#[test]
fn rounding_trigonometry_and_remainders_match_the_reference_on_the_gpu() {
    // ceil, round, sign, tan, asin, acos, atan, log2 and rem of a value each particle draws
    // in [-3.5, 3.5) (asin and acos past their domain, clamped; a remainder by zero, 0), set
    // at spawn and once a step: the GPU's f32 functions against f64. Vulkan lets atan be 4096
    // ulps off (5e-4 relative), asin and acos inherit that through atan2, and tan inherits
    // sin's and cos's 2^-11 absolute: 2e-3 of 1 + |value| bounds those (llvmpipe: 2.2e-4 for
    // asin). log2, rem and the rest are within a few ulps (1e-5). ceil, round and sign agree
    // exactly unless the f32 argument lands on the other side of a whole number (or a half)
    // from the f64 one, which no particle here comes near.
    let src = r#"Effect(
    name: "functions",
    capacity: 512,
    seed: 5,
    emitters: [Emitter(burst: 300, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)),
        lifetime: Some((5.0, 5.0)))],
    define: {"q": "(rand(0) - 0.5) * 7.0", "p": "q + 0.01 * age"},
    attributes: {
        "a": (spawn: "vec3(ceil(q), round(2.0 * q), sign(q))", update: Some("vec3(ceil(p), round(2.0 * p), sign(p))")),
        "b": (spawn: "vec3(tan(0.4 * q), asin(0.3 * q), acos(0.3 * q))", update: Some("vec3(tan(0.4 * p), asin(p), acos(-p))")),
        "c": (spawn: "vec3(atan(q), log2(abs(q)), rem(3.0 * q, 1.7))", update: Some("vec3(atan(p), log2(abs(p)), rem(p, 0.0) + rem(-7.5, 2.0))")),
    },
    render: Render(color_by: Some("a + b + c")),
)"#;
    let e = compiled(src);
    let (_, on_gpu) = run_gpu(&e, 1);
    let (_, cpu) = run_cpu(&e, 1);
    // Words: a (ceil, round, sign), b (tan, asin, acos), c (atan, log2, rem).
    let tolerance = |w: usize| if (3..=6).contains(&w) { 2e-3 } else { 1e-5 };
    for (g, c) in on_gpu.iter().zip(&cpu) {
        for (w, (a, b)) in g.attributes.iter().zip(&c.attributes).take(9).enumerate() {
            assert!(
                (a - b).abs() <= tolerance(w) * (1.0 + b.abs()),
                "particle {} word {w}: gpu {a}, f64 {b}",
                g.id
            );
        }
    }
    // Each function's range is met: whole numbers, halves, signs both ways, a clamped asin.
    let words = |w: usize| cpu.iter().map(move |r| r.attributes[w]);
    assert!(words(0).all(|x| x == x.round()) && words(0).any(|x| x < 0.0));
    assert!(words(2).any(|x| x == -1.0) && words(2).any(|x| x == 1.0));
    assert_attributes_match(&e, 30, 2e-3);
    let (_, later) = run_cpu(&e, 30);
    for r in &later {
        // asin and acos of |p| > 1 are clamped; rem by 0 is 0, and rem(-7.5, 2) is -1.5.
        assert!(r.attributes[4].abs() <= std::f64::consts::FRAC_PI_2);
        assert!((0.0..=std::f64::consts::PI).contains(&r.attributes[5]));
        assert_eq!(r.attributes[8], -1.5);
    }
}
