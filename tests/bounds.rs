//! `Effect::live_bounds`: the box of the live particles, measured on the GPU, is exactly the box
//! of the positions read back (the same f32 values), for a stateful effect, a stateless one,
//! an effect with groups, particles split over buffers of 7 slots, and a half-motion layout
//! (its planes); and None with no particle alive.

mod common;

use common::*;
use plume::compiler::graph::compile_graph_str;
use plume::runtime::{Effect, LiveBounds};
use plume::CompileOptions;

/// The box of `records`' positions, as the GPU holds them (f32).
fn box_of(records: &[plume::compiler::reference::ParticleRecord]) -> Option<LiveBounds> {
    let mut out: Option<LiveBounds> = None;
    for r in records {
        let x = r.position.as_vec3().to_array();
        let point = LiveBounds { min: x, max: x };
        out = Some(out.map_or(point, |b| b.union(point)));
    }
    out
}

/// A stream of particles under `forces` (`extra`: more fields), 600 slots.
fn stream(forces: &str, extra: &str) -> String {
    format!(
        r#"Effect(
    name: "stream",
    capacity: 600,
    seed: 9,
    emitters: [Emitter(rate: 600.0, shape: Sphere(center: (0.5, 1.0, -0.5), radius: 0.3),
                       velocity: Cone(axis: (0.2, 1.0, 0.0), angle: 30.0, speed: (2.0, 4.0)),
                       lifetime: Some((0.5, 0.9)))],
    forces: [{forces}],
    {extra}
)"#
    )
}

const ROCKETS: &str = r#"Effect(
    name: "rockets",
    capacity: 16,
    seed: 2,
    emitters: [Emitter(rate: 20.0, shape: Point((0.0, 0.0, 0.0)),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 15.0, speed: (8.0, 10.0)),
                       lifetime: Some((0.3, 0.5)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    state: Stateful,
    events: [Event(on: Death, target: "sparks", count: 20, velocity: Radial(speed: (1.0, 3.0)),
                   lifetime: Some((0.3, 0.6)))],
    groups: [Group(name: "sparks", capacity: 800, forces: [Gravity((0.0, -9.81, 0.0))])],
)"#;

#[test]
fn the_measured_box_is_the_box_of_the_particles_read_back() {
    let gpu = gpu();
    let cases = [
        // Stateful (a custom force has no closed form), whole and split over 7-slot buffers.
        (
            "stateful",
            stream(r#"Custom(accel: "-2.0 * x")"#, "state: Stateful,"),
            None,
        ),
        (
            "stateful, split",
            stream(r#"Custom(accel: "-2.0 * x")"#, "state: Stateful,"),
            Some(7),
        ),
        // Stateless: gravity and drag have a closed form.
        (
            "stateless",
            stream("Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5)", ""),
            None,
        ),
        // Motion in halves: the planes of 16, 8 and 4 bytes, split.
        (
            "halves, split",
            stream(
                r#"Custom(accel: "-2.0 * x")"#,
                "accuracy: (position: 0.05, over: 1.0),",
            ),
            Some(7),
        ),
        ("groups", ROCKETS.to_string(), None),
    ];
    for (what, source, chunk_slots) in cases {
        let graph = compile_graph_str(&source, &CompileOptions::default())
            .unwrap_or_else(|e| panic!("{what}: {}", e.render("bounds.ron", &source)));
        if what.starts_with("halves") {
            assert!(graph.groups[0].effect.layout.half_motion, "{what}");
        }
        if what == "stateless" {
            assert!(graph.groups[0].effect.layout.stateless(), "{what}");
        }
        let mut sim = Effect::with_chunk_slots(&gpu, graph, chunk_slots).unwrap();
        assert_eq!(
            sim.live_bounds().unwrap(),
            None,
            "{what}: nothing alive yet"
        );
        for _ in 0..3 {
            sim.run(15, |_| {}).unwrap();
            let records = sim.records().unwrap();
            assert!(!records.is_empty(), "{what}");
            assert_eq!(
                sim.live_bounds().unwrap(),
                box_of(&records),
                "{what} after {} steps",
                sim.steps_done()
            );
        }
    }
}
