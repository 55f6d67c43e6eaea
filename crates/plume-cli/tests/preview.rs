//! `plume preview` in a real window: under Xvfb (Debian's `xvfb`, with Mesa's llvmpipe) the
//! scripted mode draws 30 frames of the fountain and writes a non-blank screenshot; with no
//! display at all it fails with a message that says so and suggests `plume render`. These tests
//! never skip: without `xvfb-run` they fail with how to install it (`.ci/run` installs it).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn plume() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plume"))
}

fn effect(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../effects")
        .join(name)
}

/// `xvfb-run`, or a failure that says how to get it.
fn xvfb_run() -> Command {
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    assert!(
        found,
        "xvfb-run was not found: the preview's window test needs a virtual display. \
         Install it with `apt-get install xvfb` (Debian/Ubuntu); .ci/run installs it when it is missing"
    );
    let mut c = Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 1280x720x24"]);
    c
}

#[test]
fn preview_draws_frames_in_a_window_and_writes_the_last_one() {
    let out = std::env::temp_dir().join(format!("plume-preview-{}.png", std::process::id()));
    let status = xvfb_run()
        .arg(env!("CARGO_BIN_EXE_plume"))
        .arg("preview")
        .arg(effect("fountain.ron"))
        .args(["--frames", "30", "--screenshot"])
        .arg(&out)
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(status.status.success(), "preview failed: {stderr}");
    assert!(stderr.contains("(30 frames)"), "{stderr}");
    let img = image::open(&out).expect("a PNG").to_rgba8();
    std::fs::remove_file(&out).ok();
    assert_eq!(img.dimensions(), (1280, 720), "the window's size");
    // The fountain after 30 steps: a spray of bright blue drops on the dark background.
    let bg = *img.get_pixel(0, 0);
    let lit = img
        .pixels()
        .filter(|p| p.0.iter().zip(bg.0).any(|(a, b)| a.abs_diff(b) > 40))
        .count();
    assert!(lit > 1000, "only {lit} pixels differ from the background");
}

