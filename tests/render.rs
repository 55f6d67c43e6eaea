//! Headless rendering on the GPU (llvmpipe in CI): sprites land where the camera projection
//! puts them, sorting changes overlapping alpha sprites exactly as blending predicts, and a
//! known effect matches its golden image within a tolerance.

mod common;

use common::*;
use glam::DVec3;
use plume::runtime::render::{project, sprites, Renderer};
use plume::runtime::GpuSim;

/// Renders `src` after `steps` steps at `w` x `h`.
fn render(src: &str, steps: u64, w: u32, h: u32) -> Vec<u8> {
    let e = compile(src);
    let gpu = gpu();
    let mut sim = GpuSim::new(&gpu, e.clone()).unwrap();
    sim.run(steps, |_| {}).unwrap();
    let r = Renderer::new(&gpu, w, h, e.ir.render.blend, e.ir.render.background).unwrap();
    r.draw(
        &sprites(
            &sim.records().unwrap(),
            &e.ir.render,
            &e.ir.camera,
            e.ir.sort,
        ),
        &e.ir.camera,
    )
    .unwrap()
}

fn pixel(img: &[u8], w: u32, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * w + x) * 4) as usize;
    [img[i], img[i + 1], img[i + 2], img[i + 3]]
}

/// Still particles at the given points, white and opaque, on black.
fn still_points(points: &str, extra: &str) -> String {
    format!(
        r#"Effect(
    name: "probe",
    capacity: 16,
    emitters: [Emitter(burst: 16, shape: Points([{points}]), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    {extra}
)"#
    )
}

#[test]
fn particles_appear_where_the_camera_projection_puts_them() {
    let points = [
        DVec3::new(-2.0, 1.0, 0.0),
        DVec3::new(1.5, -0.5, 2.0),
        DVec3::new(0.5, 1.2, -3.0),
    ];
    let list: Vec<String> = points
        .iter()
        .map(|p| format!("({:?}, {:?}, {:?})", p.x, p.y, p.z))
        .collect();
    let src = still_points(
        &list.join(", "),
        "render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.3)], background: (0.0, 0.0, 0.0)),",
    );
    let (w, h) = (320, 200);
    let img = render(&src, 1, w, h);
    let camera = compile(&src).ir.camera;
    for p in points {
        let (x, y) = project(&camera, w, h, p).expect("in front of the camera");
        let px = pixel(&img, w, x as u32, y as u32);
        assert!(
            px[0] > 200 && px[1] > 200 && px[2] > 200,
            "no sprite at {p:?} -> ({x}, {y}): {px:?}"
        );
    }
    // Background everywhere far from the sprites: the corners and the middle of the bottom edge.
    for (x, y) in [
        (0, 0),
        (w - 1, 0),
        (0, h - 1),
        (w - 1, h - 1),
        (w / 2, h - 2),
    ] {
        assert_eq!(
            pixel(&img, w, x, y),
            [0, 0, 0, 255],
            "background expected at ({x}, {y})"
        );
    }
}

#[test]
fn sorting_changes_overlapping_alpha_sprites_as_blending_predicts() {
    // Two big sprites with alpha 0.5 on the view axis, on black. Id 0 is near (z = 2) and lives
    // 100 s: after one step its life fraction is 1.7e-4, past the gradient's 1e-4 stop: blue.
    // Id 1 is far (z = -2) and immortal: life fraction 0: red.
    let src = |sort: bool| {
        format!(
            r#"Effect(
    name: "two",
    capacity: 2,
    emitters: [
        Emitter(burst: 1, shape: Point((0.0, 0.0, 2.0)), velocity: Constant((0.0, 0.0, 0.0)),
                lifetime: Some((100.0, 100.0))),
        Emitter(burst: 1, shape: Point((0.0, 0.0, -2.0)), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    sort: {sort},
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(
        color: [(0.0, (1.0, 0.0, 0.0, 0.5)), (0.0001, (0.0, 0.0, 1.0, 0.5))],
        size: [(0.0, 4.0)],
        background: (0.0, 0.0, 0.0),
    ),
)"#
        )
    };
    let (w, h) = (64, 64);
    let unsorted = pixel(&render(&src(false), 1, w, h), w, w / 2, h / 2);
    let sorted = pixel(&render(&src(true), 1, w, h), w, w / 2, h / 2);
    // Unsorted (id order): near blue first, then far red over it:
    //   blue over black = (0, 0, 0.5); red over that = (0.5, 0, 0.25).
    // Sorted (far first): red over black = (0.5, 0, 0); blue over that = (0.25, 0, 0.5).
    // The sprite falloff at the centre pixel is (1 - r²)² with r <= 1 px / 16 px: under 1/255
    // of change; 8-bit rounding of two blends adds at most 1 more.
    let close =
        |a: [u8; 4], b: [f64; 3]| (0..3).all(|i| (f64::from(a[i]) - b[i] * 255.0).abs() <= 3.0);
    assert!(
        close(unsorted, [0.5, 0.0, 0.25]),
        "unsorted centre pixel {unsorted:?}"
    );
    assert!(
        close(sorted, [0.25, 0.0, 0.5]),
        "sorted centre pixel {sorted:?}"
    );
}

#[test]
fn sparks_match_the_golden_image() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/golden/sparks-160x90-step20.png"
    );
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/sparks.ron"))
        .unwrap();
    let img = render(&src, 20, 160, 90);
    if std::env::var_os("PLUME_WRITE_GOLDEN").is_some() {
        image::save_buffer(path, &img, 160, 90, image::ExtendedColorType::Rgba8).unwrap();
    }
    let golden = image::open(path)
        .expect("golden image")
        .to_rgba8()
        .into_raw();
    assert_eq!(golden.len(), img.len());
    // Different drivers rasterise sprite edges and round blends differently: allow a small mean
    // difference and a few pixels that differ more, but not a different picture.
    let diffs: Vec<f64> = golden
        .iter()
        .zip(&img)
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).abs())
        .collect();
    let mean = diffs.iter().sum::<f64>() / diffs.len() as f64;
    let large = diffs.iter().filter(|&&d| d > 24.0).count();
    assert!(
        mean < 1.5,
        "mean channel difference {mean} from the golden image"
    );
    assert!(
        large < diffs.len() / 200,
        "{large} channels differ by more than 24"
    );
    // And the picture is not empty: sparks are there.
    assert!(img.chunks(4).filter(|p| p[0] > 60).count() > 50);
}
