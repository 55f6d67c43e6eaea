//! Control from the host's code: bursts fired at run time (`CompileOptions::bursts`,
//! `Effect::burst`) and params changed at run time (`CompileOptions::live_params`,
//! `Effect::set_param`), on the GPU exactly as in the f64 reference, with exact counts, and
//! every bad call refused with why.

mod common;

use common::compare::{compare_at, roundings_per_step};
use plume::compiler::bursts::{Burst, SLOTS};
use plume::compiler::placement::Placement;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::{Effect, RuntimeError};
use plume::{compile_str, CompileOptions};

/// Sparks that only bursts from code spawn (the first emitter has no rate), beside a slow
/// steady stream from a second emitter on a lattice (its spawn counter runs on through the
/// bursts fired from it).
const SPARKS: &str = r#"Effect(name: "sparks", capacity: 4000, seed: 5, dt: 0.02,
    emitters: [
        Emitter(shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.1),
            velocity: Radial(speed: (1.0, 3.0)), lifetime: Some((0.5, 1.5))),
        Emitter(rate: 100.0, shape: Grid(min: (-1.0, 0.0, -1.0), max: (1.0, 0.0, 1.0), counts: (3, 1, 3)),
            velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 10.0, speed: (1.0, 2.0)), lifetime: Some((1.0, 1.0))),
    ],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5)],
    integrator: SemiImplicitEuler)"#;

fn bursts_options() -> CompileOptions {
    CompileOptions {
        bursts: true,
        placed: true,
        ..Default::default()
    }
}

/// Burst `n` of a run: from either emitter, at its own place and velocity.
fn burst(n: u32) -> Burst {
    let f = n as f32;
    Burst::new(n % 2, 7 + 13 * n)
        .at([f - 3.0, 0.5 * f, 2.0 - f])
        .with_velocity([0.0, f, -0.5 * f])
}

#[test]
fn bursts_from_code_spawn_on_the_gpu_as_in_the_reference() {
    let compiled = compile_str(SPARKS, &bursts_options()).expect("compiles");
    assert!(
        compiled.ir.stateless.is_none(),
        "an effect with bursts is stateful"
    );
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
    let mut reference = ReferenceSim::new(&compiled.ir);
    let mut fired = 0u32;
    let mut burst_particles = 0u64;
    // Chunk 2 fires more bursts than a step has slots: the rest spawn at the next steps.
    let per_chunk = [1u32, 0, SLOTS + 5, 2, 0, 1];
    for (chunk, &bursts) in per_chunk.iter().enumerate() {
        let placement = Placement::from_cols(
            glam::Mat4::from_translation(glam::Vec3::new(chunk as f32, 0.0, 0.0)).to_cols_array(),
        )
        .expect("finite");
        sim.set_placement(placement);
        reference.set_placement(placement);
        for _ in 0..bursts {
            let b = burst(fired);
            sim.burst(0, b).expect("a burst");
            reference.burst(b).expect("a burst");
            burst_particles += u64::from(b.count);
            fired += 1;
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sim.advance(&mut encoder, 4).expect("advance");
        gpu.queue.submit([encoder.finish()]);
        reference.run(4);
    }
    let steps = 4 * per_chunk.len() as u64;
    let totals = sim.totals().expect("totals");
    // Every burst particle was spawned, beside the stream's 100 a second.
    let stream = (100.0 * 0.02 * steps as f64).floor() as u64;
    assert_eq!(totals.spawned, burst_particles + stream);
    assert_eq!(totals.dropped, 0);
    assert_eq!(totals.spawned, reference.totals().spawned);
    compare_at(
        "sparks (bursts)",
        steps,
        false,
        false,
        None,
        roundings_per_step(&compiled.ir),
        &sim.records().expect("records"),
        &reference.records(),
    );
}

#[test]
fn a_burst_emits_exactly_its_count_where_it_is_fired() {
    let compiled = compile_str(SPARKS, &bursts_options()).expect("compiles");
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, compiled).expect("GPU sim");
    // One step: the stream spawns its 2, the burst its 250 around (10, 0, 0).
    sim.burst(0, Burst::new(0, 250).at([10.0, 0.0, 0.0]))
        .expect("a burst");
    sim.run(1, |_| {}).expect("run");
    let records = sim.records().expect("records");
    let near = records
        .iter()
        .filter(|r| (r.position - glam::DVec3::new(10.0, 0.0, 0.0)).length() < 0.2)
        .count();
    assert_eq!((records.len(), near), (252, 250));
}

