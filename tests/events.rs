//! Effect graphs: groups connected by events (docs/effect-format.md, "Groups and events"), on
//! the GPU against the f64 reference graph, run against run, and drawn.
//!
//! Tolerance: tests/gpu_vs_reference.rs's bound of a few f32 roundings a step, taken over the
//! steps since step 0 whatever the group: a child starts where its parent's f32 state put it
//! (off by the parent's error so far) and adds its own roundings from then on, so its error
//! is bounded by the same sum over the whole run, with the largest per-step count of any group.

mod common;

use common::compare::{compare_at, curved_colliders, roundings_per_step};
use common::*;
use plume::compiler::graph::ReferenceGraph;
use plume::compiler::graph::{compile_graph_str, CompiledGraph};
use plume::compiler::reference::ParticleRecord;
use plume::runtime::outputs::csv_groups;
use plume::runtime::{oracle, Effect};
use plume::CompileOptions;

fn graph(source: &str) -> CompiledGraph {
    compile_graph_str(source, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("test.ron", source)))
}

/// The effect graphs among the examples.
fn graph_examples() -> Vec<std::path::PathBuf> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/effects");
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron") && is_graph_file(p))
        .collect();
    paths.sort();
    paths
}

/// Runs the GPU graph and the reference side by side, comparing every group at each of
/// `checkpoints` (steps since the start); returns the GPU instance.
fn compare_runs(name: &str, graph: &CompiledGraph, checkpoints: &[u64]) -> Effect {
    let gpu = gpu();
    let mut gsim = Effect::from_graph(&gpu, graph.clone()).expect("GPU graph");
    let mut csim = ReferenceGraph::new(graph);
    let roundings = graph
        .groups
        .iter()
        .map(|g| roundings_per_step(&g.effect.ir))
        .fold(0.0, f64::max);
    let mut done = 0;
    for &at in checkpoints {
        gsim.run(at - done, |_| {}).unwrap();
        csim.run(at - done);
        done = at;
        for (g, group) in graph.groups.iter().enumerate() {
            let label = format!("{name} group {}", group.name);
            assert_eq!(
                gsim.group_totals(g).unwrap(),
                csim.totals(g),
                "{label}: totals differ after {at} steps"
            );
            compare_at(
                &label,
                at,
                false,
                curved_colliders(&group.effect.ir),
                group
                    .effect
                    .layout
                    .half_motion
                    .then_some(group.effect.ir.dt),
                roundings,
                &gsim.group_records(g).unwrap(),
                &csim.records(g),
            );
        }
    }
    gsim
}

#[test]
fn every_example_with_events_matches_the_reference_in_every_group() {
    let examples = graph_examples();
    assert!(
        examples.len() >= 2,
        "fireworks.ron and rain.ron have groups"
    );
    for path in examples {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let graph = compile_graph_file(&path);
        // Past the first bursts and splashes (fireworks' rockets live 1.1 to 1.5 s).
        let sim = compare_runs(&name, &graph, &[60, 110]);
        for g in 1..graph.groups.len() {
            let t = sim.group_totals(g).unwrap();
            assert!(t.spawned > 0, "{name}: group {g} was never fed: {t:?}");
        }
    }
}

/// A small fireworks: rockets burst on death into sparks that leave embers every 3 steps.
const SMALL_FIREWORKS: &str = r#"Effect(
    name: "rockets",
    capacity: 16,
    seed: 3,
    emitters: [Emitter(burst: 4, rate: 20.0, shape: Disc(center: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 2.0),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 15.0, speed: (8.0, 10.0)), lifetime: Some((0.2, 0.4)))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.2)],
    events: [Event(on: Death, target: "sparks", count: 12, velocity: Radial(speed: (2.0, 4.0)),
                   lifetime: Some((0.3, 0.6)), inherit_velocity: 0.5)],
    groups: [
        Group(name: "sparks", capacity: 400, forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 1.0)], integrator: Verlet,
              events: [Event(on: Every(0.05), target: "embers", count: 2, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.05),
                             lifetime: Some((0.2, 0.3)), inherit_velocity: 0.2)]),
        Group(name: "embers", capacity: 3000, forces: [Gravity((0.0, -1.0, 0.0))], integrator: Midpoint),
    ],
)"#;

