//! `plume accuracy` on an effect with groups: each group with emitters of its own measured as
//! it runs alone, and a group fed by events alone measured on a stand-in: a burst of its
//! spawn rule where its parent first fires in f64.

use std::path::Path;
use std::process::Command;

#[test]
fn an_effect_with_groups_is_measured_group_by_group() {
    let effect = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../effects/rain.ron");
    let out = Command::new(env!("CARGO_BIN_EXE_plume"))
        .arg("accuracy")
        .arg(effect)
        .args(["--steps", "8", "--integrators", "SemiImplicitEuler,Rk4"])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("rain.ron group \"rain\" (alone: its events left out)"),
        "{stdout}"
    );
    let rows = stdout
        .lines()
        .filter(|l| l.starts_with("SemiImplicitEuler") || l.starts_with("Rk4"))
        .count();
    assert_eq!(
        rows, 20,
        "two integrators at five steps each, in each group: {stdout}"
    );
    // The splashes start where the first drop hits the ground plane (y = 0), thrown up.
    let header = stdout
        .lines()
        .find(|l| {
            l.contains("group \"splashes\" (fed by events: 256 particles of its spawn rule at (")
        })
        .unwrap_or_else(|| panic!("{stdout}"));
    let y: f64 = header
        .split(", ")
        .nth(1)
        .and_then(|y| y.parse().ok())
        .unwrap_or_else(|| panic!("{header}"));
    assert!(y.abs() < 0.01, "{header}");
    // Every splash is compared (256 of them), with the error falling as the steps shrink.
    let splash_rows: Vec<&str> = stdout
        .lines()
        .skip_while(|l| !l.contains("group \"splashes\""))
        .filter(|l| l.starts_with("SemiImplicitEuler"))
        .collect();
    assert_eq!(splash_rows.len(), 5, "{stdout}");
    for row in &splash_rows {
        assert!(
            row.trim_end().ends_with("256") || row.contains(" 256 "),
            "{row}"
        );
    }
}
