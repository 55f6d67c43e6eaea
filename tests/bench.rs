//! Smoke test of the benchmark at a tiny size on whatever adapter CI has (llvmpipe): it runs
//! and reports consistent fields. Timing is measured, never asserted.

mod common;

use common::*;
use plume::parse;
use plume::runtime::bench::{bench, bench_effect, BenchOptions};

#[test]
fn bench_runs_at_a_tiny_size_and_reports_its_fields() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/fountain.ron"))
        .unwrap();
    let effect = parse(&src).unwrap();
    let gpu = gpu();
    let options = BenchOptions {
        render: Some((64, 36)),
        ..BenchOptions::new(2000, 5)
    };
    let r = bench(&gpu, &effect, &options).unwrap();
    assert_eq!(r.particles, 2000, "all spawned at step 0 and alive");
    assert_eq!(r.steps, 5);
    assert_eq!(r.bytes_per_particle, 32, "position, velocity, die_at, id");
    assert_eq!(r.chunks, 1);
    for x in [
        r.seconds_per_step,
        r.copy_seconds,
        r.update_gbps(),
        r.copy_gbps(),
        r.ratio(),
    ] {
        assert!(x.is_finite() && x > 0.0, "{r:?}");
    }
    assert!((r.bytes_per_step() - 2.0 * 2000.0 * 32.0).abs() < 1e-9);
    let d = r.render.expect("draw timed");
    assert_eq!((d.width, d.height), (64, 36));
    for x in [d.draw, d.opaque, d.vertex_only] {
        assert!(x.is_finite() && x > 0.0, "{d:?}");
    }
    // The fountain sorts (so a frame prepares keys and a sort) and cannot be stateless.
    assert!(d.prepare.is_some_and(|p| p > 0.0), "{d:?}");
    assert_eq!(d.stateless, None);
    // Round camera-facing sprites: the compute renderer draws them too.
    assert!(
        d.compute.is_some_and(|(s, entries)| s > 0.0 && entries > 0),
        "{d:?}"
    );
}

#[test]
fn bench_draws_a_stateless_effect_from_its_closed_form() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/sparks.ron"))
        .unwrap();
    let gpu = gpu();
    let options = BenchOptions {
        render: Some((32, 18)),
        ..BenchOptions::new(1000, 3)
    };
    let r = bench(&gpu, &parse(&src).unwrap(), &options).unwrap();
    let d = r.render.expect("draw timed");
    assert!(d.stateless.is_some_and(|s| s > 0.0), "{d:?}");
    assert_eq!(d.prepare, None, "sparks does not sort");
    // Sparks glow: the compute renderer draws them into an HDR image and times the bloom too.
    assert!(
        d.compute.is_some_and(|(s, entries)| s > 0.0 && entries > 0),
        "{d:?}"
    );
    assert!(
        d.compute_stages
            .iter()
            .any(|(stage, s)| *stage == "glow" && *s > 0.0),
        "{d:?}"
    );
}

#[test]
fn bench_compares_hidden_and_compacted_dead_slots_at_low_occupancy() {
    let src =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/snow.ron")).unwrap();
    let gpu = gpu();
    let options = BenchOptions {
        render: Some((32, 18)),
        occupancy: 0.1,
        ..BenchOptions::new(4000, 2)
    };
    let mut snow = parse(&src).unwrap();
    // Its snowflake texture is named relative to the effect file.
    snow.base_dir = Some(concat!(env!("CARGO_MANIFEST_DIR"), "/effects").into());
    let r = bench(&gpu, &snow, &options).unwrap();
    assert_eq!(r.particles, 400, "a tenth of the slots alive");
    let d = r.render.expect("draw timed");
    let (compact, draw) = d.compacted.expect("snow is stateful and unsorted");
    assert!(compact > 0.0 && draw > 0.0, "{d:?}");
}

#[test]
fn the_bench_copy_fills_the_capacity_and_keeps_the_layout() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/tornado.ron"))
        .unwrap();
    let e = bench_effect(&parse(&src).unwrap(), 12345);
    assert_eq!(e.capacity, 12345);
    let bursts = e.emitters.iter().map(|em| em.burst.value(&e.params));
    assert_eq!(bursts.sum::<u32>(), 12345);
    assert!(e
        .emitters
        .iter()
        .all(|em| em.rate.value(&e.params) == 0.0 && em.lifetime.is_some()));
}

/// `--profile`: each dispatch of a step timed, labelled by kernel and scope. Times are
/// measured, never asserted; what is checked is which dispatches a step records, and how often.
#[test]
fn the_profile_names_every_dispatch_of_a_step_once() {
    let gpu = gpu();
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/fountain.ron"))
        .unwrap();
    let options = BenchOptions {
        profile: true,
        ..BenchOptions::new(2000, 4)
    };
    let r = bench(&gpu, &parse(&src).unwrap(), &options).unwrap();
    let update = r.dispatches.iter().find(|d| d.label == "update");
    assert!(
        update.is_some_and(|d| (d.per_step - 1.0).abs() < 1e-9 && d.us_per_step >= 0.0),
        "{:?}",
        r.dispatches
    );
    assert!(!BenchOptions::new(2000, 4).profile, "off unless asked for");
    // A grid flock's stages each have their own line.
    let src =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/boids.ron")).unwrap();
    let mut boids = parse(&src).unwrap();
    boids.render.texture = None;
    let r = bench(&gpu, &boids, &options).unwrap();
    let labels: Vec<&str> = r.dispatches.iter().map(|d| d.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "flock_bucket",
            "flock_scan",
            "flock_scatter",
            "flock_rank",
            "flock_search",
            "update"
        ],
        "{:?}",
        r.dispatches
    );

    let src =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/rain.ron")).unwrap();
    let graph =
        plume::runtime::bench::bench_graph(&gpu, &parse(&src).unwrap(), 40_000, 30, 4, true)
            .unwrap();
    let (with, without) = &graph.dispatches;
    let labels: Vec<&str> = with.iter().map(|d| d.label.as_str()).collect();
    // Rain's drops (group 0) are bucketed (past 8,192 slots) and feed the splashes (group 1).
    assert!(
        !labels.contains(&"s0.event_prepare"),
        "the ordering prepares the spawn: {labels:?}"
    );
    for expected in [
        "s0.bucket_count",
        "s0.bucket_place",
        "s0.bucket_rank",
        "s0.event_spawn",
        "g0.update",
        "g1.update",
    ] {
        assert!(
            labels.contains(&expected),
            "{expected} missing from {labels:?}"
        );
    }
    assert!(
        with.iter().all(|d| (d.per_step - 1.0).abs() < 1e-9),
        "{with:?}"
    );
    assert!(
        without.iter().all(|d| !d.label.starts_with('s')),
        "the step without events orders nothing: {without:?}"
    );
    assert!(
        without.iter().any(|d| d.label == "g1.update"),
        "{without:?}"
    );
}
