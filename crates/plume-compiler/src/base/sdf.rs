//! Signed distance fields baked from closed triangle meshes, for the `Mesh` collider and for
//! spawning in a mesh's volume.
//!
//! **Grid.** Nodes sit `cell` apart on a box around the mesh, padded by `PAD` cells on every
//! side (so every border node is outside, at a distance of at least `PAD` cells); `cell` is the
//! mesh's longest side over the resolution. Each node holds the signed distance (negative
//! inside) from its position to the mesh, as f32: the values the GPU and the f64 reference both
//! interpolate, trilinearly.
//!
//! **Bake** (Bridson's method, on the CPU, in f64): exact point-triangle distances for the
//! nodes within one cell of each triangle's box, then sweeps in the 8 diagonal orders that
//! hand each node its neighbours' nearest triangle when that one is nearer (two rounds), so
//! every node holds the distance to a triangle, almost always the nearest. The sign comes
//! from counting crossings along x: for each row of nodes, each triangle the row's line passes
//! through is a crossing, and a node past an odd number of them is inside. A line through a
//! shared edge or corner is counted once (a fill rule on exactly antisymmetric edge functions).
//!
//! **Cache.** Baking costs a distance per node and triangle nearby, seconds for big meshes in
//! a debug build, so the field is kept next to the mesh (`rock.obj.plume-sdf`), keyed on a
//! hash of the mesh file's bytes, the resolution and the baker's version: editing the mesh
//! (or the resolution) bakes it again. A cache that cannot be written is not an error (the
//! field is baked again next time).

use std::path::Path;

use glam::DVec3;

use crate::base::mesh::{fnv1a, read_mesh, TriMesh, FNV_OFFSET};

/// Cells of padding around the mesh's box.
pub(crate) const PAD: u32 = 3;

/// The most cells along a mesh's longest side.
pub(crate) const MAX_RESOLUTION: u32 = 128;

/// Bumped whenever the baker's output changes, so that old caches are baked again.
const BAKE_VERSION: u32 = 1;

const MAGIC: &[u8; 8] = b"PLUMESDF";

/// A baked field: nodes, their box and their signed distances.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Sdf {
    /// Nodes along x, y and z.
    pub counts: [u32; 3],
    /// Node (0, 0, 0)'s position, in the mesh's coordinates.
    pub min: DVec3,
    /// The distance between neighbouring nodes.
    pub cell: f64,
    /// Signed distances, x fastest, then y, then z.
    pub values: Vec<f32>,
}

impl Sdf {
    /// The trilinear value at grid coordinates `g` (in cells from node 0), clamped to the
    /// grid. The WGSL twin is the `Mesh` collider's `mesh{i}_value`.
    pub(crate) fn value(&self, g: DVec3) -> f64 {
        let n = self.counts.map(f64::from);
        let gc = g.clamp(DVec3::ZERO, DVec3::new(n[0] - 1.0, n[1] - 1.0, n[2] - 1.0));
        let base = gc
            .floor()
            .min(DVec3::new(n[0] - 2.0, n[1] - 2.0, n[2] - 2.0));
        let f = gc - base;
        let (i, j, k) = (base.x as usize, base.y as usize, base.z as usize);
        let (nx, ny) = (self.counts[0] as usize, self.counts[1] as usize);
        let at = |di: usize, dj: usize, dk: usize| {
            f64::from(self.values[((k + dk) * ny + j + dj) * nx + i + di])
        };
        let x00 = at(0, 0, 0) + (at(1, 0, 0) - at(0, 0, 0)) * f.x;
        let x10 = at(0, 1, 0) + (at(1, 1, 0) - at(0, 1, 0)) * f.x;
        let x01 = at(0, 0, 1) + (at(1, 0, 1) - at(0, 0, 1)) * f.x;
        let x11 = at(0, 1, 1) + (at(1, 1, 1) - at(0, 1, 1)) * f.x;
        let y0 = x00 + (x10 - x00) * f.y;
        let y1 = x01 + (x11 - x01) * f.y;
        y0 + (y1 - y0) * f.z
    }

    /// The field's gradient at `g` by central differences half a cell either side (in value
    /// per cell).
    pub(crate) fn gradient(&self, g: DVec3) -> DVec3 {
        let d = |e: DVec3| self.value(g + 0.5 * e) - self.value(g - 0.5 * e);
        DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
    }

    /// The grid's last node, in grid coordinates.
    pub(crate) fn last(&self) -> DVec3 {
        DVec3::new(
            f64::from(self.counts[0] - 1),
            f64::from(self.counts[1] - 1),
            f64::from(self.counts[2] - 1),
        )
    }
}

