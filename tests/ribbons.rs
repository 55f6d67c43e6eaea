//! Ribbons that join particles (`render.ribbon`) on the GPU (llvmpipe in CI): the table the
//! spawn kernels write holds the links the f64 reference gives (emitters' bursts split into
//! ribbons, rows shared and overwritten, children joined by their parent), the drawn strips
//! match the CPU-fed drawing of the chains the table joins (lit too), a segment is drawn only between
//! particles the table joins, and an effect without ribbons keeps no table.

mod common;

use common::*;
use plume::compiler::graph::{compile_graph_str, CompiledGraph, ReferenceGraph};
use plume::compiler::passes::layout::Role;
use plume::compiler::reference::ReferenceSim;
use plume::compiler::ribbon::{Link, Table};
use plume::runtime::oracle;
use plume::runtime::Effect;
use plume::CompileOptions;

/// Bolts of 12 particles every 6 steps, each its own ribbon (split 12: bolt n's key is 2n of
/// two emitters), living 15 steps: three bolts alive at once but one row for their even keys,
/// so each bolt overwrites the last one's entries while its particles still live; and a steady
/// stream from a second emitter, two a step, whose ribbons (odd keys) fall in row 1.
const BOLTS: &str = r#"Effect(
    name: "bolts",
    capacity: 128,
    seed: 4,
    dt: 0.016666666666666666,
    emitters: [
        Emitter(burst: 12, every: Some(0.1), shape: Custom("vec3(0.3 * sin(index * 1.7), 1.5 - 0.25 * (index - 12.0 * floor(index / 12.0)), 0.0)"),
                velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((0.25, 0.25))),
        Emitter(rate: 120.0, shape: Custom("vec3(cos(4.0 * t) - 1.5, sin(4.0 * t), 0.0)"),
                velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((0.2, 0.2))),
    ],
    camera: Camera(eye: (0.0, 0.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 0.9, 0.6, 1.0)), (1.0, (0.2, 0.4, 1.0, 0.3))],
                   size: [(0.0, 0.12), (1.0, 0.04)], background: (0.0, 0.0, 0.0),
                   ribbon: Some(Ribbon(points: 12, ribbons: 2, split: Some(12)))),
)"#;

/// Three heads that swing round, each shedding two bodies a step (an `Every` event) that live
/// 12 steps; every head's bodies are one ribbon, keyed by the head's id.
const WORMS: &str = r#"Effect(
    name: "heads",
    capacity: 4,
    seed: 8,
    dt: 0.016666666666666666,
    emitters: [Emitter(burst: 3, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
                       velocity: Custom("vec3(-x.y, x.x, 0.0) * 4.0"))],
    forces: [Custom(accel: "-16.0 * vec3(x.x, x.y, 0.0)")],
    integrator: Rk4,
    camera: Camera(eye: (0.0, 0.0, 5.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(size: [(0.0, 0.05)], background: (0.0, 0.0, 0.0)),
    events: [Event(on: Every(0.0166667), target: "bodies", count: 2, lifetime: Some((0.2, 0.2)))],
    groups: [Group(name: "bodies", capacity: 128,
                   render: Render(color: [(0.0, (1.0, 0.5, 0.2, 1.0)), (1.0, (1.0, 0.1, 0.1, 0.2))],
                                  size: [(0.0, 0.1)], background: (0.0, 0.0, 0.0),
                                  ribbon: Some(Ribbon(points: 32, ribbons: 4))))],
)"#;

fn graph(source: &str) -> CompiledGraph {
    compile_graph_str(source, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("test.ron", source)))
}

/// The GPU's table of group `g` as (id, link) per entry.
fn gpu_table(sim: &Effect, g: usize) -> Table {
    oracle::read_ribbon_table(sim, g)
        .unwrap()
        .into_iter()
        .map(|e| e.map(|(id, link, _)| (id, link)))
        .collect()
}

#[test]
fn bursts_split_into_ribbons_write_the_reference_table() {
    let effect = compile(BOLTS);
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, effect.clone()).unwrap();
    let mut reference = ReferenceSim::new(&effect.ir);
    let mut done = 0;
    for at in [1u64, 7, 20, 37] {
        sim.run(at - done, |_| {}).unwrap();
        reference.run(at - done);
        done = at;
        let (g, c) = (gpu_table(&sim, 0), reference.ribbon_table().clone());
        assert_eq!(g, c, "the tables differ after {at} steps");
    }
    // Bolt 6 (spawned at step 36) overwrote bolt 5's entries, though bolt 5's particles
    // (spawned at step 30, living 15 steps) still live after 37 steps.
    let table = gpu_table(&sim, 0);
    let bolt = |key: u32| table.iter().flatten().filter(|(_, l)| l.key == key).count();
    assert_eq!((bolt(6 * 2), bolt(5 * 2)), (12, 0));
    let live: Vec<u32> = sim.records().unwrap().iter().map(|r| r.id).collect();
    // Ids: 12 a bolt and 2 a step of the stream, the bolt's first, in emitter order.
    assert!(
        live.contains(&(5 * 12 + 30 * 2)),
        "bolt 5 is dead: {live:?}"
    );
    // The stream's links: key 1 + 2 ⌊k / 12⌋, ordinal k mod 12.
    let stream: Vec<Link> = table
        .iter()
        .flatten()
        .filter(|(_, l)| l.key % 2 == 1 && l.key > 1)
        .map(|(_, l)| *l)
        .collect();
    assert!(!stream.is_empty());
}