#[test]
fn verlet_and_midpoint_children_and_every_events_match_the_reference() {
    let g = graph(SMALL_FIREWORKS);
    let sim = compare_runs("small fireworks", &g, &[20, 45]);
    assert!(
        sim.group_totals(2).unwrap().spawned > 0,
        "embers were spawned"
    );
}

#[test]
fn exports_are_the_same_bytes_run_after_run() {
    let g = graph(SMALL_FIREWORKS);
    let export = || {
        let gpu = gpu();
        let mut sim = Effect::from_graph(&gpu, g.clone()).unwrap();
        sim.run(40, |_| {}).unwrap();
        let records: Vec<Vec<ParticleRecord>> =
            (0..3).map(|k| sim.group_records(k).unwrap()).collect();
        let parts: Vec<(&str, &[ParticleRecord])> = g
            .groups
            .iter()
            .zip(&records)
            .map(|(group, r)| (group.name.as_str(), r.as_slice()))
            .collect();
        csv_groups(&parts)
    };
    let (first, second) = (export(), export());
    let text = String::from_utf8(first.clone()).unwrap();
    assert!(text.starts_with("group,id,x,y,z,vx,vy,vz,age\n"), "{text}");
    for name in ["rockets,", "sparks,", "embers,"] {
        assert!(
            text.lines().any(|l| l.starts_with(name)),
            "no {name} line in the export"
        );
    }
    assert_eq!(first, second, "two runs exported different bytes");
}

#[test]
fn a_full_target_drops_the_same_children_every_run_and_counts_them() {
    // Twenty parents die together at step 9 (lifetime 10 steps) and ask for 10 children each:
    // 200 children for a group of 50. The first five parents by id get theirs (ids 0..50);
    // the rest are dropped, counted, and their ids used up.
    let src = r#"Effect(
        name: "parents",
        capacity: 20,
        dt: 0.01,
        emitters: [Emitter(burst: 20, shape: Box(min: (-1.0, 0.0, -1.0), max: (1.0, 1.0, 1.0)),
                           velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((0.1, 0.1)))],
        events: [Event(on: Death, target: "children", count: 10, velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((1.0, 1.0)))],
        groups: [Group(name: "children", capacity: 50)],
    )"#;
    let g = graph(src);
    assert!(
        g.warnings
            .items
            .iter()
            .any(|w| w.message.contains("capacity 50")),
        "the overflow is predicted: {:?}",
        g.warnings
    );
    let run = || {
        let gpu = gpu();
        let mut sim = Effect::from_graph(&gpu, g.clone()).unwrap();
        sim.run(15, |_| {}).unwrap();
        (sim.group_totals(1).unwrap(), sim.group_records(1).unwrap())
    };
    let (totals, records) = run();
    assert_eq!((totals.spawned, totals.dropped), (50, 150));
    let ids: Vec<u32> = records.iter().map(|r| r.id).collect();
    assert_eq!(ids, (0..50).collect::<Vec<u32>>());
    let mut reference = ReferenceGraph::new(&g);
    reference.run(15);
    assert_eq!(reference.totals(1), totals);
    let again = run();
    assert_eq!(again.0, totals);
    assert_eq!(again.1, records, "the second run kept other children");
    // The children of parent k (by id) start where it died: the parents' positions before
    // their last step (9), plus that step's 0.01 m, plus the children's first step (at most
    // 2 m/s for 0.01 s).
    let mut reference = ReferenceGraph::new(&g);
    reference.run(9);
    let parents = reference.records(0);
    assert_eq!(parents.len(), 20);
    let gpu = gpu();
    let mut sim = Effect::from_graph(&gpu, g.clone()).unwrap();
    sim.run(11, |_| {}).unwrap();
    let children = sim.group_records(1).unwrap();
    assert_eq!(children.len(), 50);
    for c in &children {
        let parent = &parents[(c.id / 10) as usize];
        let d = (c.position - parent.position).length();
        assert!(
            d <= 0.03 + 1e-5,
            "child {} is {d} m from parent {}",
            c.id,
            parent.id
        );
    }
}

