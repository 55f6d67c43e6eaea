//! Accuracy budgets (`accuracy: (position, over)`): the compiler chooses the cheapest scheme
//! that keeps each particle within the budget of its exact trajectory, and the GPU run keeps
//! it. For a stiff attractor whose particles fall through its core, a custom spring and
//! bouncing particles (no closed form), budgets from 1e-1 to 1e-4 m each hold on the GPU
//! (llvmpipe) against the f64 truth; a looser budget never costs more force evaluations a step;
//! a budget met by the closed form never steps (linear drag with k·dt from 0.01 to 2); and a
//! budget below f32's floor is an error that says what can be met.

mod common;

use common::*;
use plume::compiler::accuracy::Choice;
use plume::runtime::bench::check_budget;
use plume::{compile_str, CompileOptions};

/// An effect of 64 particles with `forces`, `collide` and `budget` metres over 1 s.
fn effect(forces: &str, extra: &str, budget: f64) -> String {
    format!(
        r#"Effect(
    name: "budget",
    capacity: 64,
    seed: 3,
    emitters: [Emitter(burst: 64, shape: Box(min: (1.5, -0.5, -0.5), max: (2.5, 0.5, 0.5)),
                       velocity: Constant((-1.0, 0.0, 0.3)))],
    forces: [{forces}],
    {extra}
    accuracy: (position: {budget:e}, over: 1.0),
)"#
    )
}

/// The stiff and the smooth cases with no closed form, and the budgets each is held to
/// (tightest first). Contacts converge at first order in the substep, the truth's too, so
/// bouncing particles are held to 1 cm at best (below, the next test).
const STEPPED: [(&str, &str, &str, &[f64]); 3] = [
    (
        "attractor through its core",
        "Attractor(center: (0.0, 0.0, 0.0), range: 4.0, strength: 30.0, core: 0.2)",
        "",
        &[1e-4, 1e-3, 1e-2, 1e-1],
    ),
    (
        "custom spring",
        r#"Custom(accel: "-40.0 * x - 0.5 * v")"#,
        "",
        &[1e-4, 1e-3, 1e-2, 1e-1],
    ),
    (
        "bouncing on a plane",
        "Gravity((0.0, -9.81, 0.0)), Drag(k: 0.3)",
        BOUNCE,
        &[1e-2, 1e-1],
    ),
];

const BOUNCE: &str = "collide: [Plane(point: (0.0, -1.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.6, friction: 0.1)],";

#[test]
fn each_budget_holds_on_the_gpu_and_a_looser_one_never_costs_more() {
    let gpu = gpu();
    for (what, forces, extra, budgets) in STEPPED {
        let mut last_cost = 0;
        // Tightest first: each looser budget may cost no more than the one before it.
        for &budget in budgets {
            let src = effect(forces, extra, budget);
            let compiled = compile_str(&src, &CompileOptions::default())
                .unwrap_or_else(|e| panic!("{what} {budget}: {}", e.render("budget.ron", &src)));
            let chosen = compiled.ir.accuracy.clone().unwrap();
            let Some(Choice::Stepped {
                scheme, estimated, ..
            }) = chosen.choice
            else {
                panic!("{what}: {:?}", chosen.choice)
            };
            assert!(estimated <= budget / 2.0, "{what}: {}", chosen.describe());
            assert_eq!(compiled.ir.integrator, scheme.integrator);
            assert_eq!(compiled.ir.substeps, scheme.substeps);
            if last_cost > 0 {
                assert!(
                    scheme.evaluations() <= last_cost,
                    "{what}: {budget} m costs {} evaluations, a tighter budget {last_cost}",
                    scheme.evaluations()
                );
            }
            last_cost = scheme.evaluations();
            let effect = plume::compiler::parse_with(&src, &CompileOptions::default()).unwrap();
            let check = check_budget(&gpu, &effect).unwrap().expect("a budget");
            assert!(
                check.met() && check.particles == 64,
                "{what}: {} measured {:.3e} m on the GPU against {budget:e} m",
                chosen.describe(),
                check.measured
            );
        }
    }
}

