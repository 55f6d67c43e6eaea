//! The compute renderer at the adapter's limits: a tile list that grows past the largest buffer
//! a binding may hold is a clear error that says what to do instead, not a wgpu validation
//! failure.

mod common;

use common::*;
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::{Camera, Effect};

#[test]
fn a_tile_list_past_the_binding_limit_is_an_error() {
    // 4,096 sprites 6 m across on a 480x270 image need some 800,000 (tile, sprite) entries, 3
    // MB a list. On a device whose largest binding is 1.5 MB (the image's 1 MB still fits),
    // growing the list past it fails with a message that names the limit and the way out,
    // where wgpu would have failed validation.
    let mut small = gpu().clone();
    small.limits.max_storage_buffer_binding_size = 1_500_000;
    let src = r#"Effect(
    name: "wall",
    capacity: 4096,
    emitters: [Emitter(burst: 4096, shape: Box(min: (-0.5, -0.45, 0.0), max: (0.5, 0.45, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (1.0, 2.0, 10.0), target: (0.0, 0.5, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (0.9, 0.5, 0.2, 0.3))], size: [(0.0, 6.0)], background: (0.0, 0.0, 0.0)),
)"#;
    let mut sim = Effect::new(&small, compile(src)).unwrap();
    sim.run(1, |_| {}).unwrap();
    let (w, h) = (480, 270);
    let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
    let error = splat.render(&sim, &camera).unwrap_err().to_string();
    assert!(
        error.contains("tile lists need")
            && error.contains("1500000-byte binding limit")
            && error.contains("raster pipeline"),
        "{error}"
    );
}