#[test]
fn children_take_on_their_parents_colour_and_pass_it_on() {
    // Eight rockets of a three-colour palette die together at step 9; each bursts into five
    // sparks that inherit its colour, and every spark sheds an ember every 2 steps that inherits
    // the spark's, times the embers' own one-colour palette (half grey). Spark s is the
    // (s mod 5)-th child of rocket s / 5 (children follow their parents' ids).
    let src = r#"Effect(
        name: "rockets",
        capacity: 8,
        dt: 0.01,
        seed: 21,
        emitters: [Emitter(burst: 8, shape: Box(min: (-1.0, 0.0, -1.0), max: (1.0, 1.0, 1.0)),
                           velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((0.1, 0.1)))],
        render: Render(palette: Some([(1.0, 0.2, 0.1), (0.2, 0.6, 1.0), (0.3, 1.0, 0.4)])),
        events: [Event(on: Death, target: "sparks", count: 5, velocity: Radial(speed: (1.0, 2.0)),
                       lifetime: Some((1.0, 1.0)), inherit_color: true)],
        groups: [
            Group(name: "sparks", capacity: 40,
                  events: [Event(on: Every(0.02), target: "embers", count: 1, lifetime: Some((1.0, 1.0)), inherit_color: true)]),
            Group(name: "embers", capacity: 2000, render: Render(palette: Some([(0.5, 0.5, 0.5)]))),
        ],
    )"#;
    let g = graph(src);
    assert!(g.warnings.items.is_empty(), "{:?}", g.warnings);
    for (k, stores) in [(0, false), (1, true), (2, true)] {
        assert_eq!(
            g.groups[k]
                .effect
                .layout
                .has(plume::compiler::passes::layout::Attribute::Tint),
            stores,
            "group {k} stores a tint: {stores}"
        );
    }
    let palette = g.groups[0].effect.ir.render.palette.clone().unwrap();
    let rocket_colour =
        |id: u32| plume::compiler::tint::pick(&palette, g.groups[0].effect.ir.seed_mix, id);
    let sim = compare_runs("colours", &g, &[12, 20]);
    let sparks = sim.group_records(1).unwrap();
    assert_eq!(sparks.len(), 40);
    // One 8-bit step of slack: a channel exactly between two steps (0.3 · 255 = 76.5) may round
    // either way on the GPU (llvmpipe rounds half to even, the reference half up).
    for s in &sparks {
        let expected = plume::compiler::tint::stored(rocket_colour(s.id / 5));
        assert!(
            (s.tint - expected).abs().max_element() <= 1.0 / 255.0 + 1e-9,
            "spark {}: tint {:?}, its rocket's colour {expected:?}",
            s.id,
            s.tint
        );
    }
    let distinct: std::collections::BTreeSet<u32> = sparks
        .iter()
        .map(|s| plume::compiler::tint::pack(s.tint))
        .collect();
    assert!(distinct.len() >= 2, "the rockets picked one colour only");
    let embers = sim.group_records(2).unwrap();
    assert!(embers.len() >= 40, "{} embers", embers.len());
    for e in &embers {
        assert!(
            sparks.iter().any(|s| {
                let half = plume::compiler::tint::stored(0.5 * s.tint);
                (e.tint - half).abs().max_element() <= 1.0 / 255.0 + 1e-9
            }),
            "ember {} has a tint {:?} no spark passes on",
            e.id,
            e.tint
        );
    }
}

#[test]
fn passing_on_a_colour_a_group_does_not_have_is_warned_about() {
    let src = SMALL_FIREWORKS.replace(
        "lifetime: Some((0.3, 0.6)), inherit_velocity: 0.5)",
        "lifetime: Some((0.3, 0.6)), inherit_velocity: 0.5, inherit_color: true)",
    );
    let g = graph(&src);
    let warning = g
        .warnings
        .items
        .iter()
        .find(|w| w.path == "events[0].inherit_color")
        .unwrap_or_else(|| panic!("no warning at events[0].inherit_color: {:?}", g.warnings));
    assert!(
        warning
            .message
            .contains("\"rockets\"'s particles, which have none"),
        "{}",
        warning.message
    );
}

