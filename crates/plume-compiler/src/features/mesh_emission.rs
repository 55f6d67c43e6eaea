//! Spawning on a mesh's surface: `shape: Mesh(file: "rock.obj", offset, scale, rotation)`,
//! uniform by area, with the surface's normal for `velocity: Normal(speed: ..)`; or in its
//! volume, `volume: true`.
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
//!
//! **Volume.** The closed mesh is baked into its signed distance field ([`crate::base::sdf`],
//! cached as the collider's is), and the field's cells whose centre is inside (the mean of
//! their eight corners below zero) are listed at compile time. A particle picks one of them
//! with one 32-bit draw (r mod n, whose bias is below n / 2³²) and a uniform point in it. The
//! decision what is inside is made once, on the CPU, so the GPU and the reference spawn at the
//! same point to a few ulps; the price is that the volume is the mesh's to within half a cell
//! (`resolution`). `spawn_data` then holds the cells' indices.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::base::mesh::{read_mesh, rotation_degrees};
use crate::base::sdf::{read_and_bake, Sdf};
use crate::base::values::Vec3;
use crate::base::writer::{u32_lit, vec3_lit, Writer};

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
    /// With `volume: true`: the inside cells to spawn in instead of the surface.
    pub(crate) volume: Option<VolumeCells>,
}

/// The cells of a mesh's field whose centre is inside it, placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct VolumeCells {
    /// Each inside cell's index, (k · cy + j) · cx + i.
    pub cells: Vec<u32>,
    /// Cells along x, y and z.
    pub counts: [u32; 3],
    /// The world position of the field's first node.
    pub origin: DVec3,
    /// One cell's edges along the field's x, y and z, in the world.
    pub edges: [DVec3; 3],
}

impl VolumeCells {
    /// The field `sdf`'s inside cells, placed by `world` (a point map) and `linear` (its
    /// linear part).
    fn new(sdf: &Sdf, world: impl Fn(DVec3) -> DVec3, linear: impl Fn(DVec3) -> DVec3) -> Self {
        let [nx, ny, nz] = sdf.counts.map(|c| c as usize);
        let counts = [nx - 1, ny - 1, nz - 1];
        let at = |i: usize, j: usize, k: usize| f64::from(sdf.values[(k * ny + j) * nx + i]);
        let mut cells = Vec::new();
        for k in 0..counts[2] {
            for j in 0..counts[1] {
                for i in 0..counts[0] {
                    let mut sum = 0.0;
                    for c in 0..8 {
                        sum += at(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2));
                    }
                    if sum < 0.0 {
                        cells.push(((k * counts[1] + j) * counts[0] + i) as u32);
                    }
                }
            }
        }
        Self {
            cells,
            counts: counts.map(|c| c as u32),
            origin: world(sdf.min),
            edges: [DVec3::X, DVec3::Y, DVec3::Z].map(|e| linear(e * sdf.cell)),
        }
    }

    /// The point for a cell draw `r` and three unit draws (the f64 twin).
    pub(crate) fn point(&self, r: u32, u: DVec3) -> DVec3 {
        let c = self.cells[(r % self.cells.len() as u32) as usize];
        let [cx, cy, _] = self.counts;
        let (i, j, k) = (c % cx, (c / cx) % cy, c / (cx * cy));
        self.origin
            + (f64::from(i) + u.x) * self.edges[0]
            + (f64::from(j) + u.y) * self.edges[1]
            + (f64::from(k) + u.z) * self.edges[2]
    }
}

