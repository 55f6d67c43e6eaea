//! Colour, opacity and size set by expressions (`render.color_by`, `alpha_by`, `size_by`): the
//! raster draw
//! and the compute renderer against the CPU-fed reference drawing, which evaluates the same
//! expression trees in f64, for stateful and stateless effects; and the factors themselves
//! (a random hue per particle, a size that grows with age, a colour from speed) measured in
//! the drawing's inputs.

mod common;

use common::*;
use plume::compiler::by_expression::Seen;
use plume::compiler::schema::State;
use plume::runtime::Effect;
use plume::{compile_str, CompileOptions};

const SIDE: u32 = 256;

/// A spray of 300 particles with `color_by`, `alpha_by` and `size_by` (RON `Some("...")`
/// strings), run for 40 steps in `state`.
fn spray([color_by, alpha_by, size_by]: [&str; 3], state: State) -> Effect {
    let src = format!(
        r#"Effect(
    name: "by",
    capacity: 600,
    seed: 3,
    dt: 0.02,
    emitters: [Emitter(burst: 100, rate: 400.0, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
        velocity: Radial(speed: (1.0, 6.0)), lifetime: Some((0.6, 1.2)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: Exact,
    camera: Camera(eye: (0.0, 0.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 0.9)), (1.0, (0.6, 0.6, 0.6, 0.3))],
        size: [(0.0, 0.12), (1.0, 0.06)], background: (0.0, 0.0, 0.0),
        color_by: {color_by}, alpha_by: {alpha_by}, size_by: {size_by}),
)"#
    );
    let options = CompileOptions {
        state: Some(state),
        ..Default::default()
    };
    let effect =
        compile_str(&src, &options).unwrap_or_else(|e| panic!("{}", e.render("by.ron", &src)));
    let mut sim = Effect::new(&gpu(), effect).unwrap();
    sim.run(40, |_| {}).unwrap();
    sim
}

const HUE: &str = r#"Some("hsv(rand(0), 0.8, 1.0) * (1.0 + 0.5 * age / max(life, dt))")"#;
const GROWTH: &str = r#"Some("(0.5 + rand(1)) * (1.0 + age)")"#;
const FLICKER: &str = r#"Some("0.3 + 0.7 * rand(2)")"#;
/// A colour and an opacity that change with the frame's time (s), the same for every particle.
const PULSE: &str = r#"Some("vec3(0.5 + 0.5 * sin(6.0 * t), 0.5 + 0.5 * cos(4.0 * t), 1.0)")"#;
const BLINK: &str = r#"Some("0.55 + 0.45 * sin(9.0 * t)")"#;
const SPEED: &str =
    r#"Some("mix(vec3(1.0, 0.3, 0.1), vec3(0.2, 0.5, 1.0), clamp(length(v) / 6.0, 0.0, 1.0))")"#;

#[test]
fn the_draws_colour_and_size_by_expression_as_the_reference_drawing_does() {
    // The same sprites, their colour and size computed in f32 on the GPU and in f64 on the
    // CPU: a channel a step apart where rounding crosses a half, a rim pixel's coverage a few
    // steps where the sizes differ by f32 rounding (as tests/looks.rs allows).
    for (what, by, state) in [
        (
            "hue, opacity and growth, stateful",
            [HUE, FLICKER, GROWTH],
            State::Stateful,
        ),
        (
            "hue, opacity and growth, stateless",
            [HUE, FLICKER, GROWTH],
            State::Stateless,
        ),
        (
            "colour from speed, stateful",
            [SPEED, "None", "None"],
            State::Stateful,
        ),
        (
            "colour from speed, stateless",
            [SPEED, "None", "None"],
            State::Stateless,
        ),
        (
            "colour and opacity over the frame's time, stateful",
            [PULSE, BLINK, "None"],
            State::Stateful,
        ),
        (
            "colour and opacity over the frame's time, stateless",
            [PULSE, BLINK, "None"],
            State::Stateless,
        ),
    ] {
        let sim = spray(by, state);
        assert_eq!(
            sim.compiled().ir.stateless.is_some(),
            state == State::Stateless
        );
        let gpu_img = assert_draws_agree(&sim, SIDE, true, what);
        let lit = gpu_img.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        assert!(lit > 500, "{what}: {lit} pixels drawn");
    }
}