#[test]
fn a_stateless_group_fires_on_death_and_every_period_as_its_stateful_twin_does() {
    // Exact shells with a lifetime and no kill volume: stateless, firing from their closed form
    // (a stream of them, so segments spawn and expire within a submission of steps). Each sheds a
    // puff every 3 steps and bursts on death. The same file with the shells `state: Stateful`
    // must spawn the same children, and both match the reference.
    let src = |state: &str| {
        format!(
            r#"Effect(
        name: "shells",
        capacity: 200,
        seed: 4,
        state: {state},
        emitters: [Emitter(burst: 5, rate: 40.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.5),
                           velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 20.0, speed: (4.0, 6.0)), lifetime: Some((0.3, 0.5)))],
        forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5)],
        integrator: Exact,
        events: [
            Event(on: Every(0.05), target: "puffs", count: 1, lifetime: Some((0.2, 0.3)), inherit_velocity: 0.5),
            Event(on: Death, target: "bursts", count: 6, velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.3, 0.4))),
        ],
        groups: [
            Group(name: "puffs", capacity: 2000, forces: [Gravity((0.0, -1.0, 0.0))]),
            Group(name: "bursts", capacity: 3000, forces: [Gravity((0.0, -9.81, 0.0))]),
        ],
    )"#
        )
    };
    let stateless = graph(&src("Auto"));
    let stateful = graph(&src("Stateful"));
    assert!(
        stateless.groups[0].effect.layout.stateless(),
        "{}",
        stateless.groups[0].effect.ir.state_reason
    );
    assert!(!stateful.groups[0].effect.layout.stateless());
    // Past 256 steps: more than one batch (each batch has a table of its own).
    let a = compare_runs("stateless shells", &stateless, &[40, 300]);
    let b = compare_runs("stateful shells", &stateful, &[40, 300]);
    for g in 1..3 {
        let (ta, tb) = (a.group_totals(g).unwrap(), b.group_totals(g).unwrap());
        assert_eq!(ta, tb, "group {g}: the children differ");
        assert!(ta.spawned > 100, "group {g} was barely fed: {ta:?}");
        let (ra, rb) = (a.group_records(g).unwrap(), b.group_records(g).unwrap());
        assert_eq!(
            ra.iter().map(|r| r.id).collect::<Vec<_>>(),
            rb.iter().map(|r| r.id).collect::<Vec<_>>()
        );
        for (x, y) in ra.iter().zip(&rb) {
            // Both within compare_runs' bound of the reference (the closed form against f32
            // steps): within twice that of each other; 1e-4 of the scale is far wider.
            assert!(
                (x.position - y.position).length() <= 1e-4 * (1.0 + y.position.length()),
                "group {g} particle {}: {:?} against {:?}",
                x.id,
                x.position,
                y.position
            );
        }
    }
    // A firing group too large to count its firings puts them in order by buckets, stateless
    // too: from its closed form, the same children as the reference's.
    use plume::compiler::events::Ordering;
    let large = graph(&src("Auto").replace("capacity: 200,", "capacity: 9000,"));
    assert!(
        large.groups[0].effect.layout.stateless(),
        "{}",
        large.groups[0].effect.ir.state_reason
    );
    assert_eq!(large.streams[0].ordering, Ordering::Bucketed);
    compare_runs("large stateless firing group", &large, &[20, 60]);
    // The host knows a stateless group fires at most once an event a particle of its table, so
    // a bucketed stream of one counts its firings into order in every batch whose table (and
    // the batch's before it) holds at most COUNTED_MAX threads. A burst of 10,000 shells makes
    // the first batches' tables larger (buckets); once it has died, the stream's few hundred
    // make them small (counting): both orderings, and the switch between, give the reference's
    // children.
    let switching = graph(
        &src("Auto")
            .replace("capacity: 200,", "capacity: 12000,")
            .replace("burst: 5,", "burst: 10000,"),
    );
    assert_eq!(switching.streams[0].ordering, Ordering::Bucketed);
    compare_runs(
        "stateless firing group, ordering switched",
        &switching,
        &[20, 70, 120],
    );
}

