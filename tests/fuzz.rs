//! Fuzzing the compiler: raw bytes, byte-edited example files and structurally valid random
//! effects (tests/common/effect_gen.rs). The compiler must never panic; every error must render
//! with a message; every effect it accepts must give WGSL that naga validates (compile_str runs
//! naga; a rejection is `CompileError::Internal`, a Plume bug) and IR whose numbers are finite.
//!
//! CI runs a few hundred inputs per kind from a fixed seed (`PLUME_FUZZ_SEED` picks another).
//! Build in debug to have integer overflow checked. The long run (docs/robustness.md):
//! `PLUME_FUZZ_CASES=350000 cargo test --release --test fuzz -- --nocapture` (three kinds, so
//! just over 10^6 inputs); each test prints how many inputs it ran and how many were accepted.

mod common;

use std::sync::atomic::{AtomicU64, Ordering};

use common::effect_gen::{self, effect, mutate, Flavor};
use glam::DVec3;
use plume::compiler::graph::compile_graph_str;
use plume::{compile_str, CompileError, CompileOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// Inputs per test: `PLUME_FUZZ_CASES`, or 300 (CI).
fn cases() -> u32 {
    std::env::var("PLUME_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300)
}

/// The generator's seed: `PLUME_FUZZ_SEED`, or a fixed one, so that CI runs the same inputs
/// every time (a failure there is reproducible; long runs pass their own seeds).
fn seed() -> [u8; 32] {
    let s: u64 = std::env::var("PLUME_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_261_121);
    let mut bytes = [0u8; 32];
    for (i, b) in s.to_le_bytes().iter().cycle().take(32).enumerate() {
        bytes[i] = b.wrapping_add(i as u8);
    }
    bytes
}

fn runner() -> TestRunner {
    TestRunner::new_with_rng(
        Config {
            cases: cases(),
            // Failures are reported with the shrunk input; no regression files are written.
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &seed()),
    )
}

/// Compiles `source` and checks the contract; returns whether it was accepted.
fn check(source: &str) -> Result<bool, TestCaseError> {
    match compile_graph_str(source, &CompileOptions::default()) {
        Ok(graph) => {
            // Warnings must render (their spans point into the source).
            let _ = graph.all_warnings().render("fuzz.ron", source);
            for group in &graph.groups {
                let c = &group.effect;
                prop_assert!(!c.wgsl.is_empty());
                prop_assert!(c.ir.dt.is_finite() && c.ir.dt > 0.0, "dt {}", c.ir.dt);
                prop_assert!(c.layout.bytes_per_particle > 0);
            }
            Ok(true)
        }
        Err(CompileError::Invalid(d)) => {
            prop_assert!(!d.items.is_empty(), "an error with no diagnostics");
            let text = d.render("fuzz.ron", source);
            prop_assert!(text.contains("error"), "{text}");
            Ok(false)
        }
        Err(e @ CompileError::Internal(_)) => Err(TestCaseError::fail(format!(
            "naga rejected accepted input:\n{source}\n{e}"
        ))),
    }
}

/// Runs `strategy` through [`check`], then prints the count.
fn fuzz<S: Strategy>(name: &str, strategy: S, to_text: impl Fn(S::Value) -> String) {
    let accepted = AtomicU64::new(0);
    let total = AtomicU64::new(0);
    let mut runner = runner();
    let result = runner.run(&strategy, |value| {
        let text = to_text(value);
        total.fetch_add(1, Ordering::Relaxed);
        if check(&text)? {
            accepted.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    });
    println!(
        "fuzz {name}: {} inputs, {} accepted, no panic",
        total.load(Ordering::Relaxed),
        accepted.load(Ordering::Relaxed)
    );
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

#[test]
fn raw_bytes_never_panic_the_compiler() {
    fuzz(
        "raw bytes",
        prop::collection::vec(any::<u8>(), 0..400),
        |bytes| String::from_utf8_lossy(&bytes).into_owned(),
    );
}

/// Bytes that matter to RON, so that edits reach past the first syntax error.
const RON_BYTES: &[u8] = b"()[],:.-+e0123456789 \n\"SomeNoneEmitterPoint_xyz";

#[test]
fn edited_example_files_never_panic_the_compiler() {
    let examples: Vec<String> = std::fs::read_dir("effects")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let n = examples.len();
    let edit = (any::<usize>(), any::<u8>(), prop::sample::select(RON_BYTES));
    fuzz(
        "edited examples",
        (0..n, prop::collection::vec(edit, 1..6)),
        move |(which, edits)| mutate(&examples[which], &edits),
    );
}

#[test]
fn wild_structured_effects_are_rejected_cleanly_or_give_valid_wgsl() {
    // Two thirds with edge values anywhere, one third valid numbers with every feature (planes,
    // kill volumes, Exact), so that many files reach the passes and naga.
    let strategy = prop_oneof![2 => effect(Flavor::Wild), 1 => effect(Flavor::Valid)];
    fuzz("structured", strategy, |text| text);
}

#[test]
fn wild_groups_and_events_are_rejected_cleanly_or_give_valid_wgsl() {
    // Effects of three groups with events between them: wild ones aim at unknown groups,
    // themselves and back up the chain, and carry edge values anywhere.
    let strategy = prop_oneof![
        2 => effect_gen::graph_effect(Flavor::Wild),
        1 => effect_gen::graph_effect(Flavor::Valid),
        1 => effect_gen::graph_effect(Flavor::Tame),
    ];
    fuzz("groups and events", strategy, |text| text);
}

#[test]
fn tame_graphs_are_all_accepted() {
    let mut runner = runner();
    runner
        .run(&effect_gen::graph_effect(Flavor::Tame), |text| {
            let accepted = check(&text)?;
            prop_assert!(accepted, "tame graph rejected:\n{text}");
            Ok(())
        })
        .unwrap();
}

#[test]
fn tame_effects_are_all_accepted() {
    // The differential test's generator must produce valid effects, or it would test nothing.
    let mut runner = runner();
    runner
        .run(&effect(Flavor::Tame), |text| {
            let accepted = check(&text)?;
            prop_assert!(accepted, "tame effect rejected:\n{text}");
            Ok(())
        })
        .unwrap();
}

/// An effect whose only force is `Custom(accel: "<expr>")`.
fn custom_effect(expr: &str) -> String {
    format!(
        "Effect(name: \"fuzz\", capacity: 16, params: {{\"k\": 0.5}},\n    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)), lifetime: Some((1.0, 2.0)))],\n    forces: [Custom(accel: \"{expr}\")],\n    integrator: Verlet,\n)"
    )
}

#[test]
fn random_expression_trees_are_rejected_cleanly_or_total() {
    // Random typed trees over every function and operator (edge constants, the particle
    // context), deep chains, and trees of the wrong type: no panic, naga-valid WGSL, and an f64
    // value that is finite at ordinary and at extreme states.
    let deep = (1usize..80).prop_map(|n| format!("{}x{}", "-(".repeat(n), ")".repeat(n)));
    let strategy = prop_oneof![
        6 => effect_gen::expression(Flavor::Wild, true, 4),
        1 => effect_gen::expression(Flavor::Wild, false, 3),
        1 => deep,
    ];
    let mut runner = runner();
    let accepted = AtomicU64::new(0);
    runner
        .run(&strategy, |expr| {
            let source = custom_effect(&expr);
            if !check(&source)? {
                return Ok(());
            }
            accepted.fetch_add(1, Ordering::Relaxed);
            let c = compile_str(&source, &CompileOptions::default()).unwrap();
            use plume::compiler::forces::{ForceTerm, ParticleCtx};
            for term in c.ir.custom_terms() {
                for (x, v, t) in [
                    (DVec3::new(0.3, -1.0, 2.0), DVec3::new(1.0, 0.0, -0.5), 0.5),
                    (DVec3::ZERO, DVec3::ZERO, 0.0),
                    (DVec3::splat(1e30), DVec3::splat(-1e30), 1e9),
                    (DVec3::splat(-1e-30), DVec3::splat(1e-30), 256.0),
                ] {
                    let ctx = ParticleCtx {
                        id: 7,
                        age0: 0.25,
                        t0: t,
                        life: 1.5,
                        ..ParticleCtx::default()
                    };
                    let a = term.accel_at(x, v, t, &ctx);
                    prop_assert!(a.is_finite(), "{expr} at x = {x}: {a}");
                }
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    println!(
        "fuzz expressions: {} accepted",
        accepted.load(Ordering::Relaxed)
    );
}

#[test]
fn random_attribute_expressions_are_rejected_cleanly_or_total() {
    // Random trees as an f32 attribute's spawn value and update and a vec3 attribute's spawn
    // value and rate, both read by a custom force: no panic, naga-valid WGSL, and values after
    // a step that are finite from ordinary and from extreme states.
    let scalar = || effect_gen::expression(Flavor::Wild, false, 3);
    let vector = || effect_gen::expression(Flavor::Wild, true, 3);
    let strategy = (scalar(), scalar(), vector(), vector());
    let mut runner = runner();
    let accepted = AtomicU64::new(0);
    runner
        .run(&strategy, |(spawn_a, update_a, spawn_b, rate_b)| {
            let source = format!(
                "Effect(name: \"fuzz\", capacity: 16, params: {{\"k\": 0.5}},\n    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)), lifetime: Some((1.0, 2.0)))],\n    attributes: {{\"a\": (spawn: \"{spawn_a}\", update: Some(\"{update_a} + a\")), \"b\": (spawn: \"{spawn_b}\", rate: Some(\"{rate_b} - b\"))}},\n    forces: [Custom(accel: \"b * a\")],\n)"
            );
            if !check(&source)? {
                return Ok(());
            }
            accepted.fetch_add(1, Ordering::Relaxed);
            let c = compile_str(&source, &CompileOptions::default()).unwrap();
            let (ir, kept) = (&c.ir, c.ir.kept_attributes());
            for (x, v, t, start) in [
                (DVec3::new(0.3, -1.0, 2.0), DVec3::new(1.0, 0.0, -0.5), 0.5, 1.0),
                (DVec3::ZERO, DVec3::ZERO, 0.0, 0.0),
                (DVec3::splat(1e30), DVec3::splat(-1e30), 1e9, 1e30),
                (DVec3::splat(-1e-30), DVec3::splat(1e-30), 256.0, -1e-30),
            ] {
                let spawned = ir.attributes.spawn_values(kept, x, v, t, 7);
                let mut inputs = plume::compiler::expr::eval::Inputs {
                    x,
                    v,
                    t,
                    age: 0.25,
                    life: 1.5,
                    id: 7,
                    attrs: spawned,
                    ..Default::default()
                };
                inputs.attrs[0] = DVec3::splat(start);
                let after = ir.attributes.step_values(kept, &inputs);
                prop_assert!(
                    spawned.iter().chain(&after).all(|a| a.is_finite()),
                    "{source}: {spawned:?} then {after:?}"
                );
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    let n = accepted.load(Ordering::Relaxed);
    println!("fuzz attribute expressions: {n} accepted");
    assert!(
        n > 0,
        "no random attribute was accepted: the test tests nothing"
    );
}
