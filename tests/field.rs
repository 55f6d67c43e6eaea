//! Baked force fields: the GPU samples the same grid the reference bakes, sampling converges at
//! the filter's order, the grid changes nothing outside its bounds, and bad fields are errors.

mod common;

use common::*;
use glam::DVec3;
use plume::compiler::passes::layout::Role;

/// Noisy wind (smooth in space) plus an attractor, baked on a grid over [-2, 2]³.
fn effect(resolution: u32, filter: &str, refresh: &str) -> String {
    format!(
        r#"Effect(name: "field", capacity: 400, seed: 4,
    emitters: [Emitter(burst: 300, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.5), velocity: Radial(speed: (0.2, 1.0)))],
    forces: [Wind(direction: (1.0, 0.0, 0.0), strength: 0.3, noise: 2.0, noise_scale: 1.5),
             Attractor(center: (0.3, 0.2, 0.0), range: 3.0, strength: 2.0), Drag(k: 0.5)],
    integrator: SemiImplicitEuler,
    field: Baked(resolution: ({resolution}, {resolution}, {resolution}), min: (-2.0, -2.0, -2.0), max: (2.0, 2.0, 2.0), filter: {filter}, refresh: {refresh}),
)"#
    )
}

#[test]
fn the_gpu_samples_the_grid_the_reference_bakes() {
    for (filter, refresh) in [("Trilinear", "EveryStep"), ("Nearest", "EveryStep")] {
        let e = compile(&effect(24, filter, refresh));
        assert!(e.ir.field.is_some());
        let steps = 60;
        let worst = worst_gpu_distance(&e, steps);
        // f32 against f64 on the same nodes and weights: the usual 4 N 2^-24 per step bound,
        // except that Nearest jumps between nodes where f32 and f64 round u differently
        // (a node spacing of 0.17 m times a force difference of up to ~1 m/s² for one step).
        let tol = if filter == "Nearest" {
            1e-3
        } else {
            4.0 * steps as f64 * U32
        };
        assert!(
            worst <= tol,
            "{filter}: {worst:.3e} (1 + |x|) from the reference"
        );
    }
}

/// The RMS difference between the sampled and the evaluated acceleration of a smooth field (the
/// noisy wind alone) over 20,000 pseudo-random points inside the grid (f64: the reference's
/// bake and sample).
fn sampling_error(resolution: u32, filter: &str) -> f64 {
    let src = effect(resolution, filter, "EveryStep").replace(
        "Attractor(center: (0.3, 0.2, 0.0), range: 3.0, strength: 2.0), ",
        "",
    );
    let e = compile(&src);
    let field = e.ir.field.as_ref().unwrap();
    let t = 0.7;
    let nodes = field.bake(&e.ir.terms, t);
    let mut sum = 0.0;
    let n = 20_000u32;
    for i in 0..n {
        // A low-discrepancy (R3) sequence: evenly spread and the same every run.
        let f = f64::from(i) + 0.5;
        let u = DVec3::new(
            (f * 0.819_172_513_396_164_4).fract(),
            (f * 0.671_043_606_703_789_2).fract(),
            (f * 0.549_700_477_901_970_5).fract(),
        );
        let x = DVec3::splat(-1.95) + u * 3.9;
        let sampled = field.sample(&nodes, x).expect("inside the grid");
        let exact = plume::compiler::field::baked_sum(&e.ir.terms, x, t);
        sum += (sampled - exact).length_squared();
    }
    (sum / f64::from(n)).sqrt()
}

#[test]
fn sampling_converges_at_the_filters_order() {
    // Trilinear interpolation is second order in the node spacing, nearest first order: each
    // doubling of the resolution divides the error by about 4 and 2.
    for (filter, theory) in [("Trilinear", 2.0), ("Nearest", 1.0)] {
        let errors: Vec<f64> = [17u32, 33, 65]
            .iter()
            .map(|&n| sampling_error(n, filter))
            .collect();
        println!("{filter}: RMS sampling errors at 17, 33, 65 nodes: {errors:?}");
        for pair in errors.windows(2) {
            let order = (pair[0] / pair[1]).log2();
            assert!(
                (order - theory).abs() < 0.35,
                "{filter}: observed order {order:.2} (errors {errors:?}), theory {theory}"
            );
        }
    }
}

#[test]
fn outside_its_bounds_a_field_changes_nothing() {
    // Particles spawned 10 m from a grid over [-2, 2]³, never reaching it: the baked run is the
    // evaluated run, bit for bit on the CPU reference.
    let far = |field: &str| {
        format!(
            r#"Effect(name: "far", capacity: 50, seed: 2,
    emitters: [Emitter(burst: 50, shape: Sphere(center: (10.0, 0.0, 0.0), radius: 0.5), velocity: Radial(speed: (0.1, 0.3)))],
    forces: [Attractor(center: (10.0, 0.0, 0.0), range: 4.0, strength: 1.0), Drag(k: 0.2)],
    integrator: Rk4,
    {field}
)"#
        )
    };
    let baked = compile(&far(
        "field: Baked(resolution: (8, 8, 8), min: (-2.0, -2.0, -2.0), max: (2.0, 2.0, 2.0)),",
    ));
    let evaluated = compile(&far(""));
    let (_, a) = run_cpu(&baked, 100);
    let (_, b) = run_cpu(&evaluated, 100);
    assert_eq!(a, b);
    // And on the GPU, within f32 rounding of each other.
    let (_, a) = run_gpu(&baked, 100);
    let (_, b) = run_gpu(&evaluated, 100);
    for (p, q) in a.iter().zip(&b) {
        assert!((p.position - q.position).length() <= 1e-5 * (1.0 + q.position.length()));
    }
}

#[test]
fn a_field_with_nothing_to_bake_is_dropped_with_a_warning() {
    let e = compile(
        r#"Effect(name: "plain", capacity: 10,
    emitters: [Emitter(burst: 10, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    field: Baked(resolution: (8, 8, 8), min: (-1.0, -1.0, -1.0), max: (1.0, 1.0, 1.0)),
)"#,
    );
    assert!(e.ir.field.is_none());
    assert!(e
        .warnings
        .items
        .iter()
        .any(|w| w.path == "field" && w.message.contains("nothing to bake")));
    assert!(!e.layout.binds(Role::Field));
}
