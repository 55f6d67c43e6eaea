//! Reported events (docs/effect-format.md, "Reported events"): the firings a host reads back
//! without waiting, against the f64 reference graph's firings, step by step.
//!
//! Tolerance: a firing's record is the firing particle's state at the end of the step it fired
//! in, so it carries the particle's error so far: tests/gpu_vs_reference.rs's bound of a few
//! f32 roundings a step over the steps since step 0 (tests/events.rs takes the same bound for
//! children, who start at their parents' records).

mod common;

use common::compare::roundings_per_step;
use common::*;
use plume::compiler::graph::{compile_graph_str, CompiledGraph, ReferenceGraph};
use plume::runtime::{Effect, EventReport, Firing};
use plume::CompileOptions;

/// Drops falling on a floor: each bounce is reported (an event with no target), and each
/// death spawns two sparks and is reported too.
const DROPS: &str = r#"Effect(
    name: "drops",
    capacity: 4096,
    dt: 0.01,
    seed: 7,
    emitters: [Emitter(rate: 2000.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.5),
                       velocity: Radial(speed: (0.5, 1.5)), lifetime: Some((0.4, 0.9)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.1)],
    events: [
        Event(on: Collide, report: REPORT),
        Event(on: Death, target: "sparks", count: 2, lifetime: Some((0.2, 0.2)), report: REPORT),
    ],
    groups: [Group(name: "sparks", capacity: 8192, forces: [Gravity((0.0, -9.81, 0.0))])],
)"#;

/// Frames that bring back nothing new before every firing has come back: a copy is mapped in
/// the frame after it was recorded and taken in the one after that (docs/effect-format.md).
const LATENCY: usize = 3;

fn graph(report: u32) -> (CompiledGraph, String) {
    let source = DROPS.replace("REPORT", &report.to_string());
    let graph = compile_graph_str(&source, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("drops.ron", &source)));
    (graph, source)
}