#[test]
fn a_group_outside_the_events_keeps_its_own_state_decision() {
    // Stars that neither fire nor are fed by events: Exact, a burst, no lifetime; stateless
    // beside a stateful fed group and a stateless firing one, and all match the reference.
    let src = r#"Effect(
        name: "rockets",
        capacity: 64,
        emitters: [Emitter(burst: 3, rate: 10.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 12.0, 0.0)),
                           lifetime: Some((0.3, 0.5)))],
        forces: [Gravity((0.0, -9.81, 0.0))],
        events: [Event(on: Death, target: "sparks", count: 10, velocity: Radial(speed: (2.0, 4.0)), lifetime: Some((0.5, 1.0)))],
        groups: [
            Group(name: "sparks", capacity: 2000),
            Group(name: "stars", capacity: 100, emitters: [Emitter(burst: 100, shape: Sphere(center: (0.0, 20.0, 0.0), radius: 10.0),
                                                                  velocity: Constant((0.0, 0.0, 0.0)))]),
        ],
    )"#;
    let g = graph(src);
    let stateless: Vec<bool> = g
        .groups
        .iter()
        .map(|k| k.effect.layout.stateless())
        .collect();
    assert_eq!(stateless, [true, false, true], "rockets, sparks, stars");
    let sim = compare_runs("stars", &g, &[30, 60]);
    assert_eq!(sim.group_totals(2).unwrap().alive, 100);
    assert!(sim.group_totals(1).unwrap().spawned > 0);
}

#[test]
fn collisions_fire_events_where_the_particle_hits() {
    // Drops fall on a plane at y = 0 and stop; each contact spawns 3 droplets at the drop.
    let src = r#"Effect(
        name: "drops",
        capacity: 300,
        dt: 0.01,
        emitters: [Emitter(rate: 400.0, shape: Box(min: (-2.0, 1.0, -2.0), max: (2.0, 2.0, 2.0)),
                           velocity: Constant((0.3, -3.0, 0.0)), lifetime: Some((2.0, 2.0)))],
        forces: [Gravity((0.0, -9.81, 0.0))],
        collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.0, friction: 1.0)],
        kill: [InsideBox(min: (-9.0, -1.0, -9.0), max: (9.0, 0.001, 9.0))],
        events: [Event(on: Collide, target: "droplets", count: 3, velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 40.0, speed: (0.5, 1.0)),
                       lifetime: Some((0.05, 0.05)), inherit_velocity: 0.0)],
        groups: [Group(name: "droplets", capacity: 2000, forces: [Gravity((0.0, -9.81, 0.0))], integrator: SemiImplicitEuler)],
    )"#;
    let g = graph(src);
    let sim = compare_runs("drops", &g, &[40, 70]);
    let droplets = sim.group_records(1).unwrap();
    assert!(!droplets.is_empty());
    // A droplet lives 5 steps at under 1.1 m/s from where its drop touched the plane.
    for d in &droplets {
        assert!(d.position.y > -1e-3 && d.position.y < 0.06, "{d:?}");
    }
}

#[test]
fn two_streams_into_one_group_take_its_slots_in_stream_order() {
    // Each stream's ordering pops its children's slots from the child's counters as its first
    // kernel starts, and the stream's spawn reads what it wrote: the second stream into the same
    // group must pop after the first one's spawn. Both streams fire every step here (ticks and
    // deaths), the child fills up, and the children and drops match the reference, counted
    // (a firing group of 2,000 slots) and bucketed (9,000).
    use plume::compiler::events::Ordering;
    for (capacity, ordering) in [(2000, Ordering::Counted), (9000, Ordering::Bucketed)] {
        let src = format!(
            r#"Effect(
        name: "twice",
        capacity: {capacity},
        dt: 0.01,
        emitters: [Emitter(rate: 40000.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 1.0),
                           velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.03, 0.08)))],
        forces: [Gravity((0.0, -9.81, 0.0))],
        events: [
            Event(on: Every(0.02), target: "motes", count: 2, velocity: Radial(speed: (0.2, 0.4)), lifetime: Some((0.1, 0.1))),
            Event(on: Death, target: "motes", count: 3, velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.05, 0.2))),
        ],
        groups: [Group(name: "motes", capacity: 6000, forces: [Gravity((0.0, -9.81, 0.0))])],
    )"#
        );
        let g = graph(&src);
        assert_eq!(g.streams.len(), 2);
        assert!(g.streams.iter().all(|s| s.ordering == ordering));
        let sim = compare_runs(&format!("two streams, {ordering:?}"), &g, &[3, 12, 25]);
        let t = sim.group_totals(1).unwrap();
        assert!(
            t.spawned > 6000 && t.dropped > 0,
            "{ordering:?}: both streams spawn and the group fills up: {t:?}"
        );
    }
}