#[test]
fn children_join_their_parent_in_the_order_it_sheds_them() {
    let g = graph(WORMS);
    let gpu = gpu();
    let mut sim = Effect::from_graph(&gpu, g.clone()).unwrap();
    let mut reference = ReferenceGraph::new(&g);
    for _ in 0..3 {
        sim.run(9, |_| {}).unwrap();
        reference.run(9);
        assert_eq!(
            gpu_table(&sim, 1),
            reference.group(1).ribbon_table().clone()
        );
    }
    // Each head's bodies are one chain in the reference's joins: 12 steps of two, the oldest
    // pair's first just dead (lifetime 12 steps), so 3 chains of 22 to 24 points.
    let ir = &g.groups[1].effect.ir;
    let ribbon = ir.render.ribbon.unwrap();
    let records = reference.records(1);
    let alive = |id: u32| records.iter().any(|r| r.id == id);
    let chains = ribbon.chains(reference.group(1).ribbon_table(), &alive);
    assert_eq!(chains.len(), 3, "{chains:?}");
    for chain in &chains {
        assert!((22..=24).contains(&chain.len()), "{chain:?}");
        assert!(
            chain.windows(2).all(|w| w[0] < w[1]),
            "not in shedding order: {chain:?}"
        );
    }
}

#[test]
fn the_drawn_ribbons_match_the_cpu_fed_drawing() {
    // The reference drawing places each point's vertices in f64 in world space, the GPU in f32
    // in view space: an edge pixel's coverage moves by a step or two, as for trails
    // (tests/trails.rs); a segment missing or joined wrongly changes tens of pixels by tens.
    for (name, source, g, steps) in [("bolts", BOLTS, 0, 33u64), ("worms", WORMS, 1, 30)] {
        let gpu = gpu();
        let mut sim = Effect::from_graph(&gpu, graph(source)).unwrap();
        sim.run(steps, |_| {}).unwrap();
        let (gpu_img, cpu_img) = draw_group_and_reference(&sim, g, 200);
        if std::env::var_os("PLUME_DUMP").is_some() {
            image::save_buffer(
                format!("/tmp/ribbons_{name}.png"),
                &gpu_img,
                200,
                200,
                image::ColorType::Rgba8,
            )
            .unwrap();
        }
        let lit = gpu_img.chunks(4).filter(|p| p[0] > 40).count();
        let (mean, max, over) = differences(&gpu_img, &cpu_img, 2);
        eprintln!("{name}: mean {mean:.5}, max {max}, {over} over 2, {lit} pixels lit");
        assert!(lit > 100, "{name}: only {lit} pixels lit");
        assert!(
            mean < 0.02 && max <= 8 && over * 1000 < gpu_img.len(),
            "{name}: GPU and CPU-fed ribbons differ: mean {mean}, max {max}, {over} over 2"
        );
    }
}

/// A lit look lights its ribbons as it lights trails (each strip a flat card facing the eye,
/// square to the ribbon): the lit bolts match the reference drawing (each point lit in f64)
/// as closely as the unlit ones do, and the light changes them.
#[test]
fn lit_ribbons_match_the_cpu_fed_drawing() {
    let lit_bolts = BOLTS
        .replace(
            "    render: Render(",
            "    lights: [Point(position: (1.0, 1.0, 1.5), color: (1.0, 0.8, 0.6), intensity: 2.0, range: 5.0),\n             Ambient(intensity: 0.2)],\n    render: Render(",
        )
        .replace(
            "split: Some(12)))),",
            "split: Some(12))), lit: Some(Lit(wrap: 0.3, emissive: 0.1))),",
        );
    let gpu = gpu();
    let draw = |source: &str| {
        let mut sim = Effect::from_graph(&gpu, graph(source)).unwrap();
        assert_eq!(sim.compiled().ir.render.lit.is_some(), source != BOLTS);
        sim.run(33, |_| {}).unwrap();
        draw_group_and_reference(&sim, 0, 200)
    };
    let (lit, reference) = draw(&lit_bolts);
    let (unlit, _) = draw(BOLTS);
    let (mean, max, over) = differences(&lit, &reference, 2);
    assert!(
        mean < 0.02 && max <= 8 && over * 1000 < lit.len(),
        "GPU and CPU-fed lit ribbons differ: mean {mean}, max {max}, {over} over 2"
    );
    let (_, _, changed) = differences(&lit, &unlit, 8);
    assert!(changed > 200, "the light changes only {changed} channels");
}

#[test]
fn only_a_group_drawn_as_ribbons_keeps_a_table() {
    let with = compile(BOLTS);
    assert!(with
        .layout
        .bindings
        .iter()
        .any(|b| b.role == Role::RibbonTable));
    assert_eq!(
        with.ir.render.ribbon.unwrap().table_bytes(),
        2 * 12 * 16,
        "two rows of 12 entries of 16 bytes"
    );
    let without = compile(&BOLTS.replace(
        "ribbon: Some(Ribbon(points: 12, ribbons: 2, split: Some(12)))",
        "",
    ));
    assert!(!without
        .layout
        .bindings
        .iter()
        .any(|b| b.role == Role::RibbonTable));
    assert!(!without.draw_wgsl.contains("ribbon"));
    assert!(!without.wgsl.contains("ribbon"));
}
