//! Stateless effects: the `evaluate` kernel computes each particle from (id, spawn step, age)
//! and keeps no state. It must give the same particles as the stateful kernels and the f64
//! reference, and equal the closed form (relative 1e-6) at any t, t = 10^6 s included.
//!
//! Tolerance: the kernel sums x0 + F v0 + (τ - F) u + Q g in f32. Each coefficient is within a
//! few ulps (the series' remainder is under 2^-24; at z = kτ = 1, where the direct form takes
//! over, 1 - e^{-z} loses under 3 ulps), τ is rounded once from f64, and the spawn draws carry
//! the few ulps of f32 sin, cos and sqrt. So the error is a few ulps of the *terms'* size,
//! X + F|v0| + (τ - F)|u| + Q|g| with X = max(|x0|, the spawn shape's extent) (a position drawn
//! in a box from -2 to 2 carries the rounding of 2), which is |x| wherever terms do not cancel. The tests hold
//! the kernel to 1e-6 of that size (17 ulps) and report the worst they see.

mod common;

use common::*;
use plume::compiler::reference::closed_form;
use plume::compiler::reference::{ParticleRecord, ReferenceSim};
use plume::compiler::schedule::{LiveSegments, Schedule};
use plume::compiler::CompiledEffect;
use plume::runtime::oracle;
use plume::runtime::Effect;

/// The closed form's records after `steps`, from the same bookkeeping the runtime keeps.
fn closed_form_at(e: &CompiledEffect, steps: u64) -> Vec<(ParticleRecord, f64)> {
    let plan = e.ir.stateless.as_ref().expect("stateless");
    let mut schedule = Schedule::new(&e.ir);
    let mut segments = LiveSegments::new(plan.lives.clone());
    segments.advance(&mut schedule, steps);
    closed_form::records(&e.ir, &segments, &schedule)
}

/// The worst position and velocity errors of `gpu` against the closed form, each over the
/// terms' size, after asserting the same live ids and ages.
fn worst_against_closed_form(gpu: &[ParticleRecord], exact: &[(ParticleRecord, f64)]) -> f64 {
    assert_eq!(gpu.len(), exact.len(), "live counts differ");
    let mut worst: f64 = 0.0;
    for (g, (c, scale)) in gpu.iter().zip(exact) {
        assert_eq!(g.id, c.id, "live ids differ");
        assert!((g.age - c.age).abs() <= 1e-9 * c.age, "ages differ");
        let dx = (g.position - c.position).length() / scale.max(1e-30);
        worst = worst.max(dx);
    }
    worst
}

/// Three emitters: a mortal stream, an immortal burst and a burst-plus-stream with one fixed
/// lifetime, under gravity, drag and wind.
const MIXED: &str = r#"Effect(name: "mixed", capacity: 6000, seed: 11, dt: 0.02,
    emitters: [
        Emitter(rate: 900.0, shape: Disc(center: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 0.5),
                velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 25.0, speed: (2.0, 4.0)), lifetime: Some((1.0, 3.0))),
        Emitter(burst: 500, shape: Sphere(center: (1.0, 2.0, 0.0), radius: 0.3), velocity: Radial(speed: (0.5, 1.5))),
        Emitter(burst: 200, rate: 150.0, shape: Box(min: (-1.0, 0.0, -1.0), max: (1.0, 0.5, 1.0)),
                velocity: Constant((0.0, 0.0, 1.0)), lifetime: Some((0.5, 0.5))),
    ],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.8), Wind(direction: (1.0, 0.0, 0.0), strength: 2.0)],
)"#;

