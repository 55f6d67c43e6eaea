//! Flocking on the GPU (llvmpipe in CI): the grid finds exactly the neighbours all-pairs finds,
//! the GPU follows the f64 reference, a flock holds together without collapsing, and the
//! stability analysis's cohesion and alignment limits are real.

mod common;

use common::*;
use plume::compiler::passes::stability::{drag_limit, oscillation_limit};
use plume::runtime::oracle;
use plume::runtime::Effect;
use plume::Integrator;

/// A cloud of boids with some slots left free (burst < capacity), so that dead slots are
/// skipped, and capacities that are not multiples of the 256-boid tile.
fn cloud(capacity: u32, burst: u32, scope: &str, neighbors: &str) -> String {
    cloud_in(capacity, burst, scope, neighbors, 1.0)
}

/// [`cloud`] in a box `scale` times as large.
fn cloud_in(capacity: u32, burst: u32, scope: &str, neighbors: &str, scale: f64) -> String {
    let (a, b, c, d) = (2.0 * scale, scale, 1.5 * scale, 2.5 * scale);
    format!(
        r#"Effect(name: "cloud", capacity: {capacity}, seed: 9,
    emitters: [Emitter(burst: {burst}, shape: Box(min: (-{a:?}, -{b:?}, -{c:?}), max: ({d:?}, {b:?}, {c:?})), velocity: Radial(speed: (0.2, 1.0)))],
    forces: [Flock(radius: 0.5, separation: 3.0, avoidance: 1.0, cohesion: 0.5, alignment: 0.8, scope: {scope}, neighbors: {neighbors})],
    integrator: SemiImplicitEuler,
)"#
    )
}

/// The `flock_out` words after one step: per slot (push, count), sum x, sum v.
fn flock_out(src: &str) -> Vec<[f32; 12]> {
    let e = compile(src);
    let g = gpu();
    let mut sim = Effect::new(&g, e).unwrap();
    sim.run(1, |_| {}).unwrap();
    let bytes =
        oracle::read_flock_buffer(&sim, plume::compiler::passes::layout::Role::FlockOut).unwrap();
    bytes
        .chunks_exact(48)
        .map(|c| {
            let mut w = [0f32; 12];
            for (k, v) in w.iter_mut().enumerate() {
                *v = f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]);
            }
            w
        })
        .collect()
}

#[test]
fn grid_and_all_pairs_find_the_same_neighbours_and_forces() {
    // Dense clouds (4 to 30 boids a cell here) and a sparse one (under one boid a 0.5 m cell);
    // the last capacity is past GRID_SPLIT_BELOW: one search thread a boid instead of nine (few
    // of its slots alive, so that llvmpipe runs it quickly). All must find exactly what all
    // pairs finds.
    let one_thread = plume::compiler::forces::flock::GRID_SPLIT_BELOW;
    for (capacity, burst, scale) in [
        (1000u32, 937u32, 1.0),
        (3001, 3001, 1.0),
        (1500, 1300, 2.0),
        (one_thread, 900, 1.0),
    ] {
        let pairs = flock_out(&cloud_in(capacity, burst, "Local", "AllPairs", scale));
        // A cell exactly the radius, and one twice as big: both must be exact.
        for cell in ["0.5", "1.0"] {
            let grid = flock_out(&cloud_in(
                capacity,
                burst,
                "Local",
                &format!("Grid(cell: {cell})"),
                scale,
            ));
            assert_eq!(pairs.len(), grid.len());
            let mut neighbours = 0.0;
            for (slot, (a, b)) in pairs.iter().zip(&grid).enumerate() {
                // Words: push (0-2), Σw (3), Σ w x (4-6), count (7), Σ w v (8-10).
                // The same f32 distance test on the same snapshot: identical neighbour sets.
                assert_eq!(a[7], b[7], "slot {slot}: {} vs {} neighbours", a[7], b[7]);
                neighbours += a[7];
                // Sums over the same terms in another order: f32 rounding of each term
                // (|term| <= 4 m/s² or 3 m here) times the count, with a factor 4 margin.
                let tol = 4.0 * f32::EPSILON * (1.0 + a[7]) * 4.0;
                for k in [0, 1, 2] {
                    assert!(
                        (a[k] - b[k]).abs() <= tol,
                        "slot {slot}: push {} vs {}",
                        a[k],
                        b[k]
                    );
                    assert!(
                        (a[4 + k] - b[4 + k]).abs() <= tol * 3.0,
                        "slot {slot}: sum x"
                    );
                    assert!(
                        (a[8 + k] - b[8 + k]).abs() <= tol * 3.0,
                        "slot {slot}: sum v"
                    );
                }
                assert!((a[3] - b[3]).abs() <= tol, "slot {slot}: total weight");
            }
            assert!(
                neighbours / f64::from(burst) as f32 > 2.0,
                "too few neighbours ({neighbours}) for the test to mean anything"
            );
        }
    }
}

