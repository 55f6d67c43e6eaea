//! Smoke test of the benchmark at a tiny size on whatever adapter CI has (llvmpipe): it runs
//! and reports consistent fields. Timing is measured, never asserted.

mod common;

use common::*;
use plume::parse;
use plume::runtime::bench::{bench, bench_effect};

#[test]
fn bench_runs_at_a_tiny_size_and_reports_its_fields() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/fountain.ron"))
        .unwrap();
    let effect = parse(&src).unwrap();
    let gpu = gpu();
    let r = bench(&gpu, &effect, 2000, 5, Some((64, 36))).unwrap();
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
    let (w, h, frame) = r.render.expect("render timed");
    assert!((w, h) == (64, 36) && frame > 0.0);
}

#[test]
fn the_bench_copy_fills_the_capacity_and_keeps_the_layout() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/tornado.ron"))
        .unwrap();
    let e = bench_effect(&parse(&src).unwrap(), 12345);
    assert_eq!(e.capacity, 12345);
    assert_eq!(e.emitters.iter().map(|em| em.burst).sum::<u32>(), 12345);
    assert!(e
        .emitters
        .iter()
        .all(|em| em.rate == 0.0 && em.lifetime.is_some()));
}
