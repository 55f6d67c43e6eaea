//! Tests of the passes through the public API: folding, pruning, integrator resolution,
//! stability warnings and layout, and WGSL validity for every integrator and feature mix.

use glam::DVec3;
use plume::compiler::forces::Term;
use plume::compiler::passes::layout::Attribute;
use plume::compiler::passes::layout::Role;
use plume::{compile_str, CompileError, CompileOptions, CompiledEffect, Integrator, Severity};

/// An effect with one emitter around the given forces and extra top-level fields.
fn effect(forces: &str, extra: &str) -> String {
    format!(
        r#"Effect(
    name: "test",
    capacity: 1000,
    emitters: [Emitter(burst: 100, shape: Point((0.0, 1.0, 0.0)),
                       velocity: Constant((1.0, 2.0, 0.0)))],
    forces: [{forces}],
    {extra}
)"#
    )
}

fn compile(src: &str) -> CompiledEffect {
    compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("test.ron", src)))
}

fn compile_err(src: &str) -> String {
    match compile_str(src, &CompileOptions::default()) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.render("test.ron", src),
    }
}

/// Sum of the IR's f64 accelerations at one point.
fn accel(c: &CompiledEffect, x: DVec3, v: DVec3) -> DVec3 {
    c.ir.terms.iter().map(|t| t.as_dyn().accel(x, v, 0.5)).sum()
}

#[test]
fn gravity_only_wgsl_has_no_trace_of_other_forces_and_a_minimal_layout() {
    let c = compile(&effect(
        "Gravity((0.0, -9.81, 0.0))",
        "integrator: SemiImplicitEuler,",
    ));
    for absent in [
        "value_noise",
        "noise",
        "cross(",
        "r_hat",
        "fall",
        "- v)",
        "* v;",
        "p.age",
        "life =",
        "dx",
        "pow(",
        "POINTS",
        "inverseSqrt",
    ] {
        assert!(
            !c.wgsl.contains(absent),
            "gravity-only WGSL contains `{absent}`:\n{}",
            c.wgsl
        );
    }
    assert!(c.wgsl.contains("a += vec3<f32>(0.0, -9.81, 0.0);"));
    assert_eq!(
        c.layout.attributes,
        vec![Attribute::Position, Attribute::Id, Attribute::Velocity]
    );
    // 28 bytes of attributes, padded to whole 16-byte words for vec4 access.
    assert_eq!(c.layout.bytes_per_particle, 32);
}

#[test]
fn fold_merges_constants_and_drags_without_changing_the_acceleration() {
    let forces = "Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5, fluid: (2.0, 0.0, 0.0)), \
                  Wind(direction: (0.0, 0.0, 2.0), strength: 3.0), Drag(k: 1.5, fluid: (0.0, 0.0, -1.0)), \
                  Gravity((0.0, 1.0, 0.0))";
    let c = compile(&effect(forces, "integrator: Rk4,"));
    assert_eq!(
        c.ir.terms.len(),
        2,
        "one constant and one drag: {:?}",
        c.ir.terms
    );
    let Term::Constant(k) = &c.ir.terms[0] else {
        panic!("constant first")
    };
    assert!((k.accel - DVec3::new(0.0, -8.81, 3.0)).length() < 1e-12);
    assert_eq!(k.origins, vec![0, 2, 4]);
    let Term::Drag(d) = &c.ir.terms[1] else {
        panic!("drag second")
    };
    assert!((d.k - 2.0).abs() < 1e-12);
    // Unfolded sum at a few velocities: -0.5 (v - (2,0,0)) - 1.5 (v - (0,0,-1)) + g + wind.
    for v in [
        DVec3::ZERO,
        DVec3::new(1.0, -2.0, 3.0),
        DVec3::new(-7.0, 0.5, 0.0),
    ] {
        let expected = DVec3::new(0.0, -8.81, 3.0)
            - 0.5 * (v - DVec3::new(2.0, 0.0, 0.0))
            - 1.5 * (v - DVec3::new(0.0, 0.0, -1.0));
        assert!((accel(&c, DVec3::ONE, v) - expected).length() < 1e-12);
    }
}