#[test]
fn events_that_cannot_fire_are_warned_about() {
    let src = r#"Effect(
        name: "immortal",
        capacity: 10,
        emitters: [Emitter(burst: 10, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))],
        events: [
            Event(on: Death, target: "a", count: 1, lifetime: Some((1.0, 1.0))),
            Event(on: Collide, target: "a", count: 1, lifetime: Some((1.0, 1.0))),
        ],
        groups: [Group(name: "a", capacity: 100)],
    )"#;
    let g = graph(src);
    let text = g.all_warnings().render("immortal.ron", src);
    assert!(
        text.contains("events[0].on: fires on death, but the group's particles never die"),
        "{text}"
    );
    assert!(
        text.contains("events[1].on: fires on collision, but the group has no colliders"),
        "{text}"
    );
    assert!(text.contains("immortal.ron:6:"), "located: {text}");
}

#[test]
fn every_example_group_draws_like_its_cpu_fed_drawing() {
    // Each group's draw against the reference drawing of the same particles (the criterion of
    // tests/render.rs's every-example test: within a few 8-bit steps).
    for path in graph_examples() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let gpu = gpu();
        let mut sim = Effect::from_graph(&gpu, compile_graph_file(&path)).unwrap();
        sim.run(100, |_| {}).unwrap();
        let mut lit_groups = 0;
        for g in 0..sim.group_names().len() {
            let (gpu_img, cpu_img) = draw_group_and_reference(&sim, g, 160);
            // Pixels brighter than the background's darkest corner by 20 levels.
            let bg = &gpu_img[..4];
            let lit = gpu_img
                .chunks(4)
                .filter(|p| p.iter().zip(bg).any(|(a, b)| a.abs_diff(*b) > 20))
                .count();
            lit_groups += usize::from(lit > 20);
            let (mean, max, over) = differences(&gpu_img, &cpu_img, 2);
            eprintln!(
                "{name} group {}: mean {mean:.5}, max {max}, {over} over 2, {lit} pixels lit",
                sim.group_names()[g]
            );
            assert!(
                mean < 0.01 && max <= 4 && over * 2000 < gpu_img.len(),
                "{name} group {g}: GPU and CPU-fed draws differ"
            );
        }
        assert!(
            lit_groups >= 2,
            "{name}: only {lit_groups} groups show on screen"
        );
    }
}

#[test]
fn groups_split_into_chunks_run_as_one_buffer_does() {
    // Every group's particles split into buffers of 37 slots: the parents' records are indexed
    // by global slot and each chunk spawns only the children whose slots it holds.
    let g = graph(SMALL_FIREWORKS);
    let gpu = gpu();
    let run = |chunk: Option<u64>| {
        let mut sim = Effect::with_chunk_slots(&gpu, g.clone(), chunk).unwrap();
        sim.run(40, |_| {}).unwrap();
        assert_eq!(oracle::chunk_count(&sim, 2).unwrap() > 1, chunk.is_some());
        (0..3)
            .map(|k| (sim.group_totals(k).unwrap(), sim.group_records(k).unwrap()))
            .collect::<Vec<_>>()
    };
    let (whole, split) = (run(None), run(Some(37)));
    for (k, (a, b)) in whole.iter().zip(&split).enumerate() {
        assert_eq!(a.0, b.0, "group {k}: totals differ");
        let ids = |r: &[ParticleRecord]| r.iter().map(|p| p.id).collect::<Vec<_>>();
        assert_eq!(ids(&a.1), ids(&b.1), "group {k}: live ids differ");
        for (p, q) in a.1.iter().zip(&b.1) {
            // The same kernels on the same values: the same f32 results.
            assert_eq!(p.position, q.position, "group {k} particle {}", p.id);
        }
    }
    assert!(whole[2].1.len() > 37, "embers fill more than one chunk");
}

