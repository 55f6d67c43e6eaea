//! What the CLI's test files share: comparing two images a test drew both ways.

#![allow(dead_code)] // each test file uses its own part

use std::path::PathBuf;

/// Two temporary PNG paths for a test's two images of one thing, named after `what` and the
/// process (so parallel test binaries do not collide).
pub fn image_pair(what: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir();
    let pid = std::process::id();
    (
        dir.join(format!("plume-{what}-raster-{pid}.png")),
        dir.join(format!("plume-{what}-compute-{pid}.png")),
    )
}

/// Reads and deletes the two images at `paths`.
pub fn take_images(paths: &(PathBuf, PathBuf)) -> (image::RgbaImage, image::RgbaImage) {
    let read = |p: &PathBuf| {
        let img = image::open(p).expect("a PNG").to_rgba8();
        std::fs::remove_file(p).ok();
        img
    };
    (read(&paths.0), read(&paths.1))
}

/// The mean absolute difference of two images of one size, over every channel (0 to 255).
pub fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / a.as_raw().len() as f64
}
