//! Turbulence on the GPU: the curl-noise field matches the f64 reference (steady, several
//! octaves, evolving, baked), and the kernels carry only the turbulence code an effect uses.

mod common;

use common::*;

fn effect(turbulence: &str, extra: &str) -> String {
    format!(
        r#"Effect(
    name: "turbulence",
    capacity: 3000,
    seed: 4,
    dt: 0.016666667,
    emitters: [Emitter(burst: 1000, rate: 600.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.0, 1.0)), lifetime: Some((2.0, 4.0)))],
    forces: [Drag(k: 0.5), {turbulence}],
    integrator: SemiImplicitEuler,
    {extra}
)"#
    )
}

#[test]
fn the_gpu_follows_the_reference() {
    // The field is smooth (C²) and hashed with integers, so the GPU's f32 evaluation differs
    // from f64 only by rounding: 4 roundings a step, as in the examples. The flow then
    // stretches those differences: with |∂a/∂x| <= ω² (the stiffness the stability pass uses,
    // ω² = strength · octaves · 20 / scale), a difference grows at most like cosh(ω t). Over
    // 30 steps (0.5 s) that is a factor of 12 at ω = 6.3 rad/s (strength 3, scale 1.5).
    for t in [
        "Turbulence(strength: 3.0, scale: 1.5)",
        "Turbulence(strength: 3.0, scale: 1.5, octaves: 4)",
        "Turbulence(strength: 3.0, scale: 1.5, octaves: 2, evolution: 1.5)",
    ] {
        let e = compile(&effect(t, ""));
        let omega =
            e.ir.terms
                .iter()
                .find_map(|term| match term.as_dyn().stiffness() {
                    plume::compiler::forces::Stiffness::Oscillation(w) => Some(w),
                    _ => None,
                })
                .expect("turbulence has a stiffness");
        let worst = worst_gpu_distance(&e, 30);
        let bound = 4.0 * 30.0 * U32 * (omega * 30.0 * e.ir.dt).cosh();
        assert!(worst <= bound, "{t}: {worst:e} > {bound:e}");
        // It moves things: the turbulent run differs from drag alone.
        let calm = compile(&effect("Drag(k: 0.0)", ""));
        let (a, b) = (run_cpu(&e, 60).1, run_cpu(&calm, 60).1);
        let moved = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p.position - q.position).length())
            .fold(0.0, f64::max);
        assert!(
            moved > 0.1,
            "{t}: turbulence moved particles by at most {moved}"
        );
    }
}

#[test]
fn baked_turbulence_follows_the_baked_reference() {
    let e = compile(&effect(
        "Turbulence(strength: 3.0, scale: 1.5, octaves: 2, evolution: 0.5)",
        "field: Baked(resolution: (24, 24, 24), min: (-4.0, -3.0, -4.0), max: (4.0, 5.0, 4.0), refresh: EveryStep),",
    ));
    assert!(e.ir.field.is_some());
    assert!(!e.wgsl.contains("turbulence(") || e.wgsl.contains("fn bake"));
    // Trilinear samples of a grid are only Lipschitz, and their slopes are the node
    // differences: the same growth bound as evaluated turbulence, over 30 steps.
    let worst = worst_gpu_distance(&e, 30);
    let omega = (3.0_f64 * 2.0 * 20.0 / 1.5).sqrt();
    let bound = 4.0 * 30.0 * U32 * (omega * 30.0 * e.ir.dt).cosh();
    assert!(worst <= bound, "baked: {worst:e} > {bound:e}");
}

#[test]
fn only_the_turbulence_an_effect_uses_is_emitted() {
    let none = compile(&effect("Drag(k: 0.1)", ""));
    assert!(!none.wgsl.contains("turb_curl"));
    let steady = compile(&effect("Turbulence(strength: 1.0, scale: 2.0)", ""));
    assert!(steady.wgsl.contains("turb_octaves("));
    assert!(!steady.wgsl.contains("a += 1.0 * turbulence("));
    assert!(
        steady.ir.wraps_kernel_time(),
        "steady turbulence keeps the wrapped time"
    );
    let evolving = compile(&effect(
        "Turbulence(strength: 1.0, scale: 2.0, evolution: 0.5)",
        "",
    ));
    assert!(evolving.wgsl.contains("turbulence("));
    assert!(
        !evolving.ir.wraps_kernel_time(),
        "evolution needs the whole time"
    );
    // Zero strength is pruned.
    let zero = compile(&effect("Turbulence(strength: 0.0, scale: 2.0)", ""));
    assert!(!zero.wgsl.contains("turb_curl"));
}

#[test]
fn bad_turbulence_parameters_are_located() {
    for (bad, needle) in [
        (
            "Turbulence(strength: 1.0, scale: 0.0)",
            "scale: must be > 0",
        ),
        (
            "Turbulence(strength: 1.0, scale: 1.0, octaves: 9)",
            "octaves: must be in [1, 8]",
        ),
        (
            "Turbulence(strength: 1.0, scale: 1.0, evolution: -1.0)",
            "evolution",
        ),
    ] {
        let src = effect(bad, "");
        let err = plume::compile_str(&src, &plume::CompileOptions::default())
            .err()
            .unwrap_or_else(|| panic!("{bad} compiled"));
        let text = err.render("t.ron", &src);
        assert!(text.contains(needle), "{bad}: {text}");
        assert!(
            text.contains("t.ron:8:"),
            "{bad}: not located on the forces line: {text}"
        );
    }
}