#[test]
fn firings_counted_or_bucketed_spawn_the_reference_children_when_thousands_fire_at_once() {
    // A group of up to COUNTED_MAX slots has its firings counted into order; a larger one drops
    // them into buckets by id (one id a bucket here: the ids span fewer than the slots). Each here fires thousands at once (a burst whose lifetimes all end at
    // step 9: counting's worst case, every slot firing) and a few a step after (a stream of
    // 200 a second), and gives the reference's children.
    use plume::compiler::events::{Ordering, COUNTED_MAX};
    for (capacity, ordering) in [
        (COUNTED_MAX, Ordering::Counted),
        (COUNTED_MAX + 2000, Ordering::Bucketed),
    ] {
        let burst = capacity - 200;
        let src = format!(
            r#"Effect(
        name: "crowd",
        capacity: {capacity},
        dt: 0.01,
        emitters: [
            Emitter(burst: {burst}, shape: Box(min: (-5.0, 0.0, -5.0), max: (5.0, 1.0, 5.0)),
                    velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 30.0, speed: (1.0, 2.0)), lifetime: Some((0.1, 0.1))),
            Emitter(rate: 200.0, shape: Sphere(center: (0.0, 3.0, 0.0), radius: 1.0),
                    velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.05, 0.2))),
        ],
        forces: [Gravity((0.0, -9.81, 0.0))],
        events: [Event(on: Death, target: "children", count: 1, velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.3, 0.3)))],
        groups: [Group(name: "children", capacity: 12000, forces: [Gravity((0.0, -9.81, 0.0))])],
    )"#
        );
        let g = graph(&src);
        assert_eq!(g.streams[0].ordering, ordering);
        let sim = compare_runs(&format!("{ordering:?}"), &g, &[9, 11, 30]);
        let t = sim.group_totals(1).unwrap();
        assert!(
            u64::from(burst) < t.spawned,
            "{ordering:?}: the burst's children: {t:?}"
        );
    }
}

#[test]
fn firings_whose_ids_span_more_than_the_slots_spawn_in_id_order_by_bits_or_shared_buckets() {
    // 3,000 immortal particles born first (ids 0..3,000) tick every step beside a stream of
    // short-lived ones that asks for more particles a step than the 8,000 free slots hold: each
    // step the firing ids run from 0 past the newest, far more than the 11,000 slots. Under
    // 32 ids a slot, the ordering sets a bit an id and counts the bits below each firing's
    // (past 8,192 words, 262,144 ids, a group count covers more than 4 words: the faster
    // stream by step 10); past 32 ids a slot (by step 14), a bucket holds several ids (a shift
    // above 0) and the firings of each bucket are ranked among themselves. The children
    // (dropped where they overflow their group) match the reference's, which orders by id
    // alone.
    use plume::compiler::events::Ordering;
    const SLOTS: u64 = 11_000;
    for (rate, checkpoints, spread) in [
        (200_000.0, [1, 6, 15], SLOTS..32 * 8192),
        (3_000_000.0, [1, 6, 10], 32 * 8192..32 * SLOTS),
        (3_000_000.0, [1, 14, 20], 32 * SLOTS..u64::MAX),
    ] {
        let src = format!(
            r#"Effect(
        name: "ancients",
        capacity: {SLOTS},
        dt: 0.01,
        emitters: [
            Emitter(burst: 3000, shape: Box(min: (-5.0, 0.0, -5.0), max: (5.0, 1.0, 5.0)),
                    velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 30.0, speed: (0.1, 0.2)), lifetime: None),
            Emitter(rate: {rate:?}, shape: Sphere(center: (0.0, 3.0, 0.0), radius: 1.0),
                    velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.02, 0.04))),
        ],
        forces: [Gravity((0.0, -9.81, 0.0))],
        events: [Event(on: Every(0.01), target: "ticks", count: 1, velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.05, 0.05)))],
        groups: [Group(name: "ticks", capacity: 30000, forces: [Gravity((0.0, -9.81, 0.0))])],
    )"#
        );
        let g = graph(&src);
        assert_eq!(g.streams[0].ordering, Ordering::Bucketed);
        let sim = compare_runs(&format!("ids spread at {rate}/s"), &g, &checkpoints);
        let parents = sim.group_records(0).unwrap();
        let ids = parents.iter().map(|p| u64::from(p.id));
        let (lo, hi) = (ids.clone().min().unwrap(), ids.max().unwrap());
        assert!(
            spread.contains(&(hi - lo)),
            "at {rate}/s after {checkpoints:?} steps the live (and firing) ids span {lo}..{hi}, not {spread:?}"
        );
        let t = sim.group_totals(1).unwrap();
        assert!(
            t.dropped > 0 && t.spawned > 10_000,
            "at {rate}/s ticks spawned and dropped: {t:?}"
        );
    }
}