#[test]
fn prune_drops_terms_that_cannot_act() {
    let forces = "Gravity((0.0, -9.81, 0.0)), Wind(direction: (0.0, 1.0, 0.0), strength: 9.81), \
                  Drag(k: 0.0), Attractor(center: (0.0, 0.0, 0.0), range: 1.0, strength: 0.0), \
                  Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 1.0, height: 1.0, spin: 0.0)";
    let c = compile(&effect(forces, ""));
    assert!(
        c.ir.terms.is_empty(),
        "all cancel or vanish: {:?}",
        c.ir.terms
    );
    // With nothing acting, Auto's closed form is plain drift.
    assert_eq!(c.ir.integrator, Integrator::Exact);
    assert!(!c.wgsl.contains("fn accel"));
}

#[test]
fn auto_picks_exact_only_when_a_closed_form_exists_and_says_why() {
    let c = compile(&effect("Gravity((0.0, -9.81, 0.0)), Drag(k: 0.3)", ""));
    assert_eq!(c.ir.integrator, Integrator::Exact);
    assert!(c.ir.integrator_reason.starts_with("Auto"));
    let c = compile(&effect(
        "Gravity((0.0, -9.81, 0.0)), Attractor(center: (0.0, 0.0, 0.0), range: 2.0, strength: 1.0)",
        "",
    ));
    assert_eq!(c.ir.integrator, Integrator::SemiImplicitEuler);
    assert!(
        c.ir.integrator_reason.contains("forces[1] (Attractor)"),
        "{}",
        c.ir.integrator_reason
    );
    let c = compile(&effect(
        "Gravity((0.0, -9.81, 0.0))",
        "max_speed: Some(3.0),",
    ));
    assert_eq!(c.ir.integrator, Integrator::SemiImplicitEuler);
    assert!(c.ir.integrator_reason.contains("max_speed"));
}

#[test]
fn exact_with_a_vortex_is_an_error_naming_it() {
    let msg = compile_err(&effect(
        "Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 1.0, height: 1.0, spin: 1.0)",
        "integrator: Exact,",
    ));
    assert!(
        msg.contains("forces[0] (Vortex) has no closed form"),
        "{msg}"
    );
    assert!(
        msg.starts_with("test.ron:7:17: error: integrator:"),
        "{msg}"
    );
}

#[test]
fn layout_follows_the_integrator_and_lifetimes() {
    let c = compile(&effect("Gravity((0.0, -9.81, 0.0))", "integrator: Verlet,"));
    assert!(c.layout.has(Attribute::Displacement) && !c.layout.has(Attribute::Velocity));
    let src = effect("", "").replace(
        "velocity: Constant((1.0, 2.0, 0.0)))",
        "velocity: Constant((1.0, 2.0, 0.0)), lifetime: Some((1.0, 2.0)))",
    );
    let c = compile(&src);
    assert!(c.layout.has(Attribute::DeathStep));
    assert_eq!(c.layout.bytes_per_particle, 32);
}

fn warnings(src: &str) -> Vec<String> {
    let c = compile(src);
    c.warnings
        .items
        .iter()
        .inspect(|d| assert_eq!(d.severity, Severity::Warning))
        .map(|d| d.render("test.ron", src))
        .collect()
}

