//! Snapshot tests: the WGSL (compute, draw, trail and flock search modules), IR and layout of every example effect,
//! and the diagnostics of every bad input in tests/bad. One glob each, so a new file gets its snapshot with no new code.

use plume::compiler::graph::compile_graph_str;
use plume::{CompileError, CompileOptions};

#[test]
fn every_example_compiles_without_warnings_and_matches_its_snapshots() {
    insta::glob!("../effects", "*.ron", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let options = CompileOptions {
            base_dir: path.parent().map(|p| p.to_path_buf()),
            ..Default::default()
        };
        let graph = compile_graph_str(&source, &options)
            .unwrap_or_else(|e| panic!("{}", e.render(&path.display().to_string(), &source)));
        let warnings = graph.all_warnings();
        assert!(
            warnings.is_empty(),
            "examples must compile without warnings:\n{}",
            warnings.render(&path.display().to_string(), &source)
        );
        // The top-level group's snapshots keep their names; other groups' add theirs.
        for (g, group) in graph.groups.iter().enumerate() {
            let name = |kind: &str| match g {
                0 => kind.to_string(),
                _ => format!("{kind}_{}", group.name),
            };
            let compiled = &group.effect;
            insta::assert_snapshot!(name("wgsl"), compiled.wgsl);
            insta::assert_snapshot!(name("draw"), compiled.draw_wgsl);
            // Only effects with trails have a trail module (and a snapshot of it).
            if let Some(trail) = &compiled.trail_wgsl {
                insta::assert_snapshot!(name("trail"), trail);
            }
            // Only grid flocks have a search module.
            if let Some(search) = &compiled.flock_search_wgsl {
                insta::assert_snapshot!(name("flock_search"), search);
            }
            insta::assert_snapshot!(
                name("ir_and_layout"),
                format!("{}\n{}", compiled.ir, compiled.layout)
            );
        }
    });
}

#[test]
fn every_bad_input_gets_a_located_error_and_matches_its_snapshot() {
    insta::glob!("bad", "*.ron", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let name = format!("tests/bad/{}", path.file_name().unwrap().to_string_lossy());
        let err = match compile_graph_str(&source, &CompileOptions::default()) {
            Ok(_) => panic!("{name} compiled, but it is in tests/bad"),
            Err(e) => e,
        };
        let rendered = err.render(&name, &source);
        match &err {
            CompileError::Invalid(d) => {
                assert!(!d.items.is_empty());
                for item in &d.items {
                    assert!(
                        item.span.is_some(),
                        "{name}: diagnostic without a location: {item}"
                    );
                }
            }
            CompileError::Internal(_) => panic!("bad input reached naga: {rendered}"),
        }
        insta::assert_snapshot!("diagnostics", rendered);
    });
}

/// The compute renderer's composite in both of its forms: with a thread per mask word (every adapter) and
/// with subgroup transposes (adapters whose subgroups are 32 wide, such as NVIDIA's; llvmpipe
/// has none, so this is where that form is checked off the GPU). Every example that the
/// splat draws with a generated composite (quads, ribbons), into an 8-bit and an HDR image,
/// must give naga-valid WGSL either way, and the subgroup form must really use subgroups.
#[test]
fn every_splat_composite_validates_with_and_without_subgroups() {
    use plume::compiler::wgsl::draw::{self, splat_discs, DrawShape};
    use plume::compiler::wgsl::trail;
    let mut composites = 0;
    insta::glob!("../effects", "*.ron", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let options = CompileOptions {
            base_dir: path.parent().map(|p| p.to_path_buf()),
            ..Default::default()
        };
        let graph = compile_graph_str(&source, &options).unwrap();
        for group in &graph.groups {
            let (ir, layout) = (&group.effect.ir, &group.effect.layout);
            for hdr in [false, true] {
                for subgroups in [false, true] {
                    let shape = DrawShape {
                        splat: true,
                        hdr,
                        subgroups,
                        ..DrawShape::single(ir)
                    };
                    let mut modules = Vec::new();
                    if !splat_discs(ir, hdr) {
                        modules.push(draw::emit(ir, layout, &shape));
                    }
                    if ir.render.trail.is_some() {
                        modules.push(trail::emit(ir, layout, &shape));
                    }
                    for wgsl in modules {
                        let what = format!("{} (hdr {hdr}, subgroups {subgroups})", path.display());
                        let module = naga::front::wgsl::parse_str(&wgsl)
                            .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(&wgsl)));
                        naga::valid::Validator::new(
                            naga::valid::ValidationFlags::all(),
                            // unpack2x16float, which every wgpu device allows.
                            naga::valid::Capabilities::SUBGROUP
                                | naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32,
                        )
                        .subgroup_stages(naga::valid::ShaderStages::COMPUTE)
                        .subgroup_operations(naga::valid::SubgroupOperationSet::all())
                        .validate(&module)
                        .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(&wgsl)));
                        assert!(wgsl.contains("fn composite("), "{what}: no composite");
                        assert_eq!(
                            wgsl.contains("subgroupShuffleXor(")
                                && wgsl.contains("@builtin(subgroup_id)"),
                            subgroups,
                            "{what}"
                        );
                        composites += 1;
                    }
                }
            }
        }
    });
    // Most examples draw quads (discs are only the plain round untextured ones).
    assert!(composites >= 20, "only {composites} composites checked");
}
