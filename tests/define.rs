//! Named expressions (`define`): read by name in any expression, they compile to what their
//! text written in place compiles to; a place reads one only where it may read what the
//! definition reads; definitions that double one another are refused before they blow up.

use plume::{compile_str, CompileOptions};

fn wgsl(src: &str) -> String {
    compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("define.ron", src)))
        .wgsl
}

/// An effect whose spawn velocity, force and draw read `r` and `pull`: `defined` names them,
/// otherwise their text stands in place.
fn effect(defined: bool) -> String {
    let (r, pull) = match defined {
        true => ("r", "pull"),
        false => (
            "(length(x - vec3(0.0, 1.0, 0.0)))",
            "(normalize(vec3(0.0, 1.0, 0.0) - x) * 4.0 * exp(-(length(x - vec3(0.0, 1.0, 0.0)))))",
        ),
    };
    format!(
        r#"Effect(
    name: "define",
    capacity: 1000,
    define: {{
        "r": "length(x - vec3(0.0, 1.0, 0.0))",
        "pull": "normalize(vec3(0.0, 1.0, 0.0) - x) * 4.0 * exp(-r)",
    }},
    emitters: [Emitter(rate: 200.0, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 1.0),
        velocity: Custom("normalize(x - vec3(0.0, 1.0, 0.0)) * {r}"), lifetime: Some((1.0, 2.0)))],
    forces: [Custom(accel: "{pull} + vec3(0.0, -{r}, 0.0)")],
    substeps: 4,
    render: Render(size_by: Some("0.5 + {r}")),
)"#
    )
}

#[test]
fn a_named_expression_compiles_as_its_text_in_place() {
    assert_eq!(wgsl(&effect(true)), wgsl(&effect(false)));
}

#[test]
fn definitions_that_double_each_other_are_refused() {
    // d0 = x.x, d1 = d0 + d0, ...: d20 would expand to millions of nodes.
    let mut defines = String::from(r#""d0": "x.x", "#);
    for i in 1..=20 {
        defines.push_str(&format!(r#""d{i}": "d{j} + d{j}", "#, j = i - 1));
    }
    let src = format!(
        r#"Effect(name: "big", capacity: 10, define: {{{defines}}},
    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))],
    forces: [Custom(accel: "vec3(d20, 0.0, 0.0)")])"#
    );
    let err = compile_str(&src, &CompileOptions::default()).unwrap_err();
    let text = err.render("big.ron", &src);
    assert!(text.contains("expand to more than 16384 nodes"), "{text}");
}
