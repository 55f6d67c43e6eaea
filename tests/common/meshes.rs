//! Meshes for the mesh tests, written as OBJ text into a folder of the test process's own.

use std::path::PathBuf;

/// The folder the meshes are written to (one per test process).
pub fn dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-test-meshes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` as `name` in the tests' folder and returns its path as the effect names it.
pub fn write(name: &str, text: &str) -> String {
    let path = dir().join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// An axis-aligned box as OBJ (8 corners, 6 quads).
pub fn box_obj(min: [f64; 3], max: [f64; 3]) -> String {
    let mut s = String::new();
    for k in 0..8 {
        let c = |axis: usize| {
            if k >> axis & 1 == 1 {
                max[axis]
            } else {
                min[axis]
            }
        };
        s += &format!("v {} {} {}\n", c(0), c(1), c(2));
    }
    // Corner k has x from bit 0, y from bit 1, z from bit 2 (1-based in the faces).
    s += "f 1 3 4 2\nf 5 6 8 7\nf 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 3 7 8 4\n";
    s
}

/// A unit sphere as OBJ: poles and `rings` rings of `segments` corners.
pub fn sphere_obj(rings: usize, segments: usize) -> String {
    let mut s = String::from("o ball\nv 0 1 0\n");
    for r in 1..=rings {
        let theta = std::f64::consts::PI * r as f64 / (rings + 1) as f64;
        for k in 0..segments {
            let phi = std::f64::consts::TAU * k as f64 / segments as f64;
            s += &format!(
                "v {} {} {}\n",
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin()
            );
        }
    }
    s += "v 0 -1 0\n";
    let at = |r: usize, k: usize| 2 + (r - 1) * segments + k % segments;
    let bottom = 2 + rings * segments;
    for k in 0..segments {
        s += &format!("f 1 {} {}\n", at(1, k + 1), at(1, k));
        for r in 1..rings {
            s += &format!(
                "f {} {} {} {}\n",
                at(r, k),
                at(r, k + 1),
                at(r + 1, k + 1),
                at(r + 1, k)
            );
        }
        s += &format!("f {bottom} {} {}\n", at(rings, k), at(rings, k + 1));
    }
    s
}
