//! `plume render --draw`: `auto` (the default) says which renderer it took and why (on a CPU
//! adapter, llvmpipe here, the raster pipeline), and `compute` is the splat's other name.

use std::path::Path;
use std::process::Command;

fn render(args: &[&str], out: &Path) -> (bool, String) {
    let effect = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../effects/fountain.ron");
    let output = Command::new(env!("CARGO_BIN_EXE_plume"))
        .arg("render")
        .arg(effect)
        .args(["--frames", "2", "--size", "64x36", "--out"])
        .arg(out)
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs");
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn auto_says_which_renderer_it_took_and_compute_names_the_splat() {
    let out = std::env::temp_dir().join(format!("plume-render-draw-{}.png", std::process::id()));
    let (ok, err) = render(&[], &out);
    assert!(ok, "{err}");
    let cpu = err.contains("Cpu");
    assert!(cpu, "these tests run on a CPU adapter: {err}");
    assert!(
        err.contains(
            "draw: the raster pipeline (auto: a CPU adapter rasterises faster than it splats)"
        ),
        "{err}"
    );
    let (ok, err) = render(&["--draw", "compute"], &out);
    assert!(ok, "{err}");
    assert!(err.contains("draw: the compute splat (as asked)"), "{err}");
    assert!(image::open(&out).is_ok(), "a PNG");
    std::fs::remove_file(&out).ok();
}