#[test]
fn drag_past_the_limit_warns_with_numbers_and_just_below_does_not() {
    // dt = 1/60: k*h = 2 at k = 120 for SemiImplicitEuler.
    let past = warnings(&effect("Drag(k: 121.0)", "integrator: SemiImplicitEuler,"));
    assert_eq!(past.len(), 1, "{past:?}");
    assert!(
        past[0].contains("k*h = 2.017") && past[0].contains("limit 2"),
        "{}",
        past[0]
    );
    assert!(
        past[0].starts_with("test.ron:6:22: warning: forces[0] (Drag).k"),
        "{}",
        past[0]
    );
    assert!(warnings(&effect("Drag(k: 119.0)", "integrator: SemiImplicitEuler,")).is_empty());
    // Rk4's limit is 2.785; Exact has none.
    assert!(warnings(&effect("Drag(k: 160.0)", "integrator: Rk4,")).is_empty());
    assert_eq!(
        warnings(&effect("Drag(k: 170.0)", "integrator: Rk4,")).len(),
        1
    );
    assert!(warnings(&effect("Drag(k: 1000.0)", "integrator: Exact,")).is_empty());
    // Substeps move the limit.
    assert!(warnings(&effect(
        "Drag(k: 121.0)",
        "integrator: SemiImplicitEuler, substeps: 2,"
    ))
    .is_empty());
}

#[test]
fn attractor_stiffness_warns_past_the_omega_h_limit() {
    // omega = sqrt(strength / core); h = 1/60: omega*h = 2 at strength/core = 14400. (These
    // strengths also trip the core-transit warning, tested in tests/accuracy.rs.)
    let a = |s: f64| {
        format!("Attractor(center: (0.0, 0.0, 0.0), range: 10.0, strength: {s:?}, core: 1.0)")
    };
    let stiff = |w: Vec<String>| -> Vec<String> {
        w.into_iter().filter(|m| m.contains("stiffness")).collect()
    };
    let past = stiff(warnings(&effect(&a(14500.0), "integrator: Verlet,")));
    assert_eq!(past.len(), 1, "{past:?}");
    assert!(past[0].contains("limit 2.000"), "{}", past[0]);
    assert!(stiff(warnings(&effect(&a(14300.0), "integrator: Verlet,"))).is_empty());
    // A repeller has no oscillation, so no stiffness warning however strong.
    assert!(stiff(warnings(&effect(&a(-1e6), "integrator: Verlet,"))).is_empty());
    // Euler always gains energy: a gentle attractor over 60 s still doubles its orbits.
    let euler = warnings(&effect(&a(4.0), "integrator: Euler,"));
    assert_eq!(euler.len(), 1, "{euler:?}");
    assert!(euler[0].contains("gains energy"));
}

#[test]
fn thin_kill_volume_and_capacity_warnings() {
    let w = warnings(&effect(
        "",
        "max_speed: Some(100.0), kill: [InsideBox(min: (-1.0, 0.0, -1.0), max: (1.0, 0.5, 1.0))],",
    ));
    assert!(w.iter().any(|m| m.contains("can pass through")), "{w:?}");
    let src = effect("", "").replace("burst: 100", "burst: 5000");
    let w = warnings(&src);
    assert!(w.iter().any(|m| m.contains("4000 are dropped")), "{w:?}");
}

