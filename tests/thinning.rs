//! Thinning: `Effect::set_spawn_scale` keeps a fraction of every spawn from the next step on
//! (what a host's budget or level of detail sets), on the GPU exactly as in the f64 reference
//! (`ReferenceSim::set_spawn_scale`, `ReferenceGraph::set_spawn_scale`): the same ids spawn at
//! the same steps, stateful, stateless and in an effect graph, and the counts are the scaled
//! rates' and bursts'.
//!
//! Tolerance: tests/gpu_vs_reference.rs's bound (`compare_at`): thinning changes which ids
//! spawn when, not how a particle moves once spawned.

mod common;

use common::compare::{compare_at, roundings_per_step};
use plume::compiler::bursts::Burst;
use plume::compiler::graph::{compile_graph_str, ReferenceGraph};
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;
use plume::{compile_str, CompileOptions};

/// A steady stream beside a burst every 0.1 s, both thinned.
const STREAM: &str = r#"Effect(name: "stream", capacity: 6000, seed: 11, dt: 0.02,
    emitters: [
        Emitter(rate: 900.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
            velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.5, 1.0))),
        Emitter(burst: 37, every: Some(0.1), shape: Point((0.0, 1.0, 0.0)),
            velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 20.0, speed: (2.0, 3.0)), lifetime: Some((0.3, 0.6))),
    ],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.3)])"#;

/// The spawn scale of each chunk of 10 steps: full, thinned, stopped, partly back, full.
const SCALES: [f32; 5] = [1.0, 0.3, 0.0, 0.7, 1.0];

fn run_thinned(options: &CompileOptions, stateless: bool) {
    let compiled = compile_str(STREAM, options).expect("compiles");
    assert_eq!(compiled.ir.stateless.is_some(), stateless);
    let gpu = common::gpu();
    let mut sim = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
    let mut reference = ReferenceSim::new(&compiled.ir);
    let mut spawned = Vec::new();
    for (chunk, &scale) in SCALES.iter().enumerate() {
        sim.set_spawn_scale(scale);
        reference.set_spawn_scale(scale);
        if options.bursts {
            let burst = Burst::new(0, 200).at([chunk as f32, 0.0, 0.0]);
            sim.burst(0, burst).expect("a burst");
            reference.burst(burst).expect("a burst");
        }
        let before = sim.totals().expect("totals").spawned;
        sim.run(10, |_| {}).expect("run");
        reference.run(10);
        let totals = sim.totals().expect("totals");
        assert_eq!(totals.spawned, reference.totals().spawned, "chunk {chunk}");
        assert_eq!(totals.alive, reference.totals().alive, "chunk {chunk}");
        spawned.push(totals.spawned - before);
        compare_at(
            "stream (thinned)",
            sim.steps_done(),
            false,
            false,
            None,
            roundings_per_step(&compiled.ir),
            &sim.records().expect("records"),
            &reference.records(),
        );
    }
    // 10 steps of 0.02 s: the stream's 180 and two bursts of 37 (at 0.1 s intervals), and the
    // burst from code's 200, each scaled, fractions carried.
    let from_code = if options.bursts { 200.0 } else { 0.0 };
    for (chunk, (&n, &scale)) in spawned.iter().zip(&SCALES).enumerate() {
        let full = 180.0 + 74.0 + from_code;
        let expected = full * f64::from(scale);
        assert!(
            (n as f64 - expected).abs() <= 3.0,
            "chunk {chunk}: {n} spawned at scale {scale}, {expected} expected"
        );
    }
    assert_eq!(spawned[2], 0, "scale 0 spawns nothing");
}

#[test]
fn a_thinned_stateful_effect_spawns_on_the_gpu_as_in_the_reference() {
    let options = CompileOptions {
        bursts: true,
        ..Default::default()
    };
    run_thinned(&options, false);
}

#[test]
fn a_thinned_stateless_effect_spawns_on_the_gpu_as_in_the_reference() {
    run_thinned(&CompileOptions::default(), true);
}