#[test]
fn flocks_on_the_gpu_follow_the_reference() {
    for (scope, neighbors) in [("Global", "AllPairs"), ("Local", "Grid(cell: 0.5)")] {
        let e = compile(&cloud(600, 555, scope, neighbors));
        let steps = 60;
        let worst = worst_gpu_distance(&e, steps);
        // Neighbour sets decided on f32 positions can differ from the f64 ones for pairs
        // within rounding of the radius; the separation they add fades to 0 at the radius
        // (w = 1 - r/radius), so such a pair changes a boid's push by ~1e-6 m/s². Over 60 steps
        // the measured worst is about 1e-6 (1 + |x|); 1e-4 leaves room for chaotic growth.
        println!("{scope}/{neighbors}: worst GPU-reference distance {worst:.3e} (1 + |x|)");
        assert!(
            worst < 1e-4,
            "{scope}/{neighbors}: GPU {worst:.3e} (1 + |x|) from the reference"
        );
    }
}

#[test]
fn a_flock_stays_together_and_apart_for_1000_steps() {
    // Starting as a loose 10 x 6 x 8 m cloud, the boids must pull together (their spread
    // shrinks) but never collapse: separation keeps every pair apart.
    let e = compile(&cloud(400, 400, "Global", "Grid(cell: 0.5)").replace(
        "Box(min: (-2.0, -1.0, -1.5), max: (2.5, 1.0, 1.5))",
        "Box(min: (-5.0, -3.0, -4.0), max: (5.0, 3.0, 4.0))",
    ));
    let g = gpu();
    let mut sim = Effect::new(&g, e).unwrap();
    let spread = |r: &[plume::compiler::reference::ParticleRecord]| {
        let n = r.len() as f64;
        let c = r.iter().map(|p| p.position).sum::<glam::DVec3>() / n;
        (r.iter()
            .map(|p| (p.position - c).length_squared())
            .sum::<f64>()
            / n)
            .sqrt()
    };
    sim.run(1, |_| {}).unwrap();
    let start = spread(&sim.records().unwrap());
    sim.run(999, |_| {}).unwrap();
    let end_records = sim.records().unwrap();
    assert_eq!(end_records.len(), 400);
    let end = spread(&end_records);
    let mut closest = f64::INFINITY;
    for (i, a) in end_records.iter().enumerate() {
        assert!(a.position.is_finite() && a.velocity.is_finite());
        for b in &end_records[i + 1..] {
            closest = closest.min((a.position - b.position).length());
        }
    }
    println!("spread {start:.3} m -> {end:.3} m, closest pair {closest:.4} m");
    assert!(
        end < 0.6 * start,
        "the flock did not cohere: spread {start:.3} m -> {end:.3} m"
    );
    assert!(
        end > 0.1,
        "the flock collapsed to a point: spread {end:.3} m"
    );
    assert!(
        closest > 0.1,
        "two boids came within {closest:.4} m (separation should keep them apart)"
    );
}

/// Two boids released at rest at ±r0 on x with global cohesion only: about their (fixed) mean
/// each is a harmonic oscillator with ω² = cohesion; with alignment only and opposite
/// velocities, their velocities decay toward the mean at rate `alignment`, like drag.
fn pair(integrator: Integrator, cohesion: f64, alignment: f64, v0: f64) -> String {
    format!(
        r#"Effect(name: "pair", capacity: 2, dt: 0.01, integrator: {},
    emitters: [Emitter(burst: 2, shape: Points([(-0.01, 0.0, 0.0), (0.01, 0.0, 0.0)]), velocity: Radial(speed: ({v0:?}, {v0:?})))],
    forces: [Flock(radius: 0.001, cohesion: {cohesion:?}, alignment: {alignment:?})],
)"#,
        integrator.name()
    )
}