#[test]
fn every_integrator_and_feature_mix_validates_in_naga() {
    let forces = "Gravity((0.0, -9.81, 0.0)), Drag(k: 0.4, fluid: (1.0, 0.0, 0.0)), \
                  Wind(direction: (1.0, 0.0, 0.0), strength: 2.0, noise: 0.5), \
                  Attractor(center: (0.0, 4.0, 0.0), range: 3.0, strength: 8.0), \
                  Vortex(center: (0.0, 0.0, 0.0), axis: (0.0, 1.0, 0.0), range: 2.0, height: 6.0, \
                         spin: 5.0, pull: 1.0, down: 0.5, curve: 1.5)";
    let extra = "max_speed: Some(30.0), substeps: 3, \
                 collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.1), \
                           Plane(point: (5.0, 0.0, 0.0), normal: (-1.0, 0.0, 0.0), restitution: 1.0, friction: 0.0)], \
                 kill: [InsideSphere(center: (0.0, 9.0, 0.0), radius: 1.0), OutsideSphere(center: (0.0, 0.0, 0.0), radius: 50.0), \
                        OutsideBox(min: (-20.0, -1.0, -20.0), max: (20.0, 30.0, 20.0))],";
    let emitters = r#"emitters: [
        Emitter(burst: 10, rate: 50.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.0),
                velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((1.0, 2.0))),
        Emitter(rate: 7.5, shape: Grid(min: (-1.0, 1.0, -1.0), max: (1.0, 1.0, 1.0), counts: (3, 1, 4)),
                velocity: Cone(axis: (1.0, 1.0, 0.0), angle: 180.0, speed: (0.0, 0.0))),
        Emitter(burst: 3, shape: Points([(0.0, 2.0, 0.0), (1.0, 2.0, 0.0)]), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(rate: 1.0, shape: Box(min: (0.0, 1.0, 0.0), max: (0.0, 1.0, 0.0)),
                velocity: Radial(speed: (3.0, 3.0)), lifetime: Some((0.5, 0.5))),
        Emitter(rate: 1.0, shape: Disc(center: (0.0, 1.0, 0.0), normal: (1.0, 0.0, 0.0), radius: 1.0),
                velocity: Cone(axis: (0.0, -1.0, 0.0), angle: 0.0, speed: (1.0, 2.0))),
    ],"#;
    let src = effect(forces, extra).replace(
        r#"emitters: [Emitter(burst: 100, shape: Point((0.0, 1.0, 0.0)),
                       velocity: Constant((1.0, 2.0, 0.0)))],"#,
        emitters,
    );
    for integrator in Integrator::CONCRETE
        .into_iter()
        .filter(|i| *i != Integrator::Exact)
    {
        let options = CompileOptions {
            integrator: Some(integrator),
            ..Default::default()
        };
        match compile_str(&src, &options) {
            Ok(c) => assert_eq!(c.ir.integrator, integrator),
            Err(CompileError::Internal(e)) => panic!("{integrator:?}: {e}"),
            Err(e) => panic!("{integrator:?}: {}", e.render("mix.ron", &src)),
        }
    }
}

#[test]
fn overrides_replace_file_values() {
    let src = effect("Gravity((0.0, -9.81, 0.0))", "");
    let c = compile_str(
        &src,
        &CompileOptions {
            dt: Some(0.01),
            seed: Some(9),
            substeps: Some(2),
            integrator: Some(Integrator::Rk4),
            sort: Some(true),
            state: None,
            base_dir: None,
            placed: true,
            bursts: true,
            live_params: true,
            step_only: true,
            files: None,
            receive_shadows: false,
            accuracy_camera: None,
        },
    )
    .unwrap();
    assert_eq!(
        (
            c.ir.dt,
            c.ir.seed,
            c.ir.substeps,
            c.ir.integrator,
            c.ir.placed,
            c.ir.bursts
        ),
        (0.01, 9, 2, Integrator::Rk4, true, true)
    );
    assert!(c.ir.sort && c.wgsl.contains("fn depth_keys"));
    let bad = compile_str(
        &src,
        &CompileOptions {
            dt: Some(-1.0),
            ..Default::default()
        },
    );
    assert!(matches!(bad, Err(CompileError::Invalid(_))));
}

#[test]
fn all_pairs_flocking_warns_from_the_measured_crossover_and_flock_blocks_exact() {
    let flock = |neighbors: &str| {
        format!("Flock(radius: 0.5, separation: 1.0, cohesion: 0.1, neighbors: {neighbors})")
    };
    let at = |capacity: u32, neighbors: &str| {
        warnings(
            &effect(&flock(neighbors), "")
                .replace("capacity: 1000", &format!("capacity: {capacity}")),
        )
    };
    let crossover = plume::compiler::forces::flock::GRID_FASTER_FROM;
    let w = at(crossover, "AllPairs");
    assert!(
        w.iter()
            .any(|m| m.contains("(Flock).neighbors: all pairs at capacity")),
        "{w:?}"
    );
    assert!(at(crossover - 1, "AllPairs").is_empty());
    assert!(at(crossover, "Grid(cell: 0.5)").is_empty());
    // A flock couples particles: no closed form.
    let err = plume::compile_str(
        &effect(&flock("AllPairs"), "integrator: Exact,"),
        &Default::default(),
    )
    .unwrap_err()
    .render("t.ron", "");
    assert!(err.contains("(Flock) couples particles"), "{err}");
    // A grid cell smaller than the radius would miss neighbours: an error.
    let err = plume::compile_str(&effect(&flock("Grid(cell: 0.4)"), ""), &Default::default())
        .unwrap_err()
        .render("t.ron", "");
    assert!(err.contains("must be >= radius"), "{err}");
}