#[test]
fn a_budget_the_closed_form_meets_never_steps() {
    let gpu = gpu();
    // Linear drag from gentle to stiff for explicit schemes (k dt = 2 diverges with Euler).
    for k_dt in [0.01, 0.1, 1.0, 2.0] {
        let k = k_dt * 60.0;
        let src = effect(
            &format!("Gravity((0.0, -9.81, 0.0)), Drag(k: {k})"),
            "",
            1e-4,
        );
        let compiled = compile_str(&src, &CompileOptions::default()).unwrap();
        let chosen = compiled.ir.accuracy.clone().unwrap();
        assert_eq!(chosen.choice, Some(Choice::Exact), "k dt {k_dt}");
        assert!(
            compiled.ir.stateless.is_some(),
            "k dt {k_dt}: {}",
            compiled.ir.state_reason
        );
        let effect = plume::compiler::parse_with(&src, &CompileOptions::default()).unwrap();
        let check = check_budget(&gpu, &effect).unwrap().unwrap();
        assert!(check.met(), "k dt {k_dt}: {:.3e} m", check.measured);
    }
}

#[test]
fn a_budget_below_what_f32_holds_is_an_error_that_says_what_can_be_met() {
    let src = effect(STEPPED[0].1, "", 1e-8);
    let error = compile_str(&src, &CompileOptions::default())
        .unwrap_err()
        .render("budget.ron", &src);
    assert!(
        error.contains("budget.ron:9:26: error: accuracy.position: 1.0e-8 m is below what f32 positions hold here")
            && error.contains("the smallest budget that can be met is about"),
        "{error}"
    );
    let bad = effect(STEPPED[0].1, "", -1.0);
    let error = compile_str(&bad, &CompileOptions::default())
        .unwrap_err()
        .render("budget.ron", &bad);
    assert!(error.contains("accuracy.position"), "{error}");
    // Bouncing particles within a millimetre: no scheme gets there in 64 substeps.
    let src = effect(STEPPED[2].1, BOUNCE, 1e-3);
    let error = compile_str(&src, &CompileOptions::default())
        .unwrap_err()
        .render("budget.ron", &src);
    assert!(
        error.contains("accuracy.position: no integrator keeps within 1.0e-3 m over 1 s with at most 64 substeps: the closest, "),
        "{error}"
    );
    // A window too long to calibrate, and a budget in both units or in none.
    for (budget, wanted) in [
        (
            "(position: 0.01, over: 1000.0)",
            "accuracy.over: 1000 s is 60000 steps of 0.016666666666666666 s; a budget is calibrated over at most 20000 steps",
        ),
        (
            "(position: 0.01, pixels: 0.5)",
            "accuracy.pixels: a budget is in metres (`position`) or on screen (`pixels`), not both",
        ),
        ("(over: 2.0)", "accuracy: a budget needs `position` (metres) or `pixels`"),
    ] {
        let src = effect(STEPPED[0].1, "", 0.01)
            .replace("accuracy: (position: 1e-2, over: 1.0)", &format!("accuracy: {budget}"));
        assert!(src.contains(budget), "{src}");
        let error = compile_str(&src, &CompileOptions::default())
            .unwrap_err()
            .render("budget.ron", &src);
        assert!(error.contains(wanted), "{error}");
    }
}

#[test]
fn a_scheme_the_file_names_is_kept_and_a_warning_says_when_it_misses_the_budget() {
    let src = effect(STEPPED[0].1, "integrator: Euler,", 1e-4);
    let compiled = compile_str(&src, &CompileOptions::default()).unwrap();
    assert_eq!(compiled.ir.integrator, plume::Integrator::Euler);
    let warnings = compiled.warnings.render("budget.ron", &src);
    assert!(
        warnings.contains("accuracy.position: Euler x1 (the file's) strays"),
        "{warnings}"
    );
}

