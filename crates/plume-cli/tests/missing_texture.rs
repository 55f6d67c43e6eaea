//! A sprite texture is needed only where something is drawn: `plume run`, and `plume bench`
//! without `--render`, step an effect whose texture file is missing; `plume render` and
//! `plume bench --render` refuse it with the file and the field, located in the effect file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn plume(args: &[&str], file: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plume"))
        .args(args)
        .arg(file)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs")
}

/// smoke.ron (a 4 x 4 flipbook played over life) copied into a directory without its texture.
fn smoke_without_texture(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "plume-missing-texture-{tag}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("smoke.ron");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../effects/smoke.ron"),
        &file,
    )
    .unwrap();
    assert!(!dir.join("textures/smoke.png").exists());
    file
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn run_and_bench_step_an_effect_whose_texture_is_missing() {
    let file = smoke_without_texture("step");
    let run = plume(&["run", "--steps", "20"], &file);
    assert!(run.status.success(), "plume run: {}", stderr(&run));
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains("alive"), "plume run's summary: {summary}");
    let bench = plume(&["bench", "--particles", "2000", "--steps", "3"], &file);
    assert!(bench.status.success(), "plume bench: {}", stderr(&bench));
    std::fs::remove_dir_all(file.parent().unwrap()).ok();
}

#[test]
fn drawing_an_effect_whose_texture_is_missing_names_the_file_and_the_field() {
    let file = smoke_without_texture("draw");
    let png = file.with_extension("png");
    let png_arg = png.to_str().unwrap().to_owned();
    for args in [
        vec!["render", "--out", &png_arg],
        vec![
            "bench",
            "--particles",
            "2000",
            "--steps",
            "3",
            "--render",
            "64x64",
        ],
    ] {
        let out = plume(&args, &file);
        let err = stderr(&out);
        assert!(
            !out.status.success(),
            "plume {args:?} drew without its texture"
        );
        assert!(
            err.contains("smoke.ron:30:37: error: render.texture.file: cannot open texture")
                && err.contains("textures/smoke.png")
                && err.contains('^'),
            "plume {args:?}: {err}"
        );
        assert!(!png.exists(), "nothing is written");
    }
    std::fs::remove_dir_all(file.parent().unwrap()).ok();
}