#[test]
fn absurd_sizes_found_by_the_debug_fuzz_are_errors_or_warnings_not_overflows() {
    // Each of these overflowed integer arithmetic in a debug build (docs/robustness.md).
    let huge_dt = effect("Drag(k: 1.36)", "max_speed: Some(5.0),")
        .replace("capacity: 1000,", "capacity: 1000,\n    dt: 1e30,");
    let w = warnings(&huge_dt);
    assert!(
        w.iter()
            .any(|m| m.contains("raise substeps to at least 18446744073709551615")),
        "{w:?}"
    );
    for counts in [
        "(4, 2147483648, 2147483648)",
        "(4294967295, 4294967295, 4294967295)",
    ] {
        let src = format!(
            r#"Effect(name: "grid", capacity: 8,
    emitters: [Emitter(burst: 1, shape: Grid(min: (-0.5, -0.5, -0.5), max: (0.5, 0.5, 0.5), counts: {counts}), velocity: Constant((0.0, 0.0, 0.0)))])"#
        );
        let err = plume::compile_str(&src, &Default::default())
            .unwrap_err()
            .render("grid.ron", &src);
        assert!(err.contains("holds more than 4294967295 points"), "{err}");
    }
}

/// What the state pass decides, and why, for each thing that needs state.
#[test]
fn stateless_only_where_nothing_needs_state() {
    let stream = |capacity: u32, lifetime: &str, extra: &str| {
        format!(
            r#"Effect(name: "s", capacity: {capacity}, dt: 0.01,
    emitters: [Emitter(burst: 50, rate: 1000.0, shape: Point((0.0, 0.0, 0.0)),
                       velocity: Constant((0.0, 1.0, 0.0)), lifetime: {lifetime})],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.3)],
    {extra}
)"#
        )
    };
    // Lifetimes up to 2 s = 200 steps: at most 50 + floor(1000 * 0.01 * 200) + 2 = 2052 alive.
    let ok = compile(&stream(2052, "Some((1.0, 2.0))", ""));
    let plan = ok.ir.stateless.as_ref().expect("stateless");
    assert_eq!(
        (plan.peak, plan.max_segments, plan.lives.clone()),
        (2052, 200, vec![Some(200)])
    );
    assert_eq!(ok.layout.state_bytes_per_particle(), 0);
    assert!(
        ok.layout.stateless() && !ok.layout.binds(Role::FreeList) && !ok.layout.binds(Role::Params)
    );
    assert!(ok
        .layout
        .to_string()
        .starts_with("state: none, 0 bytes per particle"));
    assert!(ok.ir.to_string().contains("state stateless (Auto"));
    // Each cause of state, with the reason the IR records.
    for (src, why) in [
        (
            stream(2051, "Some((1.0, 2.0))", ""),
            "capacity 2051 may drop spawns (up to 2052 alive at once)",
        ),
        (
            stream(100_000, "None", ""),
            "emitters[0] spawns at a rate and its particles never die",
        ),
        (
            stream(
                5000,
                "Some((1.0, 2.0))",
                "kill: [InsideSphere(center: (0.0, 0.0, 0.0), radius: 1.0)],",
            ),
            "kill[0] decides deaths from every earlier position",
        ),
        (
            stream(5000, "Some((1.0, 2.0))", "integrator: Rk4,"),
            "the Rk4 integrator carries each particle's state",
        ),
        (
            stream(5000, "Some((1.0, 2.0))", "max_speed: Some(3.0),"),
            "the SemiImplicitEuler integrator carries",
        ),
        (
            stream(2_000_000, "Some((1.0, 700.0))", ""),
            "particles stay alive over 70000 spawning steps, more than the 65536",
        ),
        (
            stream(5000, "Some((1.0, 2.0))", "state: Stateful,"),
            "state: Stateful in the file",
        ),
    ] {
        let c = compile(&src);
        assert!(c.ir.stateless.is_none(), "{why}");
        assert!(
            c.ir.state_reason.contains(why),
            "{} lacks {why}",
            c.ir.state_reason
        );
        assert!(c.wgsl.contains("fn update") && c.layout.state_bytes_per_particle() == 32);
    }
    // Asking for it where it cannot be is an error at `state` naming the cause.
    let err = compile_err(&stream(100, "Some((1.0, 2.0))", "state: Stateless,"));
    assert!(
        err.contains("state") && err.contains("capacity 100 may drop spawns"),
        "{err}"
    );
    // A burst that never dies needs one segment forever, and no more capacity than the burst.
    let burst = compile(
        &effect("Gravity((0.0, -9.81, 0.0))", "capacity: 100,").replace("capacity: 1000,\n", ""),
    );
    let plan = burst.ir.stateless.as_ref().expect("stateless");
    assert_eq!(
        (plan.peak, plan.max_segments, plan.lives.clone()),
        (100, 1, vec![None])
    );
}

