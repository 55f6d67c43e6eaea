//! Convergence and stability on the GPU (llvmpipe in CI).
//!
//! Orders: on three reference problems the observed order p = log2(e(h) / e(h/2)) of each
//! integrator is within ±0.2 of theory, at step pairs chosen so that the errors sit well above
//! the f32 floor (about N · 2^-24 · |x|, reached by RK4 near h = 0.05 here). Errors are the max
//! over 16 particles of the final position error against the closed form (projectile with drag)
//! or an f64 RK4 at 1/64 of the step (attractor orbit, vortex).
//!
//! Position Verlet is second order only while no force reads the velocity: the step contract
//! gives forces the backward difference (x' - x) / h, an O(h) error, so with drag it is first
//! order. Both are tested.

mod common;

use common::*;
use plume::compiler::passes::stability::drag_limit;
use plume::runtime::accuracy::{measure, AccuracyPlan, Engine};
use plume::{parse, Integrator};

const PROJECTILE: &str = r#"Effect(name: "projectile", capacity: 16,
    emitters: [Emitter(burst: 16, shape: Point((0.0, 1.0, 0.0)), velocity: Radial(speed: (5.0, 10.0)))],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 1.5, fluid: (1.0, 0.0, 0.0))],
)"#;

const ORBIT: &str = r#"Effect(name: "attractor", capacity: 16,
    emitters: [Emitter(burst: 16, shape: Sphere(center: (2.0, 0.0, 0.0), radius: 0.3), velocity: Constant((0.0, 0.5, 2.5)))],
    forces: [Attractor(center: (0.0, 0.0, 0.0), range: 6.0, strength: 6.0)],
)"#;

const VORTEX: &str = r#"Effect(name: "vortex", capacity: 16,
    emitters: [Emitter(burst: 16, shape: Sphere(center: (1.0, 2.0, 0.0), radius: 0.2), velocity: Constant((0.0, 0.0, 1.0)))],
    forces: [Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 3.0, height: 8.0, spin: 4.0, pull: 1.0, down: 0.5, curve: 0.5),
             Drag(k: 0.3)],
)"#;

/// Max errors at h and h/2, and the observed order.
fn order(src: &str, integrator: Integrator, h: f64, duration: f64) -> (f64, f64, f64) {
    let effect = parse(src).unwrap();
    let plan = AccuracyPlan {
        integrators: vec![integrator],
        dts: vec![h, h / 2.0],
        duration,
    };
    let gpu = gpu();
    let (rows, _) = measure(&Engine::Gpu(&gpu), &effect, &plan, |_, _| {}).unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r.compared == 16), "{rows:?}");
    (rows[0].max_error, rows[1].max_error, rows[1].order.unwrap())
}

fn assert_order(name: &str, src: &str, integrator: Integrator, h: f64, duration: f64, theory: f64) {
    let (e1, e2, p) = order(src, integrator, h, duration);
    assert!(
        (p - theory).abs() <= 0.2,
        "{name}, {integrator:?}: observed order {p:.3} (errors {e1:.3e} at h = {h}, {e2:.3e} at h/2), theory {theory}"
    );
    // At least 4x above the f32 floor (N 2^-24 |x| <= 160 · 6e-8 · 2 m = 2e-5 m at the finest
    // step used), or the order means nothing.
    assert!(
        e2 > 8e-5,
        "{name}, {integrator:?}: error {e2:e} too close to the f32 floor"
    );
}

#[test]
fn projectile_with_drag_orders() {
    assert_order("projectile", PROJECTILE, Integrator::Euler, 0.05, 2.0, 1.0);
    assert_order(
        "projectile",
        PROJECTILE,
        Integrator::SemiImplicitEuler,
        0.05,
        2.0,
        1.0,
    );
    assert_order(
        "projectile",
        PROJECTILE,
        Integrator::Midpoint,
        0.05,
        2.0,
        2.0,
    );
    // Drag reads the velocity: Verlet's backward-difference velocity makes it first order.
    assert_order(
        "projectile",
        PROJECTILE,
        Integrator::Verlet,
        0.025,
        2.0,
        1.0,
    );
    let (e1, e2, p) = order(PROJECTILE, Integrator::Rk4, 0.2, 2.0);
    assert!(
        (p - 4.0).abs() <= 0.2 && e2 > 1e-6,
        "Rk4: order {p:.3} ({e1:e}, {e2:e})"
    );
}