#[test]
fn bad_bursts_are_refused_with_why() {
    let gpu = common::gpu();
    let plain = compile_str(SPARKS, &CompileOptions::default()).expect("compiles");
    assert!(!plain.wgsl.contains("burst"), "bursts cost nothing unasked");
    let mut sim = Effect::new(&gpu, plain).expect("GPU sim");
    let refused = |r: Result<(), RuntimeError>| r.expect_err("refused").to_string();
    assert!(refused(sim.burst(0, Burst::new(0, 1))).contains("CompileOptions { bursts: true"));
    let compiled = compile_str(SPARKS, &bursts_options()).expect("compiles");
    let mut sim = Effect::new(&gpu, compiled).expect("GPU sim");
    assert!(refused(sim.burst(0, Burst::new(2, 1))).contains("has 2 emitter(s)"));
    assert!(refused(sim.burst(1, Burst::new(0, 1))).contains("has 1 group(s)"));
    let nan = Burst::new(0, 1).at([f32::NAN, 0.0, 0.0]);
    assert!(refused(sim.burst(0, nan)).contains("must be finite"));
    // Nothing refused was queued.
    sim.run(1, |_| {}).expect("run");
    assert_eq!(sim.totals().expect("totals").spawned, 2);
}

/// A swirl whose strength and centre height are params: the force is not constant, so it is
/// a custom term read per particle.
const SWIRL: &str = r#"Effect(name: "swirl", capacity: 2000, seed: 3, dt: 0.01,
    params: {"spin": 2.0, "lift": 0.5},
    emitters: [Emitter(rate: 800.0, shape: Disc(center: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 1.0),
        velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((1.0, 2.0)))],
    forces: [Custom(accel: "spin * cross(vec3(0, 1, 0), x) + vec3(0, lift, 0) - 0.2 * v")],
    integrator: Rk4)"#;

#[test]
fn params_changed_from_code_act_on_the_gpu_as_in_the_reference() {
    let live = CompileOptions {
        live_params: true,
        ..Default::default()
    };
    let compiled = compile_str(SWIRL, &live).expect("compiles");
    assert!(
        compiled.wgsl.contains("params.user[0u][1u]"),
        "spin is read at run time"
    );
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
    let mut reference = ReferenceSim::new(&compiled.ir);
    let settings = [(2.0, 0.5), (-3.0, 0.5), (-3.0, 4.0), (0.0, -1.0)];
    for (spin, lift) in settings {
        for (name, value) in [("spin", spin), ("lift", lift)] {
            sim.set_param(name, value).expect("a live param");
            reference.set_param(name, value).expect("a live param");
        }
        sim.run(15, |_| {}).expect("run");
        reference.run(15);
    }
    let gpu_records = sim.records().expect("records");
    compare_at(
        "swirl (live params)",
        60,
        false,
        true,
        None,
        roundings_per_step(&compiled.ir),
        &gpu_records,
        &reference.records(),
    );
    // The last setting (no spin, falling) acted: the youngest particles, spawned under it,
    // fall and stay on the disc's radius.
    let youngest = gpu_records.iter().max_by_key(|r| r.id).expect("alive");
    assert!(youngest.position.y < 0.0, "{:?}", youngest.position);
}

#[test]
fn a_live_param_set_to_the_file_value_matches_the_folded_effect() {
    let live = compile_str(
        SWIRL,
        &CompileOptions {
            live_params: true,
            ..Default::default()
        },
    )
    .expect("compiles");
    let folded = compile_str(
        &SWIRL.replace("\"spin\": 2.0", "\"spin\": -1.5"),
        &Default::default(),
    )
    .expect("compiles");
    assert!(
        !folded.wgsl.contains("params.user"),
        "params fold unless asked"
    );
    let gpu = common::gpu();
    let mut a = Effect::new(&gpu, live.clone()).expect("GPU sim");
    a.set_param("spin", -1.5).expect("live");
    a.run(40, |_| {}).expect("run");
    let mut b = Effect::new(&gpu, folded).expect("GPU sim");
    b.run(40, |_| {}).expect("run");
    // The same particles; positions within f32 rounding of one another (a literal folded
    // into the expression and a uniform read give the same f32, but the folded tree may
    // order a product differently).
    compare_at(
        "swirl (live vs folded)",
        40,
        false,
        true,
        None,
        roundings_per_step(&live.ir),
        &a.records().expect("records"),
        &b.records().expect("records"),
    );
}

#[test]
fn bad_params_are_refused_with_why() {
    let gpu = common::gpu();
    let refused = |r: Result<(), RuntimeError>| r.expect_err("refused").to_string();
    let mut folded = Effect::from_source(&gpu, SWIRL, &Default::default()).expect("compiles");
    assert!(refused(folded.set_param("spin", 1.0)).contains("live_params: true"));
    let live = CompileOptions {
        live_params: true,
        ..Default::default()
    };
    let mut sim = Effect::from_source(&gpu, SWIRL, &live).expect("compiles");
    assert!(refused(sim.set_param("spni", 1.0)).contains("the effect's params are lift, spin"));
    assert!(refused(sim.set_param("spin", f32::INFINITY)).contains("must be finite"));
    assert!(refused(sim.set_param("spin", 1e30)).contains("within ±1e18"));
}