#[test]
fn bounds_pass_through_and_bad_bounds_are_located() {
    let base = r#"Effect(name: "b", capacity: 8,
    emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))],
    bounds: Some(Bounds(min: (-1.0, 0.0, -1.0), max: (1.0, MAXY, 1.0))))"#;
    let ok = compile_str(&base.replace("MAXY", "3.0"), &CompileOptions::default()).unwrap();
    assert_eq!(
        ok.ir.bounds,
        Some((
            glam::DVec3::new(-1.0, 0.0, -1.0),
            glam::DVec3::new(1.0, 3.0, 1.0)
        ))
    );
    let bad = base.replace("MAXY", "-2.0");
    let text = compile_str(&bad, &CompileOptions::default())
        .unwrap_err()
        .render("b.ron", &bad);
    assert!(
        text.contains("bounds.min")
            && text.contains("min must be <= max")
            && text.contains("b.ron:3:"),
        "{text}"
    );
}

/// The update stores only the words holding what it changes (`store_moved`: position, motion
/// and declared attributes that change): every field any example group's update assigns must
/// be one of those, or its change would be lost.
#[test]
fn the_update_assigns_only_the_fields_it_stores() {
    use plume::compiler::graph::compile_graph_str;
    let mut updates = 0;
    let dirs = ["effects", "effects/hanabi"].map(std::fs::read_dir);
    for entry in dirs.into_iter().flat_map(|d| d.unwrap()) {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "ron") {
            continue;
        }
        let source = std::fs::read_to_string(&path).unwrap();
        let options = CompileOptions {
            base_dir: path.parent().map(|p| p.to_path_buf()),
            ..Default::default()
        };
        let graph = compile_graph_str(&source, &options).unwrap();
        for group in &graph.groups {
            let wgsl = &group.effect.wgsl;
            let changed: Vec<&str> = group
                .effect
                .layout
                .attributes
                .iter()
                .filter(|a| a.changes())
                .flat_map(|a| a.fields().0.iter().copied())
                .collect();
            let Some(start) = wgsl.find("fn update_particle(") else {
                continue;
            };
            updates += 1;
            let body = &wgsl[start..start + wgsl[start..].find("\n}\n").unwrap()];
            assert!(body.contains("store_moved(i, p)"), "{}", path.display());
            for line in body.lines().map(str::trim) {
                let Some(rest) = line.strip_prefix("p.") else {
                    continue;
                };
                let field = rest.split([' ', '=']).next().unwrap();
                assert!(
                    changed.contains(&field),
                    "{}: the update assigns p.{field}, which store_moved does not store",
                    path.display()
                );
            }
        }
    }
    assert!(updates >= 10, "only {updates} example updates found");
}
