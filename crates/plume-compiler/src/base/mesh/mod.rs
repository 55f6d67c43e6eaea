//! Triangle meshes read from Wavefront OBJ files (with the `tobj` crate) or glTF files
//! (`gltf_scene`): every object (or primitive) of the file merged, polygons fanned into
//! triangles, and vertices at the very same position welded into one, so that the mesh's topology (which edges two triangles share) is the shape's, not
//! the file's (an OBJ repeats a corner once per normal or texture coordinate it has).
//!
//! What is checked here, with the file named in every message: that the file can be read, is
//! not too big, parses, has triangles, and that every coordinate is finite. Whether a mesh is
//! closed is asked by the features that need an inside ([`TriMesh::open_edges`]).

mod gltf_scene;

use std::collections::HashMap;
use std::path::Path;

use crate::base::files::ReadError;

use glam::{DMat3, DVec3, EulerRot};

/// The largest mesh file read.
pub(crate) const MAX_FILE_BYTES: u64 = 256 << 20;

/// The most triangles a mesh may have.
pub(crate) const MAX_TRIANGLES: usize = 1 << 21;

/// A triangle mesh: welded vertices and triangles of vertex indices (counter-clockwise seen
/// from outside, as OBJ writes them; nothing here depends on it).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TriMesh {
    /// Distinct vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles, three indices into `vertices` each.
    pub triangles: Vec<[u32; 3]>,
}

/// A part of a mesh file before its vertices are welded: an OBJ object, or a glTF primitive
/// placed in its scene.
pub(crate) struct Piece {
    /// What the file calls it, for messages.
    pub name: String,
    /// Its vertex positions.
    pub positions: Vec<DVec3>,
    /// Its triangles, three indices into `positions` each.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads the mesh file at `path` (glTF where it ends in `.gltf` or `.glb`, else OBJ), or says
/// what is wrong with it. Also hands back the bytes read (the file's, then those of any buffer
/// a glTF reads from beside it), which a cache keyed on the mesh hashes.
pub(crate) fn read_mesh(path: &Path) -> Result<(TriMesh, Vec<u8>), String> {
    let shown = path.display();
    let mut bytes = crate::base::files::read(path, MAX_FILE_BYTES).map_err(|e| match e {
        ReadError::Open(e) => format!("cannot open mesh `{shown}`: {e}"),
        ReadError::Read(e) => format!("cannot read mesh `{shown}`: {e}"),
        ReadError::TooLarge(size) => format!(
            "mesh `{shown}` is {size} bytes, more than the {MAX_FILE_BYTES} a mesh file may have: simplify it"
        ),
    })?;
    let (pieces, none) = match gltf_scene::is_gltf(path) {
        true => {
            let (pieces, external) = gltf_scene::pieces(path, &bytes)?;
            bytes.extend(external);
            (pieces, "no triangle primitives in its scene")
        }
        false => (
            obj_pieces(path, &bytes)?,
            "no `f` lines with 3 or more corners",
        ),
    };
    let mut mesh = TriMesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    for piece in &pieces {
        let mut index_of = Vec::with_capacity(piece.positions.len());
        for (k, &v) in piece.positions.iter().enumerate() {
            if !v.is_finite() {
                return Err(format!(
                    "mesh `{shown}`: vertex {} of {} is ({}, {}, {}): every coordinate must be finite",
                    k + 1,
                    piece.name,
                    v.x,
                    v.y,
                    v.z
                ));
            }
            // +0 and -0 are one position.
            let key = (v + DVec3::ZERO).to_array().map(f64::to_bits);
            let next = mesh.vertices.len() as u32;
            let index = *welded.entry(key).or_insert_with(|| {
                mesh.vertices.push(v);
                next
            });
            index_of.push(index);
        }
        for t in &piece.triangles {
            let tri = t.map(|i| index_of[i as usize]);
            // A triangle with two corners at one position has no area and no edges to share.
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                mesh.triangles.push(tri);
            }
        }
        if mesh.triangles.len() > MAX_TRIANGLES {
            return Err(format!(
                "mesh `{shown}` has more than the {MAX_TRIANGLES} triangles a mesh may have: simplify it"
            ));
        }
    }
    if mesh.triangles.is_empty() {
        return Err(format!("mesh `{shown}` has no triangles ({none})"));
    }
    Ok((mesh, bytes))
}

/// The objects of an OBJ file, each a piece: polygons fanned into triangles.
fn obj_pieces(path: &Path, bytes: &[u8]) -> Result<Vec<Piece>, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials are not needed: a missing .mtl must not stop a collider.
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("cannot read mesh `{}` as OBJ: {e}", path.display()))?;
    Ok(models
        .into_iter()
        .map(|model| {
            let m = model.mesh;
            Piece {
                name: format!("object `{}`", model.name),
                positions: m
                    .positions
                    .chunks_exact(3)
                    .map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into()))
                    .collect(),
                triangles: m
                    .indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            }
        })
        .collect())
}