fn max_after(
    src: &str,
    steps: u64,
    f: impl Fn(&plume::compiler::reference::ParticleRecord) -> f64,
) -> (f64, bool) {
    let e = compile(src);
    let warned = e.warnings.items.iter().any(|w| w.path.contains("(Flock)"));
    let g = gpu();
    let mut sim = Effect::new(&g, e).unwrap();
    let mut worst: f64 = 0.0;
    for _ in 0..steps {
        sim.run(1, |_| {}).unwrap();
        for r in sim.records().unwrap() {
            worst = worst.max(f(&r));
        }
    }
    (worst, warned)
}

#[test]
fn cohesion_and_alignment_blow_up_just_past_their_limits_and_not_just_below() {
    let h: f64 = 0.01;
    for integrator in [Integrator::SemiImplicitEuler, Integrator::Rk4] {
        // Cohesion: ω = sqrt(cohesion); 0.01 m from the mean, at rest.
        let limit = oscillation_limit(integrator).unwrap();
        let spring = |wh: f64| {
            max_after(&pair(integrator, (wh / h).powi(2), 0.0, 0.0), 60, |r| {
                r.position.length()
            })
        };
        let (below, warned_below) = spring(0.95 * limit);
        let (past, warned_past) = spring(1.05 * limit);
        assert!(
            below < 0.04,
            "{integrator:?}: cohesion below the limit reached {below} m"
        );
        assert!(
            past > 0.5,
            "{integrator:?}: cohesion past the limit only reached {past} m"
        );
        assert!(
            warned_past && !warned_below,
            "{integrator:?}: cohesion warnings"
        );
        // Alignment: the two boids fly apart at ±1 m/s; the mean velocity is 0.
        let limit = drag_limit(integrator).unwrap();
        let damping = |kh: f64| {
            max_after(&pair(integrator, 0.0, kh / h, 1.0), 150, |r| {
                r.velocity.length()
            })
        };
        let (below, warned_below) = damping(0.95 * limit);
        let (past, warned_past) = damping(1.05 * limit);
        assert!(
            below <= 1.0 + 1e-6,
            "{integrator:?}: alignment below the limit grew to {below} m/s"
        );
        assert!(
            past > 100.0,
            "{integrator:?}: alignment past the limit only reached {past} m/s"
        );
        assert!(
            warned_past && !warned_below,
            "{integrator:?}: alignment warnings"
        );
    }
}

#[test]
fn flocking_runs_are_deterministic() {
    // Both searches: nine threads a boid over whole cells, and (from GRID_SPLIT_BELOW) one
    // thread a boid over cells split along x.
    let one_thread = plume::compiler::forces::flock::GRID_SPLIT_BELOW;
    for (capacity, steps) in [(700u32, 40u64), (one_thread, 20)] {
        let src = cloud(capacity, 650, "Local", "Grid(cell: 0.5)");
        let run = || {
            let (_, r) = run_gpu(&compile(&src), steps);
            plume::runtime::outputs::csv(&r)
        };
        let first = run();
        assert!(
            first.split(|&b| b == b'\n').count() > 600,
            "too few rows to compare"
        );
        assert_eq!(first, run(), "capacity {capacity}");
    }
}

#[test]
fn a_second_flock_is_refused_where_it_is_written() {
    let src = pair(Integrator::SemiImplicitEuler, 1.0, 0.0, 0.0).replace(
        "forces: [Flock(",
        "forces: [Flock(radius: 0.5), Gravity((0.0, -1.0, 0.0)), Flock(",
    );
    let err = plume::compile_str(&src, &Default::default()).unwrap_err();
    let text = err.render("pair.ron", &src);
    assert!(
        text.contains("forces[2] (Flock): a second Flock: an effect has one flock")
            && text.contains("pair.ron:3:"),
        "{text}"
    );
}