/// The closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() < 1e-300 {
        // A sliver: its nearest corner is close enough.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| {
                (p - *x)
                    .length_squared()
                    .total_cmp(&(p - *y).length_squared())
            })
            .unwrap_or(a);
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// The edge function of `p` against the edge `a` -> `b` in the (y, z) plane, computed from
/// the lexicographically smaller end so that the edge seen from its two triangles gives
/// exactly opposite values (the crossing count's fill rule needs that).
fn edge(a: (f64, f64), b: (f64, f64), p: (f64, f64)) -> f64 {
    if a <= b {
        (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
    } else {
        -((a.0 - b.0) * (p.1 - b.1) - (a.1 - b.1) * (p.0 - b.0))
    }
}

/// Whether a point exactly on the edge `a` -> `b` of a counter-clockwise triangle belongs to
/// it: a fixed rule on the edge's direction, so that of two triangles on either side of a
/// shared edge exactly one takes it.
fn owns_edge(a: (f64, f64), b: (f64, f64)) -> bool {
    let (dy, dz) = (b.0 - a.0, b.1 - a.1);
    dz < 0.0 || (dz == 0.0 && dy > 0.0)
}

/// Bakes `mesh` at `resolution` cells along its longest side.
pub(crate) fn bake(mesh: &TriMesh, resolution: u32) -> Sdf {
    let (lo, hi) = mesh.bounds();
    let cell = (hi - lo).max_element() / f64::from(resolution);
    let min = lo - DVec3::splat(f64::from(PAD) * cell);
    let counts = ((hi - lo) / cell)
        .ceil()
        .to_array()
        .map(|c| c as u32 + 2 * PAD + 1);
    let [nx, ny, nz] = counts.map(|c| c as usize);
    let node = |i: usize, j: usize, k: usize| min + DVec3::new(i as f64, j as f64, k as f64) * cell;
    let index = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let far = (hi - lo).length() + 4.0 * f64::from(PAD) * cell;
    let mut dist = vec![far; nx * ny * nz];
    let mut nearest = vec![u32::MAX; nx * ny * nz];
    let grid_of = |p: DVec3| (p - min) / cell;
    // Exact distances near each triangle.
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(t);
        let g0 = (grid_of(a.min(b).min(c)) - 1.0).floor().max(DVec3::ZERO);
        let g1 = (grid_of(a.max(b).max(c)) + 1.0).ceil();
        for k in g0.z as usize..=(g1.z as usize).min(nz - 1) {
            for j in g0.y as usize..=(g1.y as usize).min(ny - 1) {
                for i in g0.x as usize..=(g1.x as usize).min(nx - 1) {
                    let p = node(i, j, k);
                    let d = (p - closest_on_triangle(p, a, b, c)).length();
                    let at = index(i, j, k);
                    if d < dist[at] {
                        dist[at] = d;
                        nearest[at] = t as u32;
                    }
                }
            }
        }
    }
    // Sweeps: each node tries its neighbours' nearest triangles.
    for _round in 0..2 {
        for order in 0..8 {
            let (di, dj, dk) = (order & 1 != 0, order & 2 != 0, order & 4 != 0);
            let walk = |n: usize, back: bool| -> Vec<usize> {
                if back {
                    (0..n).rev().collect()
                } else {
                    (0..n).collect()
                }
            };
            for k in walk(nz, dk) {
                for j in walk(ny, dj) {
                    for i in walk(nx, di) {
                        let p = node(i, j, k);
                        let at = index(i, j, k);
                        let step = |c: usize, back: bool, n: usize| {
                            if back {
                                (c + 1 < n).then_some(c + 1)
                            } else {
                                c.checked_sub(1)
                            }
                        };
                        let neighbours = [
                            step(i, di, nx).map(|i| index(i, j, k)),
                            step(j, dj, ny).map(|j| index(i, j, k)),
                            step(k, dk, nz).map(|k| index(i, j, k)),
                        ];
                        for n in neighbours.into_iter().flatten() {
                            let t = nearest[n];
                            if t == u32::MAX || t == nearest[at] {
                                continue;
                            }
                            let [a, b, c] = mesh.corners(t as usize);
                            let d = (p - closest_on_triangle(p, a, b, c)).length();
                            if d < dist[at] {
                                dist[at] = d;
                                nearest[at] = t;
                            }
                        }
                    }
                }
            }
        }
    }
    // Signs: crossings along x, row by row.
    let mut crossings = vec![0u32; nx * ny * nz];
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(t);
        let (mut pa, mut pb, pc) = ((a.y, a.z), (b.y, b.z), (c.y, c.z));
        let (mut xa, mut xb, xc) = (a.x, b.x, c.x);
        let area = edge(pa, pb, pc);
        if area == 0.0 {
            continue; // edge-on to the rows: its neighbours count the crossing
        }
        if area < 0.0 {
            std::mem::swap(&mut pa, &mut pb);
            std::mem::swap(&mut xa, &mut xb);
        }
        let g0 = grid_of(a.min(b).min(c)).floor().max(DVec3::ZERO);
        let g1 = grid_of(a.max(b).max(c)).ceil();
        for k in g0.z as usize..=(g1.z as usize).min(nz - 1) {
            for j in g0.y as usize..=(g1.y as usize).min(ny - 1) {
                let p = node(0, j, k);
                let p = (p.y, p.z);
                let w = [edge(pb, pc, p), edge(pc, pa, p), edge(pa, pb, p)];
                let owned = [owns_edge(pb, pc), owns_edge(pc, pa), owns_edge(pa, pb)];
                if !(0..3).all(|e| w[e] > 0.0 || (w[e] == 0.0 && owned[e])) {
                    continue;
                }
                let x = (w[0] * xa + w[1] * xb + w[2] * xc) / (w[0] + w[1] + w[2]);
                // The first node past the crossing.
                let first = ((x - min.x) / cell).floor() + 1.0;
                if first < nx as f64 {
                    crossings[index(first.max(0.0) as usize, j, k)] += 1;
                }
            }
        }
    }
    let mut values = vec![0f32; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            let mut inside = false;
            for i in 0..nx {
                let at = index(i, j, k);
                inside ^= crossings[at] % 2 == 1;
                values[at] = if inside { -dist[at] } else { dist[at] } as f32;
            }
        }
    }
    Sdf {
        counts,
        min,
        cell,
        values,
    }
}

