//! `plume render --draw`: `auto` (the default) says which renderer it took and why (on a CPU
//! adapter, llvmpipe here, the raster pipeline), `compute` takes the compute renderer, and over
//! the meshes an effect names the compute renderer tests their depth (the embedding API's compute
//! renderer) and draws the raster image.

mod common;

use std::path::Path;
use std::process::Command;

fn render(args: &[&str], out: &Path) -> (bool, String) {
    let mut all = vec!["--frames", "2", "--size", "64x36"];
    all.extend_from_slice(args);
    render_effect("fountain", &all, out)
}

/// `plume render effects/NAME.ron ARGS --out OUT`: whether it succeeded, and what it wrote
/// to stderr.
fn render_effect(name: &str, args: &[&str], out: &Path) -> (bool, String) {
    let effect = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../effects/{name}.ron"));
    let output = Command::new(env!("CARGO_BIN_EXE_plume"))
        .arg("render")
        .arg(effect)
        .args(args)
        .arg("--out")
        .arg(out)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs");
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn auto_says_which_renderer_it_took_and_compute_takes_the_compute_renderer() {
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
    assert!(
        err.contains("draw: the compute renderer (as asked)"),
        "{err}"
    );
    assert!(image::open(&out).is_ok(), "a PNG");
    std::fs::remove_file(&out).ok();
}

#[test]
fn over_the_scene_s_meshes_the_compute_renderer_draws_the_raster_image() {
    // crystal.ron names a mesh (a collider) that `plume render` draws around the particles:
    // the compute renderer now draws over it too, tested against its depth.
    let paths = common::image_pair("crystal");
    let args = |draw| {
        [
            "--draw", draw, "--size", "160x90", "--frames", "1", "--every", "40",
        ]
    };
    let (ok, err) = render_effect("crystal", &args("raster"), &paths.0);
    assert!(ok, "{err}");
    let (ok, err) = render_effect("crystal", &args("compute"), &paths.1);
    assert!(ok, "{err}");
    assert!(err.contains("scene:"), "the meshes are drawn: {err}");
    let (a, b) = common::take_images(&paths);
    // The same meshes; the particles in front of them and not behind: a raster draw rounds
    // after every blend and snaps edges, the compute renderer blends once at pixel centres (tests/embed.rs
    // in the facade measures the same gap on five effects), so the mean stays small.
    let diff = common::mean_difference(&a, &b);
    assert!(diff < 1.0, "mean difference {diff:.3} of 255");
    // The mesh is shaded grey (channels within a few steps; the sparks are gold).
    let grey = |p: &image::Rgba<u8>| {
        p.0[0] > 40 && p.0[0].abs_diff(p.0[1]) <= 4 && p.0[1].abs_diff(p.0[2]) <= 4
    };
    let mesh_grey = b.pixels().filter(|p| grey(p)).count();
    assert!(
        mesh_grey > 100,
        "only {mesh_grey} grey mesh pixels under the compute renderer"
    );
}