/// Runs `steps` frames of one step each, reading reports every frame, then frames with no step
/// until every copy is back. Returns each frame's reports.
fn run_reported(graph: &CompiledGraph, steps: usize) -> Vec<Vec<EventReport>> {
    let gpu = gpu();
    let mut effect = Effect::from_graph(&gpu, graph.clone()).expect("GPU graph");
    assert!(effect.reports_events());
    let mut frames = Vec::new();
    for frame in 0..steps + LATENCY + 1 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        effect
            .advance(&mut encoder, u64::from(frame < steps))
            .unwrap();
        frames.push(effect.watch_reports(&mut encoder).unwrap());
        gpu.queue.submit([encoder.finish()]);
        gpu.device
            .poll(plume::runtime::wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
    frames
}

/// The reference's firings of every event of the top group, step by step: (event, step, firing).
fn reference_firings(
    graph: &CompiledGraph,
    steps: usize,
) -> Vec<(usize, u64, plume::compiler::reference::Fired)> {
    let mut reference = ReferenceGraph::new(graph);
    let mut out = Vec::new();
    for step in 0..steps as u64 {
        reference.step();
        for j in 0..2 {
            let mut fired = reference.group(0).fired(j).to_vec();
            fired.sort_by_key(|f| f.id);
            out.extend(fired.into_iter().map(|f| (j, step, f)));
        }
    }
    out
}

#[test]
fn every_firing_is_reported_once_as_the_reference_fires_it() {
    let steps = 120;
    let (graph, _) = graph(4096);
    let frames = run_reported(&graph, steps);
    let tol = roundings_per_step(&graph.groups[0].effect.ir) * steps as f64 * U32;
    let expected = reference_firings(&graph, steps);
    for j in 0..2 {
        let mut got: Vec<Firing> = Vec::new();
        for (frame, reports) in frames.iter().enumerate() {
            for r in reports.iter().filter(|r| r.event == j) {
                assert_eq!(r.group, 0);
                assert_eq!(r.missed(), 0, "event {j}: the bound holds every firing");
                for f in &r.firings {
                    assert!(
                        frame as u64 <= f.step + LATENCY as u64,
                        "event {j}: step {}'s firing came back at frame {frame}",
                        f.step
                    );
                }
                got.extend(&r.firings);
            }
        }
        let want: Vec<_> = expected.iter().filter(|e| e.0 == j).collect();
        assert!(want.len() > 100, "event {j} fires {} times", want.len());
        let keys = |f: &Firing| (f.step, f.id);
        assert_eq!(
            got.iter().map(keys).collect::<Vec<_>>(),
            want.iter().map(|(_, s, f)| (*s, f.id)).collect::<Vec<_>>(),
            "event {j}: the firings, by step and id"
        );
        for (g, (_, step, c)) in got.iter().zip(&want) {
            let x = glam::DVec3::from(g.position.map(f64::from));
            let v = glam::DVec3::from(g.velocity.map(f64::from));
            assert!(
                (x - c.x).length() <= tol * (1.0 + c.x.length())
                    && (v - c.v).length() <= tol * (1.0 + c.v.length()),
                "event {j}, particle {} at step {step}: gpu {x:?} {v:?}, f64 {:?} {:?}",
                c.id,
                c.x,
                c.v
            );
        }
    }
}

#[test]
fn a_bound_keeps_that_many_a_readback_and_counts_the_rest() {
    let steps = 60;
    let bound = 4;
    let (graph, _) = graph(bound);
    let frames = run_reported(&graph, steps);
    let expected = reference_firings(&graph, steps);
    for j in 0..2 {
        let reports: Vec<&EventReport> = frames.iter().flatten().filter(|r| r.event == j).collect();
        let fired: u64 = reports.iter().map(|r| r.fired).sum();
        assert_eq!(
            fired,
            expected.iter().filter(|e| e.0 == j).count() as u64,
            "event {j}: every firing counted"
        );
        assert!(reports.iter().any(|r| r.missed() > 0));
        for r in &reports {
            assert_eq!(r.firings.len() as u64, r.fired.min(u64::from(bound)));
            // What was kept fired: each is one of the reference's firings of its step.
            for f in &r.firings {
                assert!(expected
                    .iter()
                    .any(|(e, s, c)| *e == j && *s == f.step && c.id == f.id));
            }
        }
    }
}

#[test]
fn a_stateless_group_reports_its_deaths() {
    let source = r#"Effect(name: "puffs", capacity: 256, dt: 0.02, seed: 3, integrator: Exact,
        emitters: [Emitter(rate: 300.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
                           velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.3, 0.5)))],
        forces: [Gravity((0.0, -2.0, 0.0))],
        events: [Event(on: Death, report: 1024)])"#;
    let graph = compile_graph_str(source, &CompileOptions::default()).unwrap();
    assert!(
        graph.groups[0].effect.ir.stateless.is_some(),
        "runs stateless"
    );
    let steps = 50;
    let frames = run_reported(&graph, steps);
    let mut reference = ReferenceGraph::new(&graph);
    let mut want = Vec::new();
    for step in 0..steps as u64 {
        reference.step();
        want.extend(
            reference
                .group(0)
                .fired(0)
                .iter()
                .map(|f| (step, f.id, f.x)),
        );
    }
    want.sort_by_key(|w| (w.0, w.1));
    let got: Vec<Firing> = frames
        .into_iter()
        .flatten()
        .flat_map(|r| r.firings)
        .collect();
    assert!(want.len() > 50);
    assert_eq!(
        got.iter().map(|f| (f.step, f.id)).collect::<Vec<_>>(),
        want.iter().map(|w| (w.0, w.1)).collect::<Vec<_>>()
    );
    // The closed form's position, in f32 from step 0: a few roundings of its terms.
    for (g, (_, _, x)) in got.iter().zip(&want) {
        let p = glam::DVec3::from(g.position.map(f64::from));
        assert!(
            (p - *x).length() <= 64.0 * U32 * (1.0 + x.length()),
            "{p:?} vs {x:?}"
        );
    }
}