#[test]
fn exact_sits_at_the_f32_floor_at_any_step() {
    let effect = parse(PROJECTILE).unwrap();
    let plan = AccuracyPlan {
        integrators: vec![Integrator::Exact],
        dts: vec![0.2, 0.05, 0.0125],
        duration: 2.0,
    };
    let gpu = gpu();
    let (rows, _) = measure(&Engine::Gpu(&gpu), &effect, &plan, |_, _| {}).unwrap();
    for r in &rows {
        // |x| stays under 12 m: the floor 4 N u (1 + |x|) is at most 4 · 160 · 6e-8 · 13 = 5e-4.
        let floor = 4.0 * r.steps as f64 * U32 * 13.0;
        assert!(
            r.max_error <= floor,
            "Exact at dt {}: error {:e} above the f32 floor {floor:e}",
            r.dt,
            r.max_error
        );
    }
}

#[test]
fn attractor_orbit_orders() {
    assert_order("orbit", ORBIT, Integrator::Euler, 0.05, 2.0, 1.0);
    assert_order(
        "orbit",
        ORBIT,
        Integrator::SemiImplicitEuler,
        0.025,
        2.0,
        1.0,
    );
    assert_order("orbit", ORBIT, Integrator::Verlet, 0.05, 2.0, 2.0);
    assert_order("orbit", ORBIT, Integrator::Midpoint, 0.025, 2.0, 2.0);
    let (e1, e2, p) = order(ORBIT, Integrator::Rk4, 0.125, 4.0);
    assert!(
        (p - 4.0).abs() <= 0.2 && e2 > 1e-6,
        "Rk4: order {p:.3} ({e1:e}, {e2:e})"
    );
}

#[test]
fn vortex_orders() {
    assert_order("vortex", VORTEX, Integrator::Euler, 0.025, 2.0, 1.0);
    assert_order(
        "vortex",
        VORTEX,
        Integrator::SemiImplicitEuler,
        0.025,
        2.0,
        1.0,
    );
    assert_order("vortex", VORTEX, Integrator::Midpoint, 0.05, 2.0, 2.0);
    let (e1, e2, p) = order(VORTEX, Integrator::Rk4, 0.1, 2.0);
    assert!(
        (p - 4.0).abs() <= 0.2 && e2 > 1e-6,
        "Rk4: order {p:.3} ({e1:e}, {e2:e})"
    );
}

/// A particle launched at 10 m/s into still air with drag k, integrated at dt.
fn drag_effect(integrator: Integrator, k: f64, dt: f64) -> String {
    format!(
        r#"Effect(name: "drag", capacity: 1, dt: {dt:?}, integrator: {},
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((10.0, 0.0, 0.0)))],
    forces: [Drag(k: {k:?})],
)"#,
        integrator.name()
    )
}

/// Speed after `steps` of the drag particle, and the number of compiler warnings.
fn speed_after(integrator: Integrator, k: f64, dt: f64, steps: u64) -> (f64, usize) {
    let e = compile_str_warn(&drag_effect(integrator, k, dt));
    let (_, records) = run_gpu(&e.0, steps);
    (records[0].velocity.length(), e.1)
}

fn compile_str_warn(src: &str) -> (plume::CompiledEffect, usize) {
    let c = compile(src);
    let n = c.warnings.items.len();
    (c, n)
}

#[test]
fn drag_blows_up_just_past_each_limit_and_not_just_below() {
    let dt = 0.01;
    for integrator in [
        Integrator::Euler,
        Integrator::SemiImplicitEuler,
        Integrator::Verlet,
        Integrator::Midpoint,
        Integrator::Rk4,
    ] {
        let limit = drag_limit(integrator).unwrap();
        // 5% either side of k*h = limit, for 150 steps: the amplification per step is about
        // 1.05 to 1.1 past the limit (growth over 1000x) and below 1 just below it.
        let (below, warned_below) = speed_after(integrator, 0.95 * limit / dt, dt, 150);
        let (past, warned_past) = speed_after(integrator, 1.05 * limit / dt, dt, 150);
        assert!(
            below < 10.0,
            "{integrator:?}: k*h just below the limit grew to {below} m/s"
        );
        assert!(
            past > 1000.0,
            "{integrator:?}: k*h just past the limit only reached {past} m/s"
        );
        assert!(
            warned_past >= 1,
            "{integrator:?}: no warning past the limit"
        );
        // Euler also warns (overshoot) below the limit when k*h > 1; others are silent below.
        if integrator != Integrator::Euler {
            assert_eq!(warned_below, 0, "{integrator:?}: warning below the limit");
        }
    }
    // Exact has no limit: even k*h = 10 decays.
    let (v, w) = speed_after(Integrator::Exact, 10.0 / dt, dt, 150);
    assert!(v < 10.0 && w == 0);
}