#[test]
fn a_pixel_budget_integrates_a_distant_effect_more_cheaply_and_both_stay_within_it() {
    // A spring of half a metre seen from 2 m and from 200 m, half a pixel of a 720-pixel image
    // allowed: the near one needs about 1 mm, the far one 10 cm.
    let gpu = gpu();
    let at = |distance: f64| {
        format!(
            r#"Effect(
    name: "pixels",
    capacity: 64,
    seed: 3,
    emitters: [Emitter(burst: 64, shape: Box(min: (0.3, -0.1, -0.1), max: (0.5, 0.1, 0.1)),
                       velocity: Constant((-0.2, 0.0, 0.06)))],
    forces: [Custom(accel: "-40.0 * x - 0.5 * v")],
    camera: Camera(eye: (0.0, 0.0, {distance:?}), target: (0.0, 0.0, 0.0), fov_y: 45.0),
    accuracy: (pixels: 0.5, height: 720, over: 1.0),
)"#
        )
    };
    let mut costs = Vec::new();
    for distance in [2.0, 200.0] {
        let src = at(distance);
        let compiled = compile_str(&src, &CompileOptions::default())
            .unwrap_or_else(|e| panic!("{}", e.render("pixels.ron", &src)));
        let chosen = compiled.ir.accuracy.clone().unwrap();
        let Some(Choice::Stepped { scheme, .. }) = chosen.choice else {
            panic!("{distance} m: {:?}", chosen.choice)
        };
        assert!(chosen.describe().contains("px"), "{}", chosen.describe());
        costs.push(scheme.evaluations());
        let effect = plume::compiler::parse_with(&src, &CompileOptions::default()).unwrap();
        let check = check_budget(&gpu, &effect).unwrap().unwrap();
        assert!(
            check.met() && check.unit == "px",
            "{distance} m: {} measured {:.3} px",
            chosen.describe(),
            check.measured
        );
    }
    assert!(
        costs[1] < costs[0],
        "the far effect costs {} force evaluations a step, the near one {}",
        costs[1],
        costs[0]
    );
    // A host that sees the near file from 200 m (`CompileOptions::accuracy_camera`) gets the far
    // choice, and its check measures through the host's camera too.
    let host = CompileOptions {
        accuracy_camera: Some(plume::compiler::schema::Camera {
            eye: plume::compiler::schema::Vec3(0.0, 0.0, 200.0),
            target: plume::compiler::schema::Vec3(0.0, 0.0, 0.0),
            fov_y: 45.0,
        }),
        ..Default::default()
    };
    let src = at(2.0);
    let compiled = compile_str(&src, &host).unwrap();
    let chosen = compiled.ir.accuracy.clone().unwrap();
    let Some(Choice::Stepped { scheme, .. }) = chosen.choice else {
        panic!("{:?}", chosen.choice)
    };
    assert!(
        chosen.describe().contains("host's camera"),
        "{}",
        chosen.describe()
    );
    assert_eq!(scheme.evaluations(), costs[1], "{}", chosen.describe());
    let effect = plume::compiler::parse_with(&src, &host).unwrap();
    let check = check_budget(&gpu, &effect).unwrap().unwrap();
    assert!(
        check.met(),
        "{} measured {:.3} px",
        chosen.describe(),
        check.measured
    );
}

/// A group fed by events alone has no particles of its own: the graph's compiler calibrates its
/// budget on a sample burst (its spawn rule where its parent first fires in f64, with the share of
/// the parent's velocity the event passes on), and the GPU check of that sample burst keeps the
/// budget. Shells fly up under gravity (closed form: Exact) and burst into debris that an
/// attractor pulls through its core (no closed form: stepped).
#[test]
fn a_group_fed_by_events_is_calibrated_and_checked_on_a_sample_burst() {
    let src = r#"Effect(
    name: "shells",
    capacity: 8,
    seed: 4,
    emitters: [Emitter(burst: 4, shape: Point((0.0, 1.0, 0.0)),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 20.0, speed: (4.0, 5.0)),
                       lifetime: Some((0.5, 0.6)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    accuracy: (position: 1e-3, over: 1.0),
    events: [Event(on: Death, target: "debris", count: 32, velocity: Radial(speed: (1.0, 2.0)),
                   lifetime: Some((2.0, 2.0)), inherit_velocity: 0.5)],
    groups: [Group(name: "debris", capacity: 512,
                   forces: [Attractor(center: (0.0, 3.0, 0.0), range: 5.0, strength: 20.0, core: 0.3)])],
)"#;
    let graph = plume::compiler::graph::compile_graph_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("shells.ron", src)));
    let shells = graph.groups[0].effect.ir.accuracy.clone().unwrap();
    assert_eq!(shells.choice, Some(Choice::Exact), "{}", shells.describe());
    let debris = graph.groups[1].effect.ir.accuracy.clone().unwrap();
    let sample_burst = debris.sample_burst.expect("a sample burst for the debris");
    // Where a shell dies: above its launch point, after about half a second of flight.
    assert!(sample_burst.offset[1] > 1.5, "{sample_burst:?}");
    assert!(sample_burst.velocity != [0.0; 3], "{sample_burst:?}");
    let Some(Choice::Stepped {
        scheme, samples, ..
    }) = debris.choice
    else {
        panic!("{}", debris.describe())
    };
    assert_eq!(samples, 64, "{}", debris.describe());
    assert!(
        debris.describe().contains("of a sample burst at"),
        "{}",
        debris.describe()
    );
    assert_eq!(graph.groups[1].effect.ir.integrator, scheme.integrator);

    // Checked on the GPU as `plume accuracy` does: the debris alone, its spawn rule its one
    // emitter, the sample burst fired at the first step (256 particles).
    let effect = plume::compiler::parse_with(src, &CompileOptions::default()).unwrap();
    let groups = plume::compiler::graph::group_effects(&effect);
    let alone = plume::compiler::graph::reference::sampled_group(&groups, &graph, 1, 256)
        .expect("the shells fire");
    assert_eq!(alone.emitters, vec![groups[0].events[0].as_emitter()]);
    assert_eq!(
        alone.sample_burst.map(|b| (b.emitter, b.count, b.offset)),
        Some((0, 256, sample_burst.offset))
    );
    let check = check_budget(&gpu(), &alone).unwrap().expect("a budget");
    assert!(
        check.met() && check.particles == 256,
        "{}: measured {:.3e} m on the GPU against 1e-3 m",
        check.chosen,
        check.measured
    );
    // The same choice as the graph's: the same sample.
    assert!(
        check
            .chosen
            .starts_with(&format!("accuracy: {}", scheme.describe())),
        "{}",
        check.chosen
    );
}