#[test]
fn a_stateless_group_that_never_dies_fires_every_period_as_its_stateful_twin_does() {
    // A burst with no lifetime, stateless, ticking every step: its particles fire every step
    // for as long as the run goes (the closed form once took their unset death step for 0,
    // firing once and never again), as the same group stateful does, and as the reference.
    let src = |state: &str| {
        format!(
            r#"Effect(
        name: "ticks",
        capacity: 64,
        seed: 1,
        state: {state},
        emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
                           velocity: Constant((0.0, 0.0, 0.0)))],
        events: [Event(on: Every(0.016666667), target: "dots", count: 1, lifetime: Some((0.02, 0.02)))],
        groups: [Group(name: "dots", capacity: 256)],
    )"#
        )
    };
    let stateless = graph(&src("Auto"));
    assert!(
        stateless.groups[0].effect.layout.stateless(),
        "{}",
        stateless.groups[0].effect.ir.state_reason
    );
    let a = compare_runs("immortal stateless ticks", &stateless, &[10, 300]);
    let b = compare_runs(
        "immortal stateful ticks",
        &graph(&src("Stateful")),
        &[10, 300],
    );
    let (ta, tb) = (a.group_totals(1).unwrap(), b.group_totals(1).unwrap());
    assert_eq!(ta, tb);
    // 64 firings a step, each spawning its dot the step after.
    assert_eq!(ta.spawned, 64 * 299, "{ta:?}");
}

#[test]
fn an_event_spawn_reads_where_its_parent_fired_as_origin() {
    // Children whose velocity adds the firing particle's position (hanabi's firework streaks)
    // and whose offset grows with its height, against the reference in every group; and an
    // emitter's origin is the effect's (0, 0, 0).
    let source = r#"Effect(
    name: "rockets",
    capacity: 16,
    seed: 6,
    dt: 0.016666666666666666,
    emitters: [Emitter(rate: 20.0, shape: Custom("origin + vec3(rand(0) - 0.5, 0.0, 0.0)"),
                       velocity: Custom("vec3(0.0, 8.0, 0.0) + origin"), lifetime: Some((0.3, 0.5)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: Euler,
    events: [Event(on: Death, target: "sparks", count: 20,
                   shape: Custom("normalize(vec3(rand(0) - 0.5, rand(1) - 0.5, rand(2) - 0.5)) * 0.1 * origin.y"),
                   velocity: Custom("origin * 0.5 + vec3(rand(3) - 0.5, 0.0, rand(4) - 0.5)"),
                   lifetime: Some((0.5, 0.5)))],
    groups: [Group(name: "sparks", capacity: 2000, forces: [Gravity((0.0, -9.81, 0.0))], integrator: Euler)],
)"#;
    let sim = compare_runs("origin", &graph(source), &[20, 45, 70]);
    let sparks = sim.group_records(1).unwrap();
    assert!(sparks.len() > 100, "{} sparks", sparks.len());
    // The origin matters: the rockets die about 2.4 m up, so half of that is added to every
    // spark's upward speed, against the same effect with the origin at zero.
    let mean_up = |records: &[plume::compiler::reference::ParticleRecord]| {
        records.iter().map(|r| r.velocity.y).sum::<f64>() / records.len() as f64
    };
    let zero = graph(&source.replace("origin", "vec3(0.0, 0.0, 0.0)"));
    let mut without = Effect::from_graph(&gpu(), zero).unwrap();
    without.run(70, |_| {}).unwrap();
    let (with, plain) = (
        mean_up(&sparks),
        mean_up(&without.group_records(1).unwrap()),
    );
    assert!(
        with - plain > 0.8,
        "mean upward speed {with} with the origin, {plain} without"
    );
    // An emitter's origin is the effect's: the rockets spawn within half a metre of x = 0.
    for r in sim.group_records(0).unwrap() {
        assert!(
            r.position.x.abs() <= 0.5 + 1e-6,
            "rocket at {:?}",
            r.position
        );
    }
}
