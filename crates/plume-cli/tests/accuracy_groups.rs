//! `plume accuracy` on an effect with groups: each group with emitters of its own measured as
//! it runs alone, and a group fed by events alone listed as not measured.

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
    assert_eq!(rows, 10, "two integrators at five steps each: {stdout}");
    assert!(
        stderr.contains("group \"splashes\": note: fed by events alone, no particles of its own: not measured alone"),
        "{stderr}"
    );
}
