//! `plume run --bounds`: the box of every live particle at the end of every step, printed as a
//! `bounds:` line to paste into the file, the same (to the centimetre it rounds to) from the GPU
//! and from the f64 reference; and in the JSON.

use std::path::PathBuf;
use std::process::Command;

const EFFECT: &str = r#"Effect(
    name: "jet",
    capacity: 400,
    seed: 4,
    emitters: [Emitter(rate: 300.0, shape: Point((1.0, 0.5, 0.0)),
                       velocity: Cone(axis: (1.0, 1.0, 0.0), angle: 10.0, speed: (3.0, 4.0)),
                       lifetime: Some((1.0, 1.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    state: Stateful,
)"#;

fn effect_file() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-run-bounds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("jet.ron");
    std::fs::write(&file, EFFECT).unwrap();
    file
}

/// The six numbers of the printed `bounds:` line.
fn printed_bounds(extra: &[&str]) -> Vec<f64> {
    let out = Command::new(env!("CARGO_BIN_EXE_plume"))
        .args(["run", "--steps", "90", "--bounds"])
        .args(extra)
        .arg(effect_file())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("bounds: Some(Bounds(min: ("))
        .unwrap_or_else(|| panic!("{stdout}"));
    line.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
        .filter_map(|t| t.parse().ok())
        .collect()
}

#[test]
fn the_bounds_line_holds_the_jet_and_agrees_with_the_reference() {
    let gpu = printed_bounds(&[]);
    let cpu = printed_bounds(&["--cpu-reference"]);
    assert_eq!(gpu.len(), 6, "{gpu:?}");
    // The jet starts at (1, 0.5, 0) and flies up and along +x at 2-3 m/s each way, falling
    // back below its start within its one-second life. The box is taken at the end of each
    // step, so it starts a step's flight (3-5 cm) past x = 1.
    let (min, max) = (&gpu[..3], &gpu[3..]);
    assert!(min[0] > 1.0 && min[0] < 1.1 && max[0] > 3.0, "{gpu:?}");
    assert!(min[1] < 0.5 && max[1] > 0.9, "{gpu:?}");
    assert!(min[2] < 0.0 && max[2] > 0.0, "{gpu:?}");
    // Rounded outward to the centimetre: f32 and f64 land on the same side but for a corner
    // within rounding of a centimetre's edge.
    for (g, c) in gpu.iter().zip(&cpu) {
        assert!((g - c).abs() <= 0.0100001, "gpu {gpu:?} cpu {cpu:?}");
    }
}

#[test]
fn the_json_carries_the_measured_box() {
    let out = Command::new(env!("CARGO_BIN_EXE_plume"))
        .args(["run", "--steps", "30", "--bounds", "--json"])
        .arg(effect_file())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs");
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let (min, max) = (&v["live_bounds"]["min"], &v["live_bounds"]["max"]);
    for k in 0..3 {
        assert!(min[k].as_f64().unwrap() <= max[k].as_f64().unwrap(), "{v}");
    }
    // Every particle the run ends with lies in the box.
    let bmin = &v["bbox_min"];
    let bmax = &v["bbox_max"];
    for k in 0..3 {
        assert!(
            min[k].as_f64().unwrap() <= bmin[k].as_f64().unwrap() + 1e-6,
            "{v}"
        );
        assert!(
            max[k].as_f64().unwrap() >= bmax[k].as_f64().unwrap() - 1e-6,
            "{v}"
        );
    }
}