#[test]
fn stateless_gives_the_particles_of_the_stateful_kernels_and_the_reference() {
    let e = compile(MIXED);
    let plan = e.ir.stateless.as_ref().expect("Auto picks stateless");
    assert_eq!(e.layout.state_bytes_per_particle(), 0);
    assert!(e.wgsl.contains("fn evaluate") && !e.wgsl.contains("fn update"));
    assert!(plan.peak <= 6000);
    let stateful = plume::compile_str(
        MIXED,
        &plume::CompileOptions {
            state: Some(plume::compiler::schema::State::Stateful),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(stateful.ir.stateless.is_none() && stateful.wgsl.contains("fn update"));
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e.clone()).unwrap();
    // A view split into buffers of 1,000 slots must give the same particles.
    let mut split = common::split(&gpu, e.clone(), Some(1000));
    let mut kept = Effect::new(&gpu, stateful).unwrap();
    let mut reference = ReferenceSim::new(&e.ir);
    assert!(
        sim.is_stateless() && oracle::chunk_count(&split, 0).unwrap() == 6 && !kept.is_stateless()
    );
    let mut done = 0;
    // Step 1, mid-stream, and past every lifetime of the first spawns (segments dropped).
    for at in [1u64, 37, 200] {
        sim.run(at - done, |_| {}).unwrap();
        split.run(at - done, |_| {}).unwrap();
        kept.run(at - done, |_| {}).unwrap();
        reference.run(at - done);
        done = at;
        let totals = sim.totals().unwrap();
        assert_eq!(totals, reference.totals(), "totals at step {at}");
        assert_eq!(
            totals,
            kept.totals().unwrap(),
            "stateful totals at step {at}"
        );
        let records = sim.records().unwrap();
        assert_eq!(records, split.records().unwrap(), "split view at step {at}");
        let exact = closed_form_at(&e, at);
        // The f64 closed form is the f64 reference's stepping, to rounding.
        let stepped = reference.records();
        assert_eq!(stepped.len(), exact.len());
        for (r, (c, _)) in stepped.iter().zip(&exact) {
            assert_eq!((r.id, r.lifetime), (c.id, c.lifetime));
            assert!((r.position - c.position).length() <= 1e-9 * (1.0 + c.position.length()));
            assert!((r.velocity - c.velocity).length() <= 1e-9 * (1.0 + c.velocity.length()));
        }
        let worst = worst_against_closed_form(&records, &exact);
        eprintln!(
            "step {at}: {} alive, worst {worst:.2e} of the terms' size",
            records.len()
        );
        assert!(worst <= 1e-6, "step {at}: {worst:.3e}");
        for (g, (c, _)) in records.iter().zip(&exact) {
            assert_eq!(g.lifetime, c.lifetime);
            let dv = (g.velocity - c.velocity).length();
            assert!(
                dv <= 1e-6 * (1.0 + c.velocity.length()),
                "velocity {dv:.3e}"
            );
        }
        let ids: Vec<u32> = kept.records().unwrap().iter().map(|r| r.id).collect();
        assert_eq!(ids, records.iter().map(|r| r.id).collect::<Vec<_>>());
    }
}

/// An immortal burst under gravity (and drag k toward a wind): run to t = 10^6 s at 60 steps a
/// second, where f32 time has an ulp of 0.0625 s.
fn immortal(k: f64) -> String {
    let drag = if k > 0.0 {
        format!(", Drag(k: {k}, fluid: (3.0, 0.0, 1.0))")
    } else {
        String::new()
    };
    format!(
        r#"Effect(name: "far", capacity: 300, seed: 5, dt: 0.016666666666666666,
    emitters: [Emitter(burst: 300, shape: Sphere(center: (2.0, 5.0, -1.0), radius: 1.0),
                       velocity: Cone(axis: (0.3, 1.0, 0.0), angle: 40.0, speed: (0.1, 1.0)))],
    forces: [Gravity((0.0, -9.81, 0.0)){drag}],
)"#
    )
}

#[test]
fn stateless_equals_the_closed_form_at_a_million_seconds() {
    let steps = 60_000_000; // 10^6 s at dt = 1/60 s
                            // No drag (F = τ), drag whose z = kτ stays in the series (0.1 at 10^6 s), and drag that
                            // long since reached terminal velocity (the direct form).
    for k in [0.0, 1e-7, 0.5] {
        let e = compile(&immortal(k));
        assert!(e.ir.stateless.is_some(), "k = {k}");
        let gpu = gpu();
        let mut sim = Effect::new(&gpu, e.clone()).unwrap();
        sim.run(steps, |_| {}).unwrap();
        let records = sim.records().unwrap();
        assert_eq!(records.len(), 300);
        let exact = closed_form_at(&e, steps);
        assert!((exact[0].0.age - 1e6).abs() < 1e-3);
        let worst = worst_against_closed_form(&records, &exact);
        // Plain relative error too: here the terms do not cancel (gravity dominates).
        let plain = records
            .iter()
            .zip(&exact)
            .map(|(g, (c, _))| (g.position - c.position).length() / c.position.length())
            .fold(0.0, f64::max);
        eprintln!("k = {k}: worst {worst:.2e} of the terms' size, {plain:.2e} of |x|");
        assert!(
            worst <= 1e-6 && plain <= 1e-6,
            "k = {k}: {worst:.3e}, {plain:.3e}"
        );
    }
}