fn cache_key(mesh_bytes: &[u8], resolution: u32) -> u64 {
    let key = fnv1a(mesh_bytes, FNV_OFFSET);
    let key = fnv1a(&resolution.to_le_bytes(), key);
    fnv1a(&BAKE_VERSION.to_le_bytes(), key)
}

fn encode(sdf: &Sdf, key: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + sdf.values.len() * 4);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&key.to_le_bytes());
    for c in sdf.counts {
        out.extend_from_slice(&c.to_le_bytes());
    }
    for v in sdf.min.to_array().into_iter().chain([sdf.cell]) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in &sdf.values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The cached field, when `bytes` is a cache for `key` (anything else reads as no cache).
fn decode(bytes: &[u8], key: u64) -> Option<Sdf> {
    let (head, rest) = bytes.split_at_checked(8 + 8 + 12 + 32)?;
    if &head[..8] != MAGIC || u64::from_le_bytes(head[8..16].try_into().ok()?) != key {
        return None;
    }
    let u = |at: usize| u32::from_le_bytes(head[at..at + 4].try_into().unwrap());
    let f = |at: usize| f64::from_le_bytes(head[at..at + 8].try_into().unwrap());
    let counts = [u(16), u(20), u(24)];
    let nodes = counts
        .iter()
        .try_fold(1usize, |n, &c| n.checked_mul(c as usize))?;
    if rest.len() != nodes.checked_mul(4)? || counts.iter().any(|&c| c < 2) {
        return None;
    }
    Some(Sdf {
        counts,
        min: DVec3::new(f(28), f(36), f(44)),
        cell: f(52),
        values: rest
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect(),
    })
}

/// Where the field of the mesh at `mesh_path` is cached.
pub(crate) fn cache_path(mesh_path: &Path) -> std::path::PathBuf {
    let mut name = mesh_path.as_os_str().to_owned();
    name.push(".plume-sdf");
    name.into()
}

