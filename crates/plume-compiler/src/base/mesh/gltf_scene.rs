//! Triangle meshes read from glTF 2.0 files (`.gltf` JSON or `.glb` binary, with the `gltf`
//! crate): every triangle primitive of the file's scene (its default one, else its first; a
//! file without scenes gives every mesh as it is), each placed by its node's transform and its
//! parents'. Buffers come from the `.glb`'s own binary chunk, a base64 `data:` URI, or a file
//! beside the glTF, read through the compiler's file source like every file an effect names.

use std::path::Path;

use base64::Engine;
use glam::{DMat4, DVec3};

use super::{Piece, MAX_FILE_BYTES};
use crate::base::files::ReadError;

/// Whether `path` names a glTF file (by its extension).
pub(crate) fn is_gltf(path: &Path) -> bool {
    let extension = path.extension().and_then(|e| e.to_str());
    extension.is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// The file's triangles as pieces (one per primitive, placed in the scene), and the bytes of
/// the external buffers it reads (which a cache keyed on the mesh must see too).
pub(crate) fn pieces(path: &Path, bytes: &[u8]) -> Result<(Vec<Piece>, Vec<u8>), String> {
    let shown = path.display();
    let not_gltf = |e: gltf::Error| format!("cannot read mesh `{shown}` as glTF: {e}");
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(not_gltf)?;
    // The gltf crate's validation looks a primitive's POSITION accessor up unchecked (one past
    // the file's accessors panics): such an index is refused here first.
    let json = document.into_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .values()
                .find(|i| i.value() >= json.accessors.len())
            {
                return Err(format!(
                    "mesh `{shown}`: mesh {m} (primitive {p}) names accessor {}, past the file's {}",
                    index.value(),
                    json.accessors.len()
                ));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(not_gltf)?;
    let mut external = Vec::new();
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.clone().ok_or_else(|| {
                format!(
                    "mesh `{shown}`: buffer {} is the binary chunk, which the file does not have",
                    buffer.index()
                )
            })?,
            gltf::buffer::Source::Uri(uri) => {
                let data = buffer_at(path, uri)?;
                if !uri.starts_with("data:") {
                    external.extend_from_slice(&data);
                }
                data
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "mesh `{shown}`: buffer {} has {} bytes, fewer than the {} the file says",
                buffer.index(),
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    let mut placed = Vec::new();
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => {
            // A tree of nodes is no deeper than it has nodes; deeper, its nodes form a cycle.
            let deepest = document.nodes().len();
            for node in scene.nodes() {
                place(&node, DMat4::IDENTITY, deepest, &mut placed)
                    .map_err(|cycle| format!("mesh `{shown}`: {cycle}"))?;
            }
        }
        None => placed.extend(document.meshes().map(|m| (m, DMat4::IDENTITY))),
    }
    let mut pieces = Vec::new();
    for (mesh, transform) in placed {
        // A transform that mirrors turns the triangles' winding round.
        let mirrored = transform.determinant() < 0.0;
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let name = match mesh.name() {
                Some(name) => format!("mesh `{name}` (primitive {})", primitive.index()),
                None => format!("mesh {} (primitive {})", mesh.index(), primitive.index()),
            };
            let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            // An accessor past the end of its buffer reads as none: refused, not skipped.
            let unread =
                |what| format!("mesh `{shown}`: {name}'s {what} lie past its buffer's end");
            let Some(positions) = reader.read_positions() else {
                match primitive.get(&gltf::Semantic::Positions) {
                    Some(_) => return Err(unread("positions")),
                    None => continue,
                }
            };
            let positions: Vec<DVec3> = positions
                .map(|p| {
                    transform.transform_point3(DVec3::new(p[0].into(), p[1].into(), p[2].into()))
                })
                .collect();
            let indices: Vec<u32> = match (reader.read_indices(), primitive.indices()) {
                (Some(indices), _) => indices.into_u32().collect(),
                (None, Some(_)) => return Err(unread("indices")),
                (None, None) => (0..positions.len() as u32).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(format!(
                    "mesh `{shown}`: {name} names vertex {bad} of its {}",
                    positions.len()
                ));
            }
            let triangles = indices
                .chunks_exact(3)
                .map(|t| match mirrored {
                    true => [t[0], t[2], t[1]],
                    false => [t[0], t[1], t[2]],
                })
                .collect();
            pieces.push(Piece {
                name,
                positions,
                triangles,
            });
        }
    }
    Ok((pieces, external))
}

/// Each mesh under `node` (itself included) with its transform in the scene, or the cycle
/// found where the nodes go on past `depth` more levels.
fn place<'a>(
    node: &gltf::Node<'a>,
    parent: DMat4,
    depth: usize,
    out: &mut Vec<(gltf::Mesh<'a>, DMat4)>,
) -> Result<(), String> {
    if depth == 0 {
        return Err(format!(
            "node {} is its own ancestor: a scene's nodes must form a tree",
            node.index()
        ));
    }
    let local = node
        .transform()
        .matrix()
        .map(|column| column.map(f64::from));
    let transform = parent * DMat4::from_cols_array_2d(&local);
    if let Some(mesh) = node.mesh() {
        out.push((mesh, transform));
    }
    for child in node.children() {
        place(&child, transform, depth - 1, out)?;
    }
    Ok(())
}

/// The bytes of a buffer at `uri`: a base64 `data:` URI, or a file beside the glTF at `path`.
fn buffer_at(path: &Path, uri: &str) -> Result<Vec<u8>, String> {
    let shown = path.display();
    if let Some(data) = uri.strip_prefix("data:") {
        let encoded = data
            .split_once(";base64,")
            .map(|(_, encoded)| encoded)
            .ok_or_else(|| format!("mesh `{shown}`: a `data:` buffer that is not base64"))?;
        return base64::engine::general_purpose::STANDARD
            .decode(encoded)
            .map_err(|e| format!("mesh `{shown}`: its base64 buffer does not decode: {e}"));
    }
    let beside = path.parent().unwrap_or(Path::new("")).join(uri);
    let named = beside.display();
    crate::base::files::read(&beside, MAX_FILE_BYTES).map_err(|e| match e {
        ReadError::Open(e) => format!("mesh `{shown}`: cannot open its buffer `{named}`: {e}"),
        ReadError::Read(e) => format!("mesh `{shown}`: cannot read its buffer `{named}`: {e}"),
        ReadError::TooLarge(size) => format!(
            "mesh `{shown}`: its buffer `{named}` is {size} bytes, more than the {MAX_FILE_BYTES} a mesh file may have"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{read_mesh, TriMesh};
    use super::*;

    /// The unit cube's 8 corners and 12 triangles, counter-clockwise seen from outside.
    fn cube() -> (Vec<[f32; 3]>, Vec<u16>) {
        let corners = (0..8)
            .map(|k| [k & 1, k >> 1 & 1, k >> 2 & 1].map(|b| b as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
            .collect();
        (corners, triangles)
    }

    /// The cube's buffer (positions, then indices) and a glTF document placing it twice: as it
    /// is under a parent moved by (10, 0, 0), and mirrored in x by a child's scale of -1.
    fn cube_document(uri: Option<&str>) -> (String, Vec<u8>) {
        let (corners, indices) = cube();
        let mut bin: Vec<u8> = corners
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let index_offset = bin.len();
        bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
        bin.resize(bin.len().next_multiple_of(4), 0);
        let uri = uri.map_or(String::new(), |u| format!(r#""uri": "{u}", "#));
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"translation": [10, 0, 0], "children": [1, 2]}}, {{"mesh": 0}},
            {{"mesh": 0, "scale": [-1, 1, 1]}}],
  "meshes": [{{"name": "cube", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{{uri}"byteLength": {len}}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 96}},
                  {{"buffer": 0, "byteOffset": {index_offset}, "byteLength": 72}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 1]}},
                {{"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}}]}}"#,
            len = bin.len()
        );
        (json, bin)
    }

    /// A binary glTF: the header, the JSON chunk (space-padded), the BIN chunk.
    fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let mut json = json.as_bytes().to_vec();
        json.resize(json.len().next_multiple_of(4), b' ');
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }

    fn dir() -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("plume-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Six times the volume the triangles enclose (positive when they face outward).
    fn volume6(mesh: &TriMesh) -> f64 {
        (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                a.dot(b.cross(c))
            })
            .sum()
    }

    #[test]
    fn a_scene_is_read_placed_and_wound_outward_from_every_buffer_source() {
        let dir = dir();
        let (json, bin) = cube_document(Some("cube.bin"));
        std::fs::write(dir.join("beside.gltf"), &json).unwrap();
        std::fs::write(dir.join("cube.bin"), &bin).unwrap();
        let encoded = base64::engine::general_purpose::STANDARD.encode(&bin);
        let uri = format!("data:application/octet-stream;base64,{encoded}");
        std::fs::write(dir.join("inline.gltf"), cube_document(Some(&uri)).0).unwrap();
        std::fs::write(dir.join("cube.glb"), glb(&cube_document(None).0, &bin)).unwrap();
        let mut read = Vec::new();
        for name in ["beside.gltf", "inline.gltf", "cube.glb"] {
            let (mesh, bytes) = read_mesh(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
            // Two cubes, 16 corners: one at x 10..11, its mirror at x 9..10 (sharing a face).
            assert_eq!(mesh.triangles.len(), 24, "{name}");
            assert_eq!(mesh.vertices.len(), 12, "{name}");
            assert_eq!(
                mesh.bounds(),
                (DVec3::new(9.0, 0.0, 0.0), DVec3::new(11.0, 1.0, 1.0)),
                "{name}"
            );
            // Both cubes face outward, the mirrored one too: twice the unit volume.
            assert!(
                (volume6(&mesh) - 12.0).abs() < 1e-9,
                "{name}: {}",
                volume6(&mesh)
            );
            // The shared face is used twice, every other edge by two triangles: closed.
            assert_eq!(mesh.open_edges().0, 0, "{name}");
            // An external buffer's bytes count in what a cache hashes.
            let file = std::fs::metadata(dir.join(name)).unwrap().len() as usize;
            let external = if name == "beside.gltf" { bin.len() } else { 0 };
            assert_eq!(bytes.len(), file + external, "{name}");
            read.push(mesh);
        }
        assert!(read.windows(2).all(|w| w[0] == w[1]));
    }

    #[test]
    fn damaged_gltf_files_are_read_or_refused_never_a_panic() {
        let dir = dir();
        let (json, bin) = cube_document(None);
        let good = glb(&json, &bin);
        // Bytes overwritten at spread positions (the header, the JSON, the binary chunk) with
        // values from the PCG hash, a few at a time.
        let mut key = 1u32;
        for case in 0..400 {
            let mut bytes = good.clone();
            for _ in 0..1 + case % 3 {
                key = crate::base::rng::pcg(key);
                let at = key as usize % bytes.len();
                bytes[at] = (crate::base::rng::pcg(key) >> 24) as u8;
            }
            let path = dir.join(format!("damaged-{case}.glb"));
            std::fs::write(&path, &bytes).unwrap();
            match read_mesh(&path) {
                Ok((mesh, _)) => assert!(mesh.vertices.iter().all(|v| v.is_finite())),
                Err(why) => assert!(why.contains("damaged-"), "{why}"),
            }
            std::fs::remove_file(&path).unwrap();
        }
    }

    #[test]
    fn bad_gltf_files_are_refused_with_why() {
        let dir = dir();
        let (json, bin) = cube_document(Some("gone.bin"));
        let encoded = base64::engine::general_purpose::STANDARD.encode(&bin);
        let inline = format!("data:application/octet-stream;base64,{encoded}");
        let inline_json = cube_document(Some(&inline)).0;
        let cases = [
            ("junk.gltf", b"{ not json".to_vec(), "cannot read mesh"),
            (
                "missing.gltf",
                json.clone().into_bytes(),
                "cannot open its buffer",
            ),
            (
                "short.glb",
                glb(&cube_document(None).0, &bin[..64]),
                "buffer 0 has 64 bytes, fewer than the 168",
            ),
            (
                "long.gltf",
                cube_document(Some(&inline))
                    .0
                    .replacen(r#""count": 36"#, r#""count": 360"#, 1)
                    .into_bytes(),
                "(primitive 0)'s indices lie past its buffer's end",
            ),
            (
                "accessor.gltf",
                inline_json
                    .replacen(r#""POSITION": 0"#, r#""POSITION": 7"#, 1)
                    .into_bytes(),
                "(primitive 0) names accessor 7, past the file's 2",
            ),
            (
                "cycle.gltf",
                inline_json
                    .replacen(r#"{"mesh": 0}"#, r#"{"mesh": 0, "children": [0]}"#, 1)
                    .into_bytes(),
                "is its own ancestor: a scene's nodes must form a tree",
            ),
            (
                "text.gltf",
                cube_document(Some("data:text/plain,hello")).0.into_bytes(),
                "not base64",
            ),
        ];
        for (name, bytes, want) in cases {
            std::fs::write(dir.join(name), bytes).unwrap();
            let error = read_mesh(&dir.join(name)).unwrap_err();
            assert!(
                error.contains(want) && error.contains(name),
                "{name}: {error}"
            );
        }
    }
}