/// The drag particle's x velocity after each of `steps` steps.
fn velocity_history(integrator: Integrator, k: f64, dt: f64, steps: u64) -> Vec<f64> {
    let src = drag_effect(integrator, k, dt);
    let e = compile(&src);
    let gpu = gpu();
    let mut sim = plume::runtime::GpuSim::new(&gpu, e).unwrap();
    (0..steps)
        .map(|_| {
            sim.run(1, |_| {}).unwrap();
            sim.records().unwrap()[0].velocity.x
        })
        .collect()
}

#[test]
fn euler_overshoots_just_past_kh_1_and_not_just_below() {
    // Explicit Euler multiplies the relative velocity by (1 - k h): past k h = 1 it changes sign
    // every step (the compiler's overshoot warning); below it decays without changing sign.
    let dt = 0.01;
    let past = velocity_history(Integrator::Euler, 1.05 / dt, dt, 10);
    let below = velocity_history(Integrator::Euler, 0.95 / dt, dt, 10);
    assert!(
        past.windows(2).all(|w| w[0] * w[1] < 0.0),
        "no overshoot past k h = 1: {past:?}"
    );
    assert!(
        below.iter().all(|v| *v > 0.0),
        "overshoot below k h = 1: {below:?}"
    );
    let warned = |k: f64| {
        compile(&format!(
            "Effect(name: \"d\", capacity: 1, dt: {dt:?}, integrator: Euler, forces: [Drag(k: {k:?})], emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))])"
        ))
        .warnings
        .items
        .iter()
        .any(|w| w.message.contains("overshoots"))
    };
    assert!(warned(1.05 / dt) && !warned(0.95 / dt));
}

#[test]
fn a_particle_crosses_a_kill_volume_thinner_than_its_step_and_not_a_thicker_one() {
    // A slab 0.1 m thick at x in [1.0, 1.1]; a particle at 12 m/s from x = 0.95 (0.99 below).
    let run = |dt: f64| {
        let src = format!(
            r#"Effect(name: "slab", capacity: 1, dt: {dt:?}, max_speed: Some(12.0),
    emitters: [Emitter(burst: 1, shape: Point((0.95, 0.0, 0.0)), velocity: Constant((12.0, 0.0, 0.0)))],
    kill: [InsideBox(min: (1.0, -1.0, -1.0), max: (1.1, 1.0, 1.0))],
)"#
        );
        let e = compile(&src);
        let warned = e
            .warnings
            .items
            .iter()
            .any(|w| w.message.contains("pass through"));
        let (t, _) = run_gpu(&e, 10);
        (warned, t.alive)
    };
    // 12 m/s x 0.01 s = 0.12 m per step, more than the 0.1 m slab: warned. At dt = 0.005 the
    // step is 0.06 m: no warning, and some step end must fall inside the slab.
    let (warned_coarse, _) = run(0.01);
    let (warned_fine, alive_fine) = run(0.005);
    assert!(
        warned_coarse,
        "no warning at 0.12 m per step through a 0.1 m slab"
    );
    assert!(!warned_fine, "warning at 0.06 m per step");
    assert_eq!(
        alive_fine, 0,
        "a 0.06 m step must land inside the 0.1 m slab"
    );
    // Jumping over it: from x = 0.99 at 12 m/s with dt = 0.01, the first step lands at 1.11.
    let src = r#"Effect(name: "jump", capacity: 1, dt: 0.01, max_speed: Some(12.0),
    emitters: [Emitter(burst: 1, shape: Point((0.99, 0.0, 0.0)), velocity: Constant((12.0, 0.0, 0.0)))],
    kill: [InsideBox(min: (1.0, -1.0, -1.0), max: (1.1, 1.0, 1.0))],
)"#;
    let (t, _) = run_gpu(&compile(src), 10);
    assert_eq!(
        t.alive, 1,
        "the particle should pass through the slab between checks"
    );
}

#[test]
fn capacity_warnings_predict_drops() {
    // rate x lifetime = 600 x 1 s against capacity 500 (warned) and 700 (not).
    let src = |cap: u32| {
        format!(
            r#"Effect(name: "cap", capacity: {cap},
    emitters: [Emitter(rate: 600.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)), lifetime: Some((1.0, 1.0)))],
)"#
        )
    };
    for (cap, expect_drops) in [(500u32, true), (700, false)] {
        let e = compile(&src(cap));
        let warned = e.warnings.items.iter().any(|w| w.path == "capacity");
        let (t, _) = run_gpu(&e, 120);
        assert_eq!(warned, expect_drops, "capacity {cap}: warning");
        assert_eq!(t.dropped > 0, expect_drops, "capacity {cap}: {t:?}");
    }
}
