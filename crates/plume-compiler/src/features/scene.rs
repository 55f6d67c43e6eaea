//! The effect's scene: meshes that are drawn and not simulated (`scene: [Mesh(file: ..)]` in
//! the file). `plume render` and `plume preview` draw them, with the meshes the effect's
//! colliders and emitters name, so that an author sees what the particles meet, and a
//! `SceneDepth` collider collides with the depth they leave. Particles meet a scene mesh only
//! through its depth: without a `SceneDepth` collider it is scenery.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat3, DVec3};
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::mesh::{read_mesh, rotation_degrees, TriMesh};
use crate::base::path::ValuePath;
use crate::base::values::Vec3;

/// A scene mesh as written in an effect file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) enum SceneMesh {
    /// A triangle mesh from an OBJ file, placed in the world.
    Mesh {
        /// The OBJ file, relative to the effect file.
        file: String,
        /// Where the mesh's origin sits in the world (m).
        #[serde(default = "crate::base::values::origin")]
        offset: Vec3,
        /// The mesh's size against the world's (> 0).
        #[serde(default = "crate::base::values::unit_scale")]
        scale: f64,
        /// Degrees about x, then y, then z (the world's axes).
        #[serde(default = "crate::base::values::origin")]
        rotation: Vec3,
        /// The mesh read from `file`, by [`read_scene`] before the checks.
        #[serde(skip)]
        mesh: Option<Arc<TriMesh>>,
    },
}

/// A scene mesh in the IR: the mesh and where it sits.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SceneMeshIr {
    /// The mesh file as the effect names it.
    pub file: String,
    /// Where the mesh's origin sits in the world.
    pub offset: DVec3,
    /// The mesh's size against the world's.
    pub scale: f64,
    /// The mesh's rotation (its axes in world coordinates, as columns).
    pub rotation: DMat3,
    /// The mesh, in its own coordinates.
    pub mesh: Arc<TriMesh>,
}

fn path(i: usize) -> ValuePath {
    ValuePath::root().field("scene").index(i).variant("Mesh")
}

/// Reads every scene mesh's file (relative to `base_dir`); an unreadable or empty mesh, or a
/// NaN vertex, is recorded in `c` at the mesh's `file`.
pub(crate) fn read_scene(scene: &mut [SceneMesh], base_dir: Option<&Path>, c: &mut Checker) {
    for (i, entry) in scene.iter_mut().enumerate() {
        let SceneMesh::Mesh { file, mesh, .. } = entry;
        let full = base_dir.map_or_else(|| PathBuf::from(&*file), |dir| dir.join(&*file));
        match read_mesh(&full) {
            Ok((read, _)) => *mesh = Some(Arc::new(read)),
            Err(message) => c.error(&path(i).field("file"), message),
        }
    }
}

/// Checks each scene mesh's placement.
pub(crate) fn check(scene: &[SceneMesh], c: &mut Checker) {
    for (i, entry) in scene.iter().enumerate() {
        let SceneMesh::Mesh {
            offset,
            scale,
            rotation,
            mesh,
            ..
        } = entry;
        let p = path(i);
        crate::base::mesh::check_placement(&p, c, (*offset, *scale, *rotation));
        if mesh.is_none() {
            c.error(&p.field("file"), "the mesh was not read");
        }
    }
}

impl SceneMesh {
    /// Lowers a checked scene mesh to the IR.
    pub(crate) fn lower(&self) -> SceneMeshIr {
        let SceneMesh::Mesh {
            file,
            offset,
            scale,
            rotation,
            mesh,
        } = self;
        SceneMeshIr {
            file: file.clone(),
            offset: offset.d(),
            scale: *scale,
            rotation: rotation_degrees(rotation.d()),
            mesh: mesh
                .clone()
                .expect("the checks refuse a scene mesh not read"),
        }
    }
}

impl SceneMeshIr {
    /// The mesh's triangles placed in the world.
    pub(crate) fn world_triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.mesh
            .placed_triangles(self.offset, self.scale, self.rotation)
    }
}