/// Reads the mesh at `file` (relative to `base_dir`) and places it; with `volume`, the
/// resolution of the field whose inside cells it spawns in (the mesh must then be closed).
pub(crate) fn place(
    file: &str,
    base_dir: Option<&Path>,
    (offset, scale, rotation): (Vec3, f64, Vec3),
    volume: Option<u32>,
) -> Result<MeshSurface, String> {
    let path = base_dir.map_or_else(|| PathBuf::from(file), |dir| dir.join(file));
    let r = rotation_degrees(rotation.d());
    let world = |p: DVec3| offset.d() + scale * (r * p);
    let (mesh, cells) = match volume {
        Some(resolution) => {
            let (sdf, mesh) = read_and_bake(&path, resolution)?;
            let cells = VolumeCells::new(&sdf, world, |v| scale * (r * v));
            if cells.cells.is_empty() {
                return Err(format!(
                    "mesh `{}` holds no cell of its field at resolution {resolution} (no cell's centre is inside): raise `resolution`",
                    path.display()
                ));
            }
            (mesh, Some(cells))
        }
        None => (read_mesh(&path)?.0, None),
    };
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    let (mut total, mut center, mut extent) = (0.0, DVec3::ZERO, 0.0_f64);
    for [a, b, c] in mesh.placed_triangles(offset.d(), scale, r) {
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
        volume: cells,
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

    /// The spawn point and the surface's normal there (zero in a volume) for a pick draw `r`
    /// and three unit draws (the f64 twin of the WGSL).
    pub fn spawn(&self, r: u32, u: DVec3) -> (DVec3, DVec3) {
        match &self.volume {
            Some(cells) => (cells.point(r, u), DVec3::ZERO),
            None => self.sample(r, u.x, u.y),
        }
    }

    /// The point and normal for a triangle draw `r` and two unit draws.
    pub fn sample(&self, r: u32, r1: f64, r2: f64) -> (DVec3, DVec3) {
        let [a, e1, e2, n] =
            self.triangles[self.pick(r)].map(|v| DVec3::from_array(v.map(f64::from)));
        let s = r1.sqrt();
        (a + s * (1.0 - r2) * e1 + s * r2 * e2, n)
    }

    /// The triangles as placed (from the f32 values the GPU holds).
    pub(crate) fn world_triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.triangles.iter().map(|t| {
            let [a, e1, e2, _] = t.map(|v| DVec3::from_array(v.map(f64::from)));
            [a, a + e1, a + e2]
        })
    }

    /// Binary search rounds that always finish the search.
    fn rounds(&self) -> u32 {
        usize::BITS - self.thresholds.len().leading_zeros() + 1
    }

    /// The values this shape puts in `spawn_data`: a volume's cells, or the surface's
    /// thresholds and triangles.
    pub fn data(&self) -> Vec<u32> {
        match &self.volume {
            Some(v) => v.cells.clone(),
            None => self
                .thresholds
                .iter()
                .copied()
                .chain(
                    self.triangles
                        .iter()
                        .flat_map(|t| t.iter().flat_map(|v| v.map(f32::to_bits))),
                )
                .collect(),
        }
    }

    /// How many u32 values [`MeshSurface::data`] gives.
    pub(crate) fn data_len(&self) -> u32 {
        match &self.volume {
            Some(v) => v.cells.len() as u32,
            None => (self.thresholds.len() * 13) as u32,
        }
    }

    /// Emits `fn mesh_spawn_{e}(r: u32, u: vec3<f32>) -> array<vec3<f32>, 2>` (point,
    /// normal), reading the surface (or the volume's cells) from `spawn_data` at `offset`.
    pub fn emit(&self, w: &mut Writer, e: usize, offset: u32) {
        if let Some(v) = &self.volume {
            let [cx, cy, _] = v.counts;
            w.comment(format!(
                "Emitter {e} spawns in mesh `{}` ({} field cells inside).",
                self.file,
                v.cells.len()
            ));
            w.block(
                format!("fn mesh_spawn_{e}(r: u32, u: vec3<f32>) -> array<vec3<f32>, 2>"),
                |w| {
                    w.line(format!(
                        "let c = spawn_data[{} + r % {}];",
                        u32_lit(offset),
                        u32_lit(v.cells.len() as u32)
                    ));
                    w.line(format!(
                        "let cell = vec3<f32>(vec3<u32>(c % {cx}u, (c / {cx}u) % {cy}u, c / {})) + u;",
                        u32_lit(cx * cy)
                    ));
                    w.line(format!(
                        "let x = {} + cell.x * {} + cell.y * {} + cell.z * {};",
                        vec3_lit(v.origin),
                        vec3_lit(v.edges[0]),
                        vec3_lit(v.edges[1]),
                        vec3_lit(v.edges[2])
                    ));
                    w.line("return array<vec3<f32>, 2>(x, vec3<f32>(0.0));");
                },
            );
            return;
        }
        let n = self.thresholds.len() as u32;
        let tri = offset + n;
        w.comment(format!(
            "Emitter {e} spawns on mesh `{}` ({n} triangles): pick by area, then a uniform point.",
            self.file
        ));
        w.block(
            format!("fn mesh_spawn_{e}(r: u32, u: vec3<f32>) -> array<vec3<f32>, 2>"),
            |w| {
                w.line("let r1 = u.x;");
                w.line("let r2 = u.y;");
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
