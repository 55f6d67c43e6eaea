//! Spawning on a mesh's surface: `shape: Mesh(file: "rock.obj", offset, scale, rotation)`,
//! uniform by area, with the surface's normal for `velocity: Normal(speed: ..)`.
//!
//! The OBJ file is read once, at compile time (`base/mesh.rs`), and its triangles placed in
//! the world then (offset + scale · R p, in f64, stored as f32). A particle picks its triangle
//! with one 32-bit draw against the triangles' cumulative areas, held as 32-bit integer
//! thresholds (a binary search on integers, so the GPU and the f64 reference pick the very
//! same triangle), then a uniform point in it: p = a + √r₁ (1 − r₂) e₁ + √r₁ r₂ e₂. The normal
//! is the triangle's (e₁ × e₂, normalised): outward for a mesh wound counter-clockwise seen
//! from outside, as OBJ files are.
//!
//! On the GPU the thresholds and triangles live in the read-only `spawn_data` binding, as u32
//! (floats by their bits): per mesh emitter, n thresholds, then 12 values per triangle (a, e₁,
//! e₂, n).

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::base::mesh::{read_obj, rotation_degrees};
use crate::base::values::Vec3;
use crate::base::writer::{u32_lit, Writer};

/// A mesh's triangles placed in the world, ready to sample.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshSurface {
    /// The file as the effect names it.
    pub file: String,
    /// Triangle i is picked by a draw r when `thresholds[i - 1] <= r < thresholds[i]` (the
    /// last triangle also takes r = 2³² − 1).
    pub thresholds: Vec<u32>,
    /// Per triangle: a, e₁ = b − a, e₂ = c − a and the unit normal, as the GPU holds them.
    pub triangles: Vec<[[f32; 3]; 4]>,
    /// The area-weighted centre (radial velocities point away from it).
    pub center: DVec3,
    /// The largest coordinate magnitude of any corner.
    pub extent: f64,
    /// The surface's area (m²).
    pub area: f64,
}

/// Reads the mesh at `file` (relative to `base_dir`) and places it.
pub fn place(
    file: &str,
    base_dir: Option<&Path>,
    (offset, scale, rotation): (Vec3, f64, Vec3),
) -> Result<MeshSurface, String> {
    let path = base_dir.map_or_else(|| PathBuf::from(file), |dir| dir.join(file));
    let (mesh, _) = read_obj(&path)?;
    let r = rotation_degrees(rotation.d());
    let world = |p: DVec3| offset.d() + scale * (r * p);
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    let (mut total, mut center, mut extent) = (0.0, DVec3::ZERO, 0.0_f64);
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(t).map(world);
        let cross = (b - a).cross(c - a);
        let area = 0.5 * cross.length();
        let n = cross.normalize_or_zero();
        total += area;
        center += area * (a + b + c) / 3.0;
        extent = extent.max(a.abs().max(b.abs()).max(c.abs()).max_element());
        cumulative.push(total);
        let f = |v: DVec3| v.to_array().map(|x| x as f32);
        triangles.push([f(a), f(b - a), f(c - a), f(n)]);
    }
    if total <= 0.0 || !total.is_finite() {
        return Err(format!(
            "mesh `{}` has no area to spawn on (every triangle is degenerate)",
            path.display()
        ));
    }
    let mut thresholds: Vec<u32> = cumulative
        .iter()
        .map(|&c| ((c / total) * 4_294_967_296.0).floor().min(4_294_967_295.0) as u32)
        .collect();
    if let Some(last) = thresholds.last_mut() {
        *last = u32::MAX;
    }
    Ok(MeshSurface {
        file: file.to_string(),
        thresholds,
        triangles,
        center: center / total,
        extent,
        area: total,
    })
}

impl MeshSurface {
    /// The triangle a 32-bit draw picks (the WGSL twin's binary search).
    pub fn pick(&self, r: u32) -> usize {
        let (mut lo, mut hi) = (0usize, self.thresholds.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if r < self.thresholds[mid] {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    }

    /// The point and normal for a triangle draw `r` and two unit draws (the f64 twin).
    pub fn sample(&self, r: u32, r1: f64, r2: f64) -> (DVec3, DVec3) {
        let [a, e1, e2, n] =
            self.triangles[self.pick(r)].map(|v| DVec3::from_array(v.map(f64::from)));
        let s = r1.sqrt();
        (a + s * (1.0 - r2) * e1 + s * r2 * e2, n)
    }

    /// The triangles as placed (from the f32 values the GPU holds).
    pub fn world_triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.triangles.iter().map(|t| {
            let [a, e1, e2, _] = t.map(|v| DVec3::from_array(v.map(f64::from)));
            [a, a + e1, a + e2]
        })
    }

    /// Binary search rounds that always finish the search.
    fn rounds(&self) -> u32 {
        usize::BITS - self.thresholds.len().leading_zeros() + 1
    }

    /// The values this surface puts in `spawn_data`.
    pub fn data(&self) -> impl Iterator<Item = u32> + '_ {
        self.thresholds.iter().copied().chain(
            self.triangles
                .iter()
                .flat_map(|t| t.iter().flat_map(|v| v.map(f32::to_bits))),
        )
    }

    /// How many u32 values [`MeshSurface::data`] gives.
    pub fn data_len(&self) -> u32 {
        (self.thresholds.len() * 13) as u32
    }

    /// Emits `fn mesh_spawn_{e}(r: u32, r1: f32, r2: f32) -> array<vec3<f32>, 2>` (point,
    /// normal), reading the surface from `spawn_data` at `offset`.
    pub fn emit(&self, w: &mut Writer, e: usize, offset: u32) {
        let n = self.thresholds.len() as u32;
        let tri = offset + n;
        w.comment(format!(
            "Emitter {e} spawns on mesh `{}` ({n} triangles): pick by area, then a uniform point.",
            self.file
        ));
        w.block(
            format!("fn mesh_spawn_{e}(r: u32, r1: f32, r2: f32) -> array<vec3<f32>, 2>"),
            |w| {
                w.line("var lo = 0u;");
                w.line(format!("var hi = {}u;", n - 1));
                w.block(format!("for (var it = 0u; it < {}u; it++)", self.rounds()), |w| {
                    w.block("if (lo >= hi)", |w| w.line("break;"));
                    w.line("let mid = (lo + hi) / 2u;");
                    w.block(
                        format!("if (r < spawn_data[{} + mid])", u32_lit(offset)),
                        |w| w.line("hi = mid;"),
                    );
                    w.block("else", |w| w.line("lo = mid + 1u;"));
                });
                w.line(format!("let at = {} + lo * 12u;", u32_lit(tri)));
                w.line("var t: array<vec3<f32>, 4>;");
                w.block("for (var k = 0u; k < 4u; k++)", |w| {
                    w.line("t[k] = vec3<f32>(bitcast<f32>(spawn_data[at + 3u * k]), bitcast<f32>(spawn_data[at + 3u * k + 1u]), bitcast<f32>(spawn_data[at + 3u * k + 2u]));");
                });
                w.line("let s = sqrt(r1);");
                w.line("return array<vec3<f32>, 2>(t[0] + s * (1.0 - r2) * t[1] + s * r2 * t[2], t[3]);");
            },
        );
    }
}