/// The field of `mesh` (read from `mesh_path`, whose bytes are `mesh_bytes`) at
/// `resolution`: from the cache when it is current, else baked and cached.
pub(crate) fn cached_or_baked(
    mesh: &TriMesh,
    mesh_path: &Path,
    mesh_bytes: &[u8],
    resolution: u32,
) -> Sdf {
    // A host's files (not on disk) have no folder to keep a cache in: baked each time.
    if !crate::base::files::on_disk() {
        return bake(mesh, resolution);
    }
    let key = cache_key(mesh_bytes, resolution);
    let cache = cache_path(mesh_path);
    if let Some(sdf) = std::fs::read(&cache).ok().and_then(|b| decode(&b, key)) {
        return sdf;
    }
    let sdf = bake(mesh, resolution);
    // Written aside and renamed, so that a reader never sees half a cache.
    let aside = cache.with_extension(format!(
        "plume-sdf.{}.{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    if std::fs::write(&aside, encode(&sdf, key)).is_ok() && std::fs::rename(&aside, &cache).is_err()
    {
        let _ = std::fs::remove_file(&aside);
    }
    sdf
}

/// Reads the closed OBJ mesh at `path` and bakes (or loads from the cache) its field at
/// `resolution`; says what is wrong otherwise: the file's problems, a mesh that is not closed
/// (it has no inside) or flat (no volume).
pub(crate) fn read_and_bake(path: &Path, resolution: u32) -> Result<(Sdf, TriMesh), String> {
    let (mesh, bytes) = read_mesh(path)?;
    let (open, first) = mesh.open_edges();
    if let Some((a, b)) = first {
        return Err(format!(
            "mesh `{}` is not closed: {open} edge(s) border an odd number of triangles, the first from ({}, {}, {}) to ({}, {}, {}); a solid needs a closed mesh, so that it has an inside (close the holes, or weld the vertices)",
            path.display(),
            a.x,
            a.y,
            a.z,
            b.x,
            b.y,
            b.z
        ));
    }
    let (lo, hi) = mesh.bounds();
    if (hi - lo).min_element() <= 0.0 {
        return Err(format!(
            "mesh `{}` is flat (its box is {} x {} x {}): a solid needs a volume",
            path.display(),
            hi.x - lo.x,
            hi.y - lo.y,
            hi.z - lo.z
        ));
    }
    let sdf = cached_or_baked(&mesh, path, &bytes, resolution);
    Ok((sdf, mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube from -1 to 1, 12 triangles.
    fn cube() -> TriMesh {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        TriMesh {
            vertices: vec![
                v(-1., -1., -1.),
                v(1., -1., -1.),
                v(1., 1., -1.),
                v(-1., 1., -1.),
                v(-1., -1., 1.),
                v(1., -1., 1.),
                v(1., 1., 1.),
                v(-1., 1., 1.),
            ],
            triangles: vec![
                [0, 3, 2],
                [0, 2, 1],
                [4, 5, 6],
                [4, 6, 7],
                [0, 4, 7],
                [0, 7, 3],
                [1, 2, 6],
                [1, 6, 5],
                [0, 1, 5],
                [0, 5, 4],
                [3, 7, 6],
                [3, 6, 2],
            ],
        }
    }

    /// The exact signed distance to the cube [-1, 1]³.
    fn box_distance(p: DVec3) -> f64 {
        let q = p.abs() - DVec3::ONE;
        q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
    }

    #[test]
    fn a_cube_bakes_to_its_exact_signed_distance_at_every_node() {
        // The rows pass exactly through the cube's edges and corners (nodes every 0.25 from
        // -1.75): the fill rule must count each crossing once.
        let sdf = bake(&cube(), 8);
        assert_eq!(sdf.counts, [15, 15, 15]);
        assert_eq!(sdf.cell, 0.25);
        for k in 0..15 {
            for j in 0..15 {
                for i in 0..15 {
                    let p = sdf.min + DVec3::new(i as f64, j as f64, k as f64) * sdf.cell;
                    let baked = f64::from(sdf.values[(k * 15 + j) * 15 + i]);
                    assert!(
                        (baked - box_distance(p)).abs() < 1e-6,
                        "node {p}: baked {baked}, exact {}",
                        box_distance(p)
                    );
                }
            }
        }
        // Between nodes: trilinear, exact on the flat faces.
        let g = (DVec3::new(0.3, 1.1, -0.2) - sdf.min) / sdf.cell;
        assert!((sdf.value(g) - 0.1).abs() < 1e-6);
        let n = sdf.gradient(g).normalize();
        assert!((n - DVec3::Y).length() < 1e-6, "{n}");
    }

    #[test]
    fn the_cache_is_read_back_and_ignored_when_the_mesh_changes() {
        let dir = std::env::temp_dir().join(format!("plume-sdf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cube.obj");
        let sdf = cached_or_baked(&cube(), &path, b"cube v1", 4);
        let cache = std::fs::read(cache_path(&path)).unwrap();
        assert_eq!(decode(&cache, cache_key(b"cube v1", 4)), Some(sdf.clone()));
        assert_eq!(decode(&cache, cache_key(b"cube v2", 4)), None);
        assert_eq!(decode(&cache, cache_key(b"cube v1", 5)), None);
        assert_eq!(
            decode(&cache[..cache.len() - 1], cache_key(b"cube v1", 4)),
            None
        );
        // A stale cache is replaced.
        std::fs::write(cache_path(&path), b"PLUMESDF junk").unwrap();
        assert_eq!(cached_or_baked(&cube(), &path, b"cube v1", 4), sdf);
        let cache = std::fs::read(cache_path(&path)).unwrap();
        assert_eq!(decode(&cache, cache_key(b"cube v1", 4)), Some(sdf));
    }
}