#[test]
fn streams_stay_exact_a_million_seconds_in() {
    // A stream with lifetimes, 10^6 steps of 1 s: the particles alive at the end are young,
    // and their age comes from whole steps, never from f32 time.
    let src = r#"Effect(name: "late", capacity: 100, seed: 3, dt: 1.0,
    emitters: [Emitter(rate: 3.0, shape: Point((0.0, 0.0, 0.0)),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 30.0, speed: (5.0, 8.0)), lifetime: Some((4.0, 9.0)))],
    forces: [Gravity((0.0, -1.0, 0.0)), Drag(k: 0.05)],
)"#;
    let e = compile(src);
    assert!(e.ir.stateless.is_some());
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e.clone()).unwrap();
    let steps = 1_000_000;
    sim.run(steps, |_| {}).unwrap();
    let records = sim.records().unwrap();
    let exact = closed_form_at(&e, steps);
    assert!(records.len() > 10, "{} alive", records.len());
    assert_eq!(records[0].id, exact[0].0.id);
    assert!(records[0].id > 2_900_000);
    let worst = worst_against_closed_form(&records, &exact);
    eprintln!(
        "{} alive at 10^6 s, worst {worst:.2e} of the terms' size",
        records.len()
    );
    assert!(worst <= 1e-6, "{worst:.3e}");
    let t = sim.totals().unwrap();
    assert_eq!((t.spawned, t.dropped), (3_000_000, 0));
    assert_eq!(t.alive, records.len() as u64);
}

/// Random effects (`common::effect_gen::stateless_effect`: 1 to 3 emitters, mortal or immortal
/// bursts and streams, gravity, drag, wind) must compile stateless and match the f64 reference's
/// totals and ids and the closed form within the tolerance above, at steps 1, 60 and 150.
/// `PLUME_GPU_FUZZ_CASES` raises the count (16 in CI).
#[test]
fn random_stateless_effects_match_the_reference_and_the_closed_form() {
    use proptest::strategy::{Strategy, ValueTree};
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let cases: usize = std::env::var("PLUME_GPU_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(16);
    let mut runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &[11; 32]),
    );
    let mut worst: f64 = 0.0;
    for case in 0..cases {
        let text = common::effect_gen::stateless_effect()
            .new_tree(&mut runner)
            .unwrap()
            .current();
        let e = compile(&text);
        assert!(e.ir.stateless.is_some(), "case {case}\n{text}");
        let g = gpu();
        let mut sim = Effect::new(&g, e.clone()).unwrap();
        let mut reference = ReferenceSim::new(&e.ir);
        let mut done = 0;
        for at in [1u64, 60, 150] {
            sim.run(at - done, |_| {}).unwrap();
            reference.run(at - done);
            done = at;
            assert_eq!(
                sim.totals().unwrap(),
                reference.totals(),
                "case {case} step {at}\n{text}"
            );
            let records = sim.records().unwrap();
            let ids: Vec<u32> = reference.records().iter().map(|r| r.id).collect();
            assert_eq!(
                records.iter().map(|r| r.id).collect::<Vec<_>>(),
                ids,
                "case {case}\n{text}"
            );
            let w = worst_against_closed_form(&records, &closed_form_at(&e, at));
            assert!(w <= 1e-6, "case {case} step {at}: {w:.3e}\n{text}");
            worst = worst.max(w);
        }
    }
    eprintln!("{cases} random stateless effects: worst {worst:.2e} of the terms' size");
}

#[test]
fn a_sorted_stateless_effect_draws_back_to_front() {
    let e = compile(
        &std::fs::read_to_string("effects/sparks.ron")
            .unwrap()
            .replace("integrator: Exact,", "integrator: Exact, sort: true,"),
    );
    assert!(e.ir.stateless.is_some() && e.layout.sorts());
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e.clone()).unwrap();
    sim.run(30, |_| {}).unwrap();
    let ordered = sim.records_in_draw_order().unwrap();
    let mut by_id = ordered.clone();
    by_id.sort_by_key(|r| r.id);
    assert_eq!(by_id, sim.records().unwrap());
    assert_back_to_front(&e, &ordered);
}

#[test]
fn a_stateless_effect_whose_spawn_reads_the_noise_draws_it_from_the_closed_form() {
    // The vertex shader of a stateless effect evaluates the spawn expressions again, so its
    // module needs the gradient noise as the compute module does.
    let e = compile(
        r#"Effect(
    name: "noisy-stateless",
    capacity: 2000,
    seed: 2,
    emitters: [Emitter(rate: 600.0, shape: Custom("vec3(2.0 * noise(vec3(index * 0.1, 0.5, 0.5)), 0.02 * index - 2.0, curl(vec3(index * 0.05, 0.3, 0.7)).x)"),
        velocity: Constant((0.0, 0.5, 0.0)), lifetime: Some((2.0, 2.0)))],
    integrator: Exact,
    camera: Camera(eye: (0.0, 0.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(size: [(0.0, 0.08)]),
)"#,
    );
    assert!(e.ir.stateless.is_some(), "stateless");
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e).unwrap();
    sim.run(60, |_| {}).unwrap();
    assert_draws_agree(&sim, 200, false, "noise in a stateless spawn");
}
