//! Imported vector fields (`VectorField(file: "x.fga", ..)`): an FGA file's grid acts on the
//! GPU exactly as the f64 reference interpolates it, clamped, tiled or zero outside its box,
//! placed by offset and scale; bad files and fields are refused, located at the force.

mod common;

use common::compare::{compare_at, roundings_per_step};
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;
use plume::{compile_str, CompileOptions};

/// A folder of its own with `name` holding `text`; returns the folder.
fn folder_with(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-vector-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(name), text).unwrap();
    dir
}

/// A swirl about the y axis with a lift, on 9 x 5 x 9 nodes over [-2, 2] x [0, 2] x [-2, 2]:
/// v = (-z, 0.5 + 0.1 y, x) plus a ripple in x that trilinear interpolation does not hold
/// exactly, so the GPU and the reference must agree on the cells, not only the formula.
fn swirl_fga() -> String {
    let mut text = String::from("9,5,9,\n-2,0,-2,\n2,2,2,\n");
    for k in 0..9 {
        for j in 0..5 {
            for i in 0..9 {
                let (x, y, z) = (-2.0 + 0.5 * i as f64, 0.5 * j as f64, -2.0 + 0.5 * k as f64);
                let ripple = 0.3 * ((i * 7 + j * 3 + k * 5) % 4) as f64;
                text += &format!("{:.4},{:.4},{:.4},\n", -z + ripple, 0.5 + 0.1 * y, x);
            }
        }
    }
    text
}

fn effect(field: &str) -> String {
    format!(
        r#"Effect(name: "swirl", capacity: 3000, seed: 8, dt: 0.02,
    emitters: [Emitter(rate: 600.0, shape: Disc(center: (0.0, 0.2, 0.0), normal: (0.0, 1.0, 0.0), radius: 2.5),
        velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((2.0, 3.0)))],
    forces: [{field}, Drag(k: 0.4)],
    integrator: Rk4)"#
    )
}

#[test]
fn a_vector_field_acts_on_the_gpu_as_the_reference_interpolates_it() {
    let dir = folder_with("swirl.fga", &swirl_fga());
    let options = CompileOptions {
        base_dir: Some(dir),
        ..Default::default()
    };
    let gpu = common::gpu();
    for field in [
        "VectorField(file: \"swirl.fga\", strength: 2.0)",
        "VectorField(file: \"swirl.fga\", strength: 1.5, outside: Tile, offset: (0.3, 0.0, -0.2), scale: 0.5)",
        "VectorField(file: \"swirl.fga\", strength: 3.0, outside: Zero, scale: 0.8)",
    ] {
        let compiled = compile_str(&effect(field), &options).expect("compiles");
        assert!(compiled.wgsl.contains("force_data"), "{field}");
        let mut sim = Effect::new(&gpu, compiled.clone()).expect("GPU sim");
        let mut reference = ReferenceSim::new(&compiled.ir);
        sim.run(75, |_| {}).expect("run");
        reference.run(75);
        let cpu = reference.records();
        assert!(cpu.len() > 800, "{field}: {} alive", cpu.len());
        compare_at(
            field,
            75,
            false,
            true,
            None,
            roundings_per_step(&compiled.ir),
            &sim.records().expect("records"),
            &cpu,
        );
        // The field moved them: they swirl and rise off the disc.
        let risen = cpu.iter().filter(|r| r.position.y > 0.4).count();
        assert!(risen > cpu.len() / 4, "{field}: only {risen} rose");
    }
}

#[test]
fn bad_vector_fields_are_refused_where_they_are_written() {
    let dir = folder_with("short.fga", "2,2,2, 0,0,0, 1,1,1, 0,0,0");
    std::fs::write(dir.join("huge.fga"), "4096,4096,4096, 0,0,0, 1,1,1").unwrap();
    // A 4 GiB file, sparse (it takes no disk): refused by its size, before it is read.
    std::fs::File::create(dir.join("4gb.fga"))
        .and_then(|f| f.set_len(4 << 30))
        .unwrap();
    std::fs::write(
        dir.join("ok.fga"),
        format!("2,2,2,0,0,0,1,1,1{}", ",0.5".repeat(24)),
    )
    .unwrap();
    let options = CompileOptions {
        base_dir: Some(dir),
        ..Default::default()
    };
    let cases = [
        ("VectorField(file: \"missing.fga\")", "forces[0] (VectorField).file: cannot open vector field"),
        ("VectorField(file: \"short.fga\")", "ends before its vector of node 1"),
        ("VectorField(file: \"huge.fga\")", "68719476736 nodes is more than the 4194304"),
        ("VectorField(file: \"4gb.fga\")", "is 4294967296 bytes, more than the 268435456 read"),
        ("VectorField(file: \"ok.fga\", scale: 0.0)", "forces[0] (VectorField).scale"),
        (
            "VectorField(file: \"ok.fga\"), Gravity((0.0, -1.0, 0.0)), VectorField(file: \"ok.fga\")",
            "forces[2] (VectorField): a second VectorField",
        ),
    ];
    for (field, expected) in cases {
        let source = effect(field);
        let text = compile_str(&source, &options)
            .unwrap_err()
            .render("swirl.ron", &source);
        assert!(
            text.contains(expected) && text.contains("swirl.ron:4:"),
            "{text}"
        );
    }
    let _ = std::fs::remove_file(
        std::env::temp_dir().join(format!("plume-vector-field-{}/4gb.fga", std::process::id())),
    );
}
