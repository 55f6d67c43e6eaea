//! World space: an effect compiled with `CompileOptions::placed` spawns through the placement
//! its host sets at run time, on the GPU exactly as in the f64 reference, and particles already
//! spawned stay where they are when the emitter moves on.

mod common;

use common::compare::{compare_at, roundings_per_step};
use plume::compiler::placement::Placement;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;
use plume::{compile_str, CompileOptions};

/// A stream of particles from a small sphere, flung out and falling: every spawn's position
/// and velocity go through the placement.
const STREAM: &str = r#"Effect(name: "stream", capacity: 3000, seed: 11, dt: 0.02,
    emitters: [Emitter(rate: 500.0, shape: Sphere(center: (0.0, 0.5, 0.0), radius: 0.2),
        velocity: Cone(axis: (1.0, 1.0, 0.0), angle: 20.0, speed: (2.0, 3.0)),
        lifetime: Some((1.0, 2.0)))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.3)],
    integrator: SemiImplicitEuler)"#;

/// Where the emitter is during chunk `i` of the run: moving along x and turning about y.
fn placement(i: u32) -> Placement {
    let angle = 0.4 * i as f32;
    let (s, c) = angle.sin_cos();
    // Column-major: a turn about +y, then a move.
    Placement::from_cols([
        c,
        0.0,
        -s,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        s,
        0.0,
        c,
        0.0,
        1.5 * i as f32,
        0.25,
        -0.5 * i as f32,
        1.0,
    ])
    .expect("finite")
}

#[test]
fn a_placed_effect_spawns_where_its_host_puts_it_as_the_reference_does() {
    let options = CompileOptions {
        placed: true,
        ..Default::default()
    };
    let compiled = compile_str(STREAM, &options).expect("compiles");
    assert!(
        compiled.ir.stateless.is_none(),
        "a placed effect is stateful"
    );
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
    let mut reference = ReferenceSim::new(&compiled.ir);
    let (chunks, per_chunk) = (8u32, 10u64);
    for i in 0..chunks {
        sim.set_placement(placement(i));
        reference.set_placement(placement(i));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sim.advance(&mut encoder, per_chunk).expect("advance");
        gpu.queue.submit([encoder.finish()]);
        reference.run(per_chunk);
    }
    let steps = u64::from(chunks) * per_chunk;
    let gpu_records = sim.records().expect("records");
    let cpu_records = reference.records();
    assert!(gpu_records.len() > 500, "{} alive", gpu_records.len());
    compare_at(
        "stream (placed)",
        steps,
        false,
        false,
        None,
        roundings_per_step(&compiled.ir),
        &gpu_records,
        &cpu_records,
    );
    // The particles were left behind: they spread over the whole path the emitter took
    // (x from 0 to 10.5 m), not bunched around where it is now.
    let xs: Vec<f64> = cpu_records.iter().map(|r| r.position.x).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    assert!(hi - lo > 5.0, "particles span only x {lo:.2}..{hi:.2}");
}

#[test]
fn an_unplaced_effect_ignores_a_placement_and_keeps_its_layout() {
    let plain = compile_str(STREAM, &CompileOptions::default()).expect("compiles");
    let placed = compile_str(
        STREAM,
        &CompileOptions {
            placed: true,
            ..Default::default()
        },
    )
    .expect("compiles");
    assert_eq!(
        placed.layout.params_bytes(),
        plain.layout.params_bytes() + 48
    );
    assert!(!plain.wgsl.contains("placement"));
    assert!(placed.wgsl.contains("params.placement"));
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, plain.clone()).expect("GPU sim");
    sim.set_placement(placement(3));
    sim.run(20, |_| {}).expect("run");
    let mut reference = ReferenceSim::new(&plain.ir);
    reference.set_placement(placement(3));
    reference.run(20);
    // Neither moved: the reference ignores it for an unplaced IR as the GPU does.
    let near_origin = reference
        .records()
        .iter()
        .all(|r| r.position.length() < 5.0);
    assert!(near_origin, "an unplaced effect moved");
    compare_at(
        "stream (unplaced)",
        20,
        false,
        false,
        None,
        roundings_per_step(&plain.ir),
        &sim.records().expect("records"),
        &reference.records(),
    );
}

#[test]
fn a_stateless_placed_effect_is_refused_with_the_reason() {
    let source = r#"Effect(name: "s", capacity: 64, state: Stateless, integrator: Exact,
        emitters: [Emitter(burst: 10, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)), lifetime: Some((1.0, 1.0)))])"#;
    let options = CompileOptions {
        placed: true,
        ..Default::default()
    };
    let error = compile_str(source, &options).unwrap_err();
    let text = error.render("s.ron", source);
    assert!(
        text.contains("Stateless is not possible") && text.contains("world space"),
        "{text}"
    );
}
