//! Attributes children inherit from their parent (`inherit: true`, `features::inherit`) on
//! the GPU (llvmpipe in CI): every child starts with its parent's attribute values as the
//! step that fired began, a number and a vector, from `Every` and `Death` events, as the f64
//! reference gives them; children of another stream, and the group's own spawns, keep their
//! `spawn` values; and an effect that inherits nothing compiles as before.

mod common;

use common::*;
use plume::compiler::graph::{compile_graph_str, ReferenceGraph};
use plume::compiler::passes::layout::Role;
use plume::runtime::Effect;
use plume::CompileOptions;

/// Sparks whose `heat` cools and whose `dir` turns as they fly, shedding embers every 3 steps
/// and a burst when they die; the embers inherit both.
const SHED: &str = r#"Effect(
    name: "sparks",
    capacity: 64,
    seed: 12,
    dt: 0.016666666666666666,
    emitters: [Emitter(rate: 120.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 30.0, speed: (2.0, 4.0)),
                       lifetime: Some((0.2, 0.4)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: Euler,
    attributes: {
        "heat": (spawn: "1.0 + rand(0)", rate: Some("-2.0 * heat")),
        "dir": (spawn: "rand_sphere(1)", update: Some("normalize(dir + v * 0.1)")),
    },
    events: [
        Event(on: Every(0.05), target: "embers", count: 2, lifetime: Some((0.3, 0.3))),
        Event(on: Death, target: "embers", count: 3, lifetime: Some((0.3, 0.3))),
    ],
    groups: [Group(name: "embers", capacity: 512, forces: [Drag(k: 1.0)], integrator: Euler,
                   attributes: {
                       "heat": (spawn: "0.0", inherit: true),
                       "dir": (spawn: "vec3(0.0, 0.0, 0.0)", inherit: true),
                       "own": (spawn: "2.0 + rand(3)"),
                   },
                   render: Render(color_by: Some("dir * heat * own")))],
)"#;

#[test]
fn children_start_with_their_parents_attributes_as_the_reference_gives_them() {
    let graph = compile_graph_str(SHED, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("shed.ron", SHED)));
    let gpu = gpu();
    let mut sim = Effect::from_graph(&gpu, graph.clone()).unwrap();
    let mut reference = ReferenceGraph::new(&graph);
    let mut compared = 0;
    for _ in 0..4 {
        sim.run(10, |_| {}).unwrap();
        reference.run(10);
        let (g, c) = (sim.group_records(1).unwrap(), reference.records(1));
        assert_eq!(
            g.iter().map(|r| r.id).collect::<Vec<_>>(),
            c.iter().map(|r| r.id).collect::<Vec<_>>(),
            "the embers' ids differ"
        );
        for (a, b) in g.iter().zip(&c) {
            // The words in name order: dir (3), heat, own. A parent's heat has been integrated
            // in f32 for at most 24 steps (a rounding or two each) and dir renormalised as
            // often: 1e-5 of the value bounds both with room.
            for (k, (x, y)) in a.attributes.iter().zip(&b.attributes).take(5).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-5 * (1.0 + y.abs()),
                    "ember {} word {k}: gpu {x} reference {y}",
                    a.id
                );
            }
            // Inherited: a unit direction and a heat below its spawn's 2.
            let dir = (b.attributes[0].powi(2) + b.attributes[1].powi(2) + b.attributes[2].powi(2))
                .sqrt();
            assert!((dir - 1.0).abs() < 1e-6, "ember {}: |dir| {dir}", b.id);
            assert!(b.attributes[3] > 0.0 && b.attributes[3] < 2.0);
            compared += 1;
        }
    }
    assert!(compared > 200, "only {compared} embers compared");
}

#[test]
fn a_parent_passes_only_what_a_child_inherits() {
    let graph = compile_graph_str(SHED, &CompileOptions::default()).unwrap();
    let (parent, child) = (&graph.groups[0].effect, &graph.groups[1].effect);
    // Both streams pass dir (index 0) and heat (1); the parent keeps them though nothing of
    // its own reads dir after spawn but its update.
    for e in &parent.ir.events {
        assert_eq!(e.passes, vec![0, 1]);
    }
    assert!(parent.wgsl.contains("event_attrs_out_0") && parent.wgsl.contains("event_attrs_out_1"));
    assert!(child.wgsl.contains("event_attrs_in_0") && child.wgsl.contains("inherited_at"));
    // Without inherit, no buffer and no words.
    let plain = SHED.replace(", inherit: true", "");
    let graph = compile_graph_str(&plain, &CompileOptions::default()).unwrap();
    for g in &graph.groups {
        assert!(!g.effect.wgsl.contains("event_attrs"), "{}", g.name);
        assert!(g
            .effect
            .layout
            .bindings
            .iter()
            .all(|b| !matches!(b.role, Role::AttrsOut(_) | Role::AttrsIn(_))));
    }
}