#[test]
fn the_factors_are_the_particles_own() {
    let sim = spray([HUE, FLICKER, GROWTH], State::Stateful);
    let ir = &sim.compiled().ir;
    let records = sim.records().unwrap();
    let seen = |r: &plume::compiler::reference::ParticleRecord| Seen {
        x: r.position,
        v: r.velocity,
        age: r.age,
        life: r.lifetime.unwrap_or(0.0),
        id: r.id,
        ..Seen::default()
    };
    // Hues spread over the wheel: every sixth of it is some particle's.
    let mut sixths = [0usize; 6];
    for r in &records {
        let c = ir.render.by.color_factor(&seen(r), ir.seed_mix);
        assert!(
            c.min_element() >= 0.0 && c.max_element() <= 1.5 + 1e-9,
            "{c:?}"
        );
        let hue = plume::compiler::rng::unit(plume::compiler::rng::rand_u32(ir.seed_mix, r.id, 64));
        sixths[(hue * 6.0) as usize] += 1;
        let a = ir.render.by.alpha_factor(&seen(r), ir.seed_mix);
        assert!((0.3..=1.0).contains(&a), "{a}");
        // Size: (0.5 + rand(1)) (1 + age), at least half the stops' size.
        let k = ir.render.by.size_factor(&seen(r), ir.seed_mix);
        assert!(
            k >= 0.5 * (1.0 + r.age) - 1e-9 && k <= 1.5 * (1.0 + r.age) + 1e-9,
            "{k}"
        );
    }
    assert!(sixths.iter().all(|&n| n > 10), "{sixths:?}");
}

#[test]
fn color_t_reads_the_colour_stops_at_an_expressions_t() {
    // Colour from speed through the file's own stops: slow particles red, fast ones blue,
    // whatever their age. The GPU reads the stops where the CPU-fed reference drawing does.
    let src = r#"Effect(
    name: "by-speed",
    capacity: 600,
    seed: 3,
    dt: 0.02,
    emitters: [Emitter(burst: 300, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
        velocity: Radial(speed: (0.5, 6.0)), lifetime: Some((5.0, 5.0)))],
    integrator: Exact,
    camera: Camera(eye: (0.0, 0.0, 8.0), target: (0.0, 0.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 0.0, 0.0, 1.0)), (1.0, (0.0, 0.0, 1.0, 1.0))],
        size: [(0.0, 0.1)], background: (0.0, 0.0, 0.0), blend: Additive,
        color_t: Some("clamp(length(v) / 6.0, 0.0, 1.0)")),
)"#;
    let effect = compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("t.ron", src)));
    let mut sim = Effect::new(&gpu(), effect).unwrap();
    sim.run(10, |_| {}).unwrap();
    assert_draws_agree(&sim, SIDE, true, "colour by speed");
    // The t is the speed's: the slowest particles sit near the red end, the fastest near blue.
    let ir = &sim.compiled().ir;
    let t: Vec<f64> = sim
        .records()
        .unwrap()
        .iter()
        .map(|r| {
            let seen = Seen {
                v: r.velocity,
                id: r.id,
                ..Seen::default()
            };
            ir.render.by.color_t_at(&seen, ir.seed_mix).unwrap()
        })
        .collect();
    let (lo, hi) = t
        .iter()
        .fold((1.0f64, 0.0f64), |(lo, hi), &t| (lo.min(t), hi.max(t)));
    assert!(lo < 0.15 && hi > 0.85, "t from {lo} to {hi}");
}

#[test]
fn t_is_the_time_of_the_frame_drawn() {
    // Every sprite's colour follows the frame's time: drawn after 40 and after 55 steps, the
    // same particles' mean colour moves as (0.5 + 0.5 sin 6t, 0.5 + 0.5 cos 4t) does.
    let mut sim = spray([PULSE, "None", "None"], State::Stateful);
    let mean = |sim: &Effect| {
        let (img, _) = draw_and_reference(sim, SIDE);
        let lit: Vec<&[u8]> = img.chunks(4).filter(|p| p[2] > 60).collect();
        let avg = |c: usize| lit.iter().map(|p| f64::from(p[c])).sum::<f64>() / lit.len() as f64;
        // Red and green relative to blue (1.0 in the colour: the same falloff and blending).
        (avg(0) / avg(2), avg(1) / avg(2))
    };
    let first = mean(&sim);
    sim.run(15, |_| {}).unwrap();
    let second = mean(&sim);
    let want = |t: f64| (0.5 + 0.5 * (6.0 * t).sin(), 0.5 + 0.5 * (4.0 * t).cos());
    for (got, t) in [(first, 0.8), (second, 1.1)] {
        let w = want(t);
        assert!(
            (got.0 - w.0).abs() < 0.06 && (got.1 - w.1).abs() < 0.06,
            "at t = {t}: red and green over blue {got:?}, want {w:?}"
        );
    }
}
