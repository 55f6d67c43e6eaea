//! Every example effect on the GPU (llvmpipe in CI) against the CPU f64 reference.
//!
//! Tolerance. The GPU computes in f32 (unit roundoff u = 2^-24), the reference in f64. Each step
//! a particle's position and velocity go through a handful of rounded operations (the force sum,
//! the velocity update, the position update, a contact), each off by at most about
//! u·(|x| + 1 m) once scaled to position. Bounding that by 4 roundings a step and letting errors
//! add up linearly (a worst case: measured errors are about ten times smaller) gives
//! |x_gpu - x_cpu| <= 4 N u (1 + |x|) after N steps: 2.4e-5 relative at N = 100, for one force
//! evaluation a step; substeps and multi-stage integrators multiply it (`roundings_per_step`). Velocities get
//! the same bound relative to (1 + |v|). Spawn draws are bit-identical integer hashes and deaths
//! are integer steps, so the sets of live ids must be equal exactly.

mod common;

use common::compare::{compare_at, curved_colliders, roundings_per_step};
use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;

/// The `.ron` files of `dir` (under the repository), in name order.
fn effect_files(dir: &str) -> Vec<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some("ron"))
        .collect();
    paths.sort();
    paths
}

/// Runs the single-group effect at `path` 50 and 100 steps on the GPU and in the reference
/// and compares them (see the module docs); returns whether any particle was alive.
fn matches_the_reference(path: &std::path::Path) -> bool {
    compare_runs(path, compile_file(path), None)
}

/// Runs `effect` (compiled from `path`) on the GPU and in the reference for 50 and 100 steps,
/// `burst` fired from code into both first when given; compares them at each; returns whether
/// any particle was alive to compare.
fn compare_runs(
    path: &std::path::Path,
    effect: plume::CompiledEffect,
    burst: Option<plume::compiler::bursts::Burst>,
) -> bool {
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    let gpu = gpu();
    let mut gsim = Effect::new(&gpu, effect.clone()).expect("GPU sim");
    let mut csim = ReferenceSim::new(&effect.ir);
    if let Some(burst) = burst {
        gsim.burst(0, burst).unwrap();
        csim.burst(burst).unwrap();
    }
    let mut seen_alive = false;
    for steps in [50u64, 100] {
        gsim.run(50, |_| {}).unwrap();
        csim.run(50);
        let (gt, ct) = (gsim.totals().unwrap(), csim.totals());
        assert_eq!(gt, ct, "{name}: totals differ after {steps} steps");
        let (g, c) = (gsim.records().unwrap(), csim.records());
        seen_alive |= !c.is_empty();
        compare_at(
            &name,
            steps,
            effect.ir.flock.is_some(),
            curved_colliders(&effect.ir),
            effect.layout.half_motion.then_some(effect.ir.dt),
            roundings_per_step(&effect.ir),
            &g,
            &c,
        );
    }
    seen_alive
}

#[test]
fn every_example_matches_the_reference_after_50_and_100_steps() {
    let mut checked = 0;
    for path in effect_files("effects") {
        if is_graph_file(&path) {
            // Effects with groups and events: tests/events.rs, group by group.
            continue;
        }
        assert!(
            matches_the_reference(&path),
            "{path:?}: nothing alive to compare"
        );
        checked += 1;
    }
    assert!(checked >= 6, "expected the six examples, checked {checked}");
}

#[test]
fn every_bevy_hanabi_port_compiles_without_warnings_and_matches_the_reference() {
    // effects/hanabi: bevy_hanabi's examples written as Plume effects (docs/from-hanabi.md).
    let files = effect_files("effects/hanabi");
    assert!(!files.is_empty(), "no ports in effects/hanabi");
    for path in files {
        let graph = compile_graph_file(&path);
        let warnings = graph.all_warnings();
        let source = std::fs::read_to_string(&path).unwrap();
        assert!(
            warnings.is_empty(),
            "{}",
            warnings.render(&path.display().to_string(), &source)
        );
        if is_graph_file(&path) {
            // Groups joined by events: their f64 run is tests/events.rs's kind; here the GPU
            // graph runs and spawns.
            let gpu = gpu();
            let mut sim = Effect::from_graph(&gpu, graph).expect("GPU graph");
            sim.run(100, |_| {}).unwrap();
            assert!(
                sim.group_totals(0).unwrap().spawned > 0,
                "{path:?} spawns nothing"
            );
        } else if !matches_the_reference(&path) {
            // A port that spawns only as its host drives it (a live rate switched on, bursts
            // fired from code): compiled to take bursts, one fired below the origin (in
            // activate's water), so that there is something to compare.
            let options = plume::CompileOptions {
                base_dir: path.parent().map(|p| p.to_path_buf()),
                bursts: true,
                ..Default::default()
            };
            let source = std::fs::read_to_string(&path).unwrap();
            let effect = plume::compile_str(&source, &options).unwrap();
            let burst = plume::compiler::bursts::Burst::new(0, 100).at([0.0, -1.0, 0.0]);
            assert!(
                compare_runs(&path, effect, Some(burst)),
                "{path:?}: nothing alive to compare, even after a burst"
            );
        }
    }
}