impl TriMesh {
    /// The triangle's corners.
    pub(crate) fn corners(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// The triangles placed in the world: a mesh point p at `offset` + `scale` · `rotation` p.
    pub(crate) fn placed_triangles(
        &self,
        offset: DVec3,
        scale: f64,
        rotation: DMat3,
    ) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        (0..self.triangles.len())
            .map(move |t| self.corners(t).map(|p| offset + scale * (rotation * p)))
    }

    /// The smallest box holding every vertex.
    pub(crate) fn bounds(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        )
    }

    /// Edges that an odd number of triangles use (a closed surface uses each an even number
    /// of times, two for a manifold), and the first such edge's ends.
    pub(crate) fn open_edges(&self) -> (usize, Option<(DVec3, DVec3)>) {
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let mut open: Vec<(u32, u32)> = uses
            .into_iter()
            .filter(|&(_, n)| n % 2 == 1)
            .map(|(e, _)| e)
            .collect();
        open.sort_unstable();
        let first = open
            .first()
            .map(|&(a, b)| (self.vertices[a as usize], self.vertices[b as usize]));
        (open.len(), first)
    }
}

/// Checks a mesh's placement in the world at `path`: `offset` and `rotation` finite, `scale`
/// finite and positive; returns whether the offset and rotation are finite.
pub(crate) fn check_placement(
    path: &crate::base::path::ValuePath,
    c: &mut crate::base::check::Checker,
    (offset, scale, rotation): (crate::base::values::Vec3, f64, crate::base::values::Vec3),
) -> bool {
    let placed = c.vec3(&path.field("offset"), offset) & c.vec3(&path.field("rotation"), rotation);
    c.positive(&path.field("scale"), scale);
    placed
}

/// The rotation that `degrees` (about x, then y, then z, the world's axes) stands for, as
/// meshes are placed.
pub(crate) fn rotation_degrees(degrees: DVec3) -> DMat3 {
    let r = degrees * (std::f64::consts::PI / 180.0);
    // Intrinsic ZYX of (z, y, x) is x first, then y, then z about the world's axes.
    DMat3::from_euler(EulerRot::ZYX, r.z, r.y, r.x)
}

/// FNV-1a, 64 bits: a stable hash of bytes (the standard library's may change between
/// releases, and a cache keyed on it must not).
pub(crate) fn fnv1a(bytes: &[u8], mut hash: u64) -> u64 {
    for &b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// FNV-1a's starting value.
pub(crate) const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("plume-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A unit cube whose faces repeat their corners (one per face, as with per-face normals).
    const CUBE_BY_FACE: &str = "o cube\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
        v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        v 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\n\
        v 1 0 0\nv 1 0 1\nv 1 1 1\nv 1 1 0\n\
        v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\n\
        v 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n\
        f 1 4 3 2\nf 5 6 7 8\nf 9 12 11 10\nf 13 16 15 14\nf 17 20 19 18\nf 21 24 23 22\n";

    #[test]
    fn corners_repeated_per_face_are_welded_into_a_closed_cube() {
        let (mesh, _) = read_mesh(&write("cube.obj", CUBE_BY_FACE)).unwrap();
        assert_eq!(mesh.vertices.len(), 8);
        assert_eq!(mesh.triangles.len(), 12);
        assert_eq!(mesh.open_edges().0, 0);
        assert_eq!(mesh.bounds(), (DVec3::ZERO, DVec3::ONE));
        let open = CUBE_BY_FACE.replace("f 21 24 23 22\n", "");
        let (mesh, _) = read_mesh(&write("box.obj", &open)).unwrap();
        let (count, first) = mesh.open_edges();
        assert_eq!(count, 4);
        assert!(first.is_some());
    }

    #[test]
    fn bad_files_are_refused_with_why() {
        let error = read_mesh(Path::new("no/such/rock.obj")).unwrap_err();
        assert!(
            error.starts_with("cannot open mesh `no/such/rock.obj`"),
            "{error}"
        );
        let nan = CUBE_BY_FACE.replacen("v 1 1 1", "v NaN 1 1", 1);
        let error = read_mesh(&write("nan.obj", &nan)).unwrap_err();
        assert!(
            error.contains("vertex 7 of object `cube` is (NaN, 1, 1)"),
            "{error}"
        );
        let error = read_mesh(&write("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n")).unwrap_err();
        assert!(error.contains("has no triangles"), "{error}");
        let error = read_mesh(&write("junk.obj", "v 0 0 0\nf 1 2 3\n")).unwrap_err();
        assert!(
            error.contains("as OBJ: face vertex index out of bounds"),
            "{error}"
        );
    }
}