#[test]
fn scale_one_is_the_unthinned_effect_bit_for_bit() {
    let compiled = compile_str(STREAM, &CompileOptions::default()).expect("compiles");
    let gpu = common::gpu();
    let mut plain = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
    let mut scaled = Effect::new(&gpu, compiled).expect("GPU sim");
    scaled.set_spawn_scale(1.0);
    plain.run(40, |_| {}).expect("run");
    scaled.run(40, |_| {}).expect("run");
    assert_eq!(plain.records().unwrap(), scaled.records().unwrap());
    // Out of range and NaN clamp: above 1 is 1, NaN and below 0 are 0.
    scaled.set_spawn_scale(7.0);
    assert_eq!(scaled.spawn_scale(), 1.0);
    scaled.set_spawn_scale(f32::NAN);
    assert_eq!(scaled.spawn_scale(), 0.0);
    scaled.set_spawn_scale(-1.0);
    let before = scaled.totals().unwrap().spawned;
    scaled.run(10, |_| {}).expect("run");
    assert_eq!(scaled.totals().unwrap().spawned, before);
}

/// Rockets whose deaths burst into sparks: thinning the rockets thins the sparks.
const ROCKETS: &str = r#"Effect(name: "rockets", capacity: 64, seed: 3,
    emitters: [Emitter(rate: 40.0, shape: Disc(center: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 2.0),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 15.0, speed: (8.0, 10.0)), lifetime: Some((0.2, 0.4)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    events: [Event(on: Death, target: "sparks", count: 10, velocity: Radial(speed: (2.0, 4.0)),
                   lifetime: Some((0.3, 0.6)))],
    groups: [Group(name: "sparks", capacity: 2000, forces: [Gravity((0.0, -9.81, 0.0))])],
)"#;

#[test]
fn children_of_a_thinned_graph_follow_their_parents() {
    let graph = compile_graph_str(ROCKETS, &CompileOptions::default()).expect("compiles");
    let gpu = common::gpu();
    let mut sim = Effect::from_graph(&gpu, graph.clone()).expect("GPU graph");
    let mut reference = ReferenceGraph::new(&graph);
    let mut full = Effect::from_graph(&gpu, graph.clone()).expect("GPU graph");
    sim.set_spawn_scale(0.25);
    reference.set_spawn_scale(0.25);
    sim.run(120, |_| {}).expect("run");
    reference.run(120);
    full.run(120, |_| {}).expect("run");
    for g in 0..2 {
        assert_eq!(
            sim.group_totals(g).unwrap(),
            reference.totals(g),
            "group {g}"
        );
        compare_at(
            "rockets (thinned)",
            120,
            false,
            false,
            None,
            roundings_per_step(&graph.groups[g].effect.ir),
            &sim.group_records(g).unwrap(),
            &reference.records(g),
        );
    }
    // A quarter of the rockets, so about a quarter of the sparks (each rocket's 10).
    let (rockets, sparks) = (sim.group_totals(0).unwrap(), sim.group_totals(1).unwrap());
    let full_sparks = full.group_totals(1).unwrap().spawned;
    // A quarter of 2 s at 40 a second: 20, or 19 where the carried sixths sum just under.
    assert!((19..=20).contains(&rockets.spawned), "{rockets:?}");
    assert!(
        sparks.spawned * 5 < full_sparks * 2 && sparks.spawned * 5 > full_sparks,
        "sparks {} of {full_sparks}",
        sparks.spawned
    );
}

#[test]
fn expected_alive_weighs_rates_bursts_and_lifetimes() {
    let gpu = common::gpu();
    let stream = Effect::from_source(&gpu, STREAM, &CompileOptions::default()).unwrap();
    // 900 a second for at most 1 s, and 37 every 0.1 s for 0.6 s plus the burst's own 37.
    assert_eq!(stream.expected_alive(), 900 + 37 + 37 * 6);
    let rockets = Effect::from_source(&gpu, ROCKETS, &CompileOptions::default()).unwrap();
    // 40 a second for 0.4 s; the sparks, fed by events, at their capacity.
    assert_eq!(rockets.expected_alive(), 16 + 2000);
}