#[test]
fn without_a_display_preview_says_so_and_suggests_render() {
    let out = plume()
        .arg("preview")
        .arg(effect("sparks.ron"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("plume runs");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no display"), "{stderr}");
    assert!(stderr.contains("plume render"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_file_with_errors_fails_to_open_with_located_diagnostics() {
    let dir = std::env::temp_dir().join(format!("plume-preview-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.ron");
    std::fs::write(&bad, "Effect(name: \"x\", capacity: 0)").unwrap();
    let out = xvfb_run()
        .arg(env!("CARGO_BIN_EXE_plume"))
        .arg("preview")
        .arg(&bad)
        .args(["--frames", "1"])
        .output()
        .expect("xvfb-run runs");
    std::fs::remove_dir_all(&dir).ok();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.ron:1:"), "located: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `plume render`'s 480x270 frame of step 24 of `file`, written to `out`.
/// `plume preview FILE --size 480x270 --frames FRAMES --screenshot OUT` under a virtual
/// display; fails the test with the preview's output if it fails.
fn preview_screenshot(file: &Path, frames: u32, out: &Path) {
    preview_screenshot_drawn(file, frames, out, "auto");
}

/// [`preview_screenshot`] with `--draw DRAW`; returns what the preview wrote to stderr.
fn preview_screenshot_drawn(file: &Path, frames: u32, out: &Path, draw: &str) -> String {
    let run = xvfb_run()
        .arg(env!("CARGO_BIN_EXE_plume"))
        .arg("preview")
        .arg(file)
        .args([
            "--size",
            "480x270",
            "--frames",
            &frames.to_string(),
            "--draw",
            draw,
            "--screenshot",
        ])
        .arg(out)
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(run.status.success(), "{stderr}");
    stderr
}

/// The largest difference of any channel of any pixel of two images of one size.
fn max_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> u8 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

fn render_step_24(file: &Path, out: &Path) {
    let run = plume()
        .arg("render")
        .arg(file)
        .args([
            "--frames", "1", "--every", "24", "--size", "480x270", "--out",
        ])
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
}

#[test]
fn a_glowing_effect_glows_in_the_preview_as_in_plume_render() {
    // sparks.ron has render.glow: after 24 steps the preview's screenshot (one step a frame)
    // and plume render's frame of step 24 are the same bloomed image.
    let dir = std::env::temp_dir().join(format!("plume-preview-glow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (shot, still) = (dir.join("preview.png"), dir.join("render.png"));
    preview_screenshot(&effect("sparks.ron"), 24, &shot);
    render_step_24(&effect("sparks.ron"), &still);
    // The same sparks without their glow, for comparison.
    let source = std::fs::read_to_string(effect("sparks.ron")).unwrap();
    let plain_source: String = source
        .lines()
        .filter(|l| !l.contains("glow: Some"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(plain_source.len(), source.len(), "sparks.ron glows");
    let (plain_file, plain) = (dir.join("plain.ron"), dir.join("plain.png"));
    std::fs::write(&plain_file, plain_source).unwrap();
    render_step_24(&plain_file, &plain);
    let a = image::open(&shot).unwrap().to_rgba8();
    let b = image::open(&still).unwrap().to_rgba8();
    let c = image::open(&plain).unwrap().to_rgba8();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(a.dimensions(), b.dimensions());
    let max = max_difference(&a, &b);
    assert!(max <= 1, "preview and render differ by up to {max}");
    // And the glow is there: light spills past the sparks onto pixels the plain draw leaves
    // dark, and the image is brighter overall.
    let lit = |img: &image::RgbaImage| img.pixels().filter(|p| p[0] > 8).count();
    let sum = |img: &image::RgbaImage| img.as_raw().iter().map(|&x| u64::from(x)).sum::<u64>();
    assert!(
        lit(&a) > lit(&c) * 11 / 10,
        "lit pixels: {} glowing, {} plain",
        lit(&a),
        lit(&c)
    );
    assert!(sum(&a) > sum(&c), "the glowing image is brighter");
}

#[test]
fn an_effect_with_groups_previews_as_plume_render_draws_it() {
    // Shells that burst into sparks: after 24 steps both groups are on screen, and the
    // preview's screenshot (one step a frame) is plume render's frame of step 24.
    let dir = std::env::temp_dir().join(format!("plume-preview-groups-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("shells.ron");
    std::fs::write(
        &file,
        r#"Effect(
    name: "shells",
    capacity: 64,
    emitters: [Emitter(burst: 3, rate: 30.0, shape: Sphere(center: (0.0, 0.5, 0.0), radius: 1.0),
                       velocity: Constant((0.0, 3.0, 0.0)), lifetime: Some((0.15, 0.25)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    camera: Camera(eye: (0.0, 1.0, 6.0), target: (0.0, 1.0, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.15)], blend: Additive),
    events: [Event(on: Death, target: "sparks", count: 40, velocity: Radial(speed: (1.0, 2.0)),
                   lifetime: Some((0.5, 0.8)))],
    groups: [Group(name: "sparks", capacity: 4000, forces: [Gravity((0.0, -9.81, 0.0))],
                   render: Render(color: [(0.0, (1.0, 0.6, 0.2, 1.0))], size: [(0.0, 0.06)], blend: Additive))],
)"#,
    )
    .unwrap();
    let (shot, still) = (dir.join("preview.png"), dir.join("render.png"));
    let out = xvfb_run()
        .arg(env!("CARGO_BIN_EXE_plume"))
        .arg("preview")
        .arg(&file)
        .args(["--size", "480x270", "--frames", "24", "--screenshot"])
        .arg(&shot)
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    render_step_24(&file, &still);
    let a = image::open(&shot).unwrap().to_rgba8();
    let b = image::open(&still).unwrap().to_rgba8();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(a.dimensions(), b.dimensions());
    let max = max_difference(&a, &b);
    assert!(max <= 1, "preview and render differ by up to {max}");
    // Both groups show: white shells and orange sparks.
    let white = a.pixels().filter(|p| p[0] > 200 && p[2] > 200).count();
    let orange = a.pixels().filter(|p| p[0] > 100 && p[2] < p[0] / 2).count();
    assert!(white > 10 && orange > 10, "white {white}, orange {orange}");
}

#[test]
fn the_meshes_an_effect_names_are_drawn_in_the_preview_as_in_plume_render() {
    // crystal.ron names two meshes (a spawn shape and a collider): both draw them around the
    // particles, the same image, and `plume render --no-scene` leaves them out.
    let dir = std::env::temp_dir().join(format!("plume-preview-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (shot, still, bare) = (
        dir.join("preview.png"),
        dir.join("render.png"),
        dir.join("bare.png"),
    );
    preview_screenshot(&effect("crystal.ron"), 24, &shot);
    render_step_24(&effect("crystal.ron"), &still);
    let run = plume()
        .arg("render")
        .arg(effect("crystal.ron"))
        .args([
            "--frames",
            "1",
            "--every",
            "24",
            "--size",
            "480x270",
            "--no-scene",
            "--out",
        ])
        .arg(&bare)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let a = image::open(&shot).unwrap().to_rgba8();
    let b = image::open(&still).unwrap().to_rgba8();
    let c = image::open(&bare).unwrap().to_rgba8();
    std::fs::remove_dir_all(&dir).ok();
    let max = max_difference(&a, &b);
    assert!(max <= 1, "preview and render differ by up to {max}");
    // The meshes' grey: pixels where red, green and blue are close and mid-bright. The sparks
    // make some too (white-hot when they leave the crystal, fading over black), but far fewer.
    let grey = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| {
                p[0] > 40 && p[0] < 200 && p[0].abs_diff(p[2]) < 20 && p[1].abs_diff(p[2]) < 20
            })
            .count()
    };
    assert!(
        grey(&b) > 3000,
        "only {} grey pixels with the scene",
        grey(&b)
    );
    assert!(
        grey(&c) < grey(&b) / 4,
        "{} grey pixels without the scene, {} with it",
        grey(&c),
        grey(&b)
    );
}

#[test]
fn a_scene_depth_collider_meets_the_preview_s_scene_as_it_meets_plume_render_s() {
    // steps.ron's sparks meet the steps only through the depth the scene leaves: the preview
    // gives them the last frame's depth, render draws it before the first step; the sparks
    // reach the steps after about 30 steps, so at step 60 both must be the same image.
    let dir = std::env::temp_dir().join(format!("plume-preview-depth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (shot, still, bare) = (
        dir.join("preview.png"),
        dir.join("render.png"),
        dir.join("bare.png"),
    );
    preview_screenshot(&effect("steps.ron"), 60, &shot);
    for (path, extra) in [(&still, None), (&bare, Some("--no-scene"))] {
        let mut render = plume();
        render
            .arg("render")
            .arg(effect("steps.ron"))
            .args(["--frames", "1", "--every", "60", "--size", "480x270"]);
        if let Some(flag) = extra {
            render.arg(flag);
        }
        let run = render.arg("--out").arg(path).output().unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{stderr}");
        if extra.is_some() {
            assert!(stderr.contains("meets nothing"), "{stderr}");
        }
    }
    let a = image::open(&shot).unwrap().to_rgba8();
    let b = image::open(&still).unwrap().to_rgba8();
    let c = image::open(&bare).unwrap().to_rgba8();
    std::fs::remove_dir_all(&dir).ok();
    let max = max_difference(&a, &b);
    assert!(max <= 1, "preview and render differ by up to {max}");
    // Without the scene the sparks fall through where the steps were: the spray below the top
    // tread differs in many pixels (the steps' grey aside, which --no-scene also leaves out).
    let bright = |img: &image::RgbaImage| img.pixels().filter(|p| p[0] > 200 && p[1] > 120).count();
    assert!(
        bright(&b) != bright(&c),
        "the sparks look the same with and without the steps: {}",
        bright(&b)
    );
}

#[test]
fn the_compute_renderer_previews_what_the_raster_one_does() {
    // crystal.ron: sprites over a mesh the preview draws; the compute renderer tests its depth.
    let paths = common::image_pair("preview");
    let said = preview_screenshot_drawn(&effect("crystal.ron"), 20, &paths.0, "raster");
    assert!(said.contains("drawn by raster (as asked)"), "{said}");
    let said = preview_screenshot_drawn(&effect("crystal.ron"), 20, &paths.1, "compute");
    assert!(said.contains("drawn by compute (as asked)"), "{said}");
    let (a, b) = common::take_images(&paths);
    // The raster draw rounds after every blend and snaps edges; the compute one blends once at
    // pixel centres: close on average (tests/embed.rs measures the gap per effect).
    let mean = common::mean_difference(&a, &b);
    assert!(mean < 1.0, "mean difference {mean:.3} of 255");
}