/// A host's camera that cannot measure pixels (a zero field of view, or looking at its own
/// eye) is an error at the pixel budget, not a NaN estimate.
#[test]
fn a_host_camera_that_cannot_measure_pixels_is_an_error() {
    let src = r#"Effect(
    name: "pixels",
    capacity: 16,
    emitters: [Emitter(burst: 16, shape: Point((0.4, 0.0, 0.0)), velocity: Constant((0.0, 0.1, 0.0)))],
    forces: [Custom(accel: "-40.0 * x")],
    accuracy: (pixels: 0.5),
)"#;
    use plume::compiler::schema::{Camera, Vec3};
    for camera in [
        Camera {
            eye: Vec3(0.0, 0.0, 5.0),
            target: Vec3(0.0, 0.0, 0.0),
            fov_y: 0.0,
        },
        Camera {
            eye: Vec3(1.0, 1.0, 1.0),
            target: Vec3(1.0, 1.0, 1.0),
            fov_y: 45.0,
        },
    ] {
        let host = CompileOptions {
            accuracy_camera: Some(camera),
            ..Default::default()
        };
        let err = compile_str(src, &host).expect_err("an unusable camera");
        let text = err.render("pixels.ron", src);
        assert!(
            text.contains("accuracy.pixels") && text.contains("host's camera"),
            "{text}"
        );
    }
}

#[test]
fn a_calibration_is_kept_by_content_so_a_second_compile_or_seed_runs_none() {
    // A budget with no closed form: compiling it calibrates once. The same content again,
    // or with another seed (only its sample particles differ), takes the choice from memory:
    // the same scheme, the same kernels.
    let src = effect(r#"Custom(accel: "-40.0 * x")"#, "", 1e-3)
        .replace("name: \"budget\"", "name: \"kept\"");
    let compile = |seed: Option<u32>| {
        let options = CompileOptions {
            seed,
            ..Default::default()
        };
        compile_str(&src, &options).unwrap_or_else(|e| panic!("{}", e.render("kept.ron", &src)))
    };
    let first = compile(None);
    assert!(
        matches!(
            first.ir.accuracy.as_ref().and_then(|a| a.choice.clone()),
            Some(Choice::Stepped { .. })
        ),
        "{}",
        first.ir
    );
    let remembered = |c: &plume::CompiledEffect| c.ir.accuracy.as_ref().unwrap().remembered;
    let again = compile(None);
    let reseeded = compile(Some(77));
    assert!(
        remembered(&again) && remembered(&reseeded),
        "a kept calibration ran again"
    );
    assert_eq!(again.wgsl, first.wgsl);
    assert_eq!(
        (again.ir.integrator, again.ir.substeps),
        (first.ir.integrator, first.ir.substeps)
    );
    assert_eq!(
        (reseeded.ir.integrator, reseeded.ir.substeps),
        (first.ir.integrator, first.ir.substeps)
    );
    assert_ne!(reseeded.ir.seed_mix, first.ir.seed_mix);
}
