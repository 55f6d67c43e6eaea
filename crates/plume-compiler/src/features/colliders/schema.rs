//! The colliders' schema: the `Collider` enum as effect files write it, its checks and its
//! lowering to [`super::ColliderIr`].

use std::sync::Arc;

use serde::Deserialize;

use super::{aabb, height_field, mesh, plane, scene_depth, sphere, ColliderIr, Surface};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;

/// A collider as written in an effect file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Collider {
    /// A half-space boundary: particles live on the side the normal points to.
    Plane {
        /// Any point on the plane.
        point: Vec3,
        /// Points into the allowed side (any length but zero).
        normal: Vec3,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
    },
    /// A ball: particles stay outside it, or inside it with `inside: true`.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (m), > 0.
        radius: f64,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
        /// Keep particles inside (a container) instead of outside.
        #[serde(default)]
        inside: bool,
    },
    /// An axis-aligned box: particles stay outside it, or inside it with `inside: true`.
    Box {
        /// Lower corner.
        min: Vec3,
        /// Upper corner (greater than `min` on every axis).
        max: Vec3,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
        /// Keep particles inside (a container) instead of outside.
        #[serde(default)]
        inside: bool,
    },
    /// Terrain: heights on a regular grid over an x-z rectangle, bilinear between samples;
    /// particles over the rectangle are kept above it.
    HeightField {
        /// The rectangle's (x, z) corner where the first row's first height sits.
        min: (f64, f64),
        /// The opposite (x, z) corner.
        max: (f64, f64),
        /// Heights (y, in metres): one row per z sample from min to max, each row one height
        /// per x sample from min to max; at least 2 x 2, every row the same length. Empty
        /// when `image` gives them.
        #[serde(default)]
        heights: Vec<Vec<f64>>,
        /// An 8- or 16-bit greyscale PNG whose pixels are the heights instead (top row first,
        /// relative to the effect file; see [`super::height_image`]).
        #[serde(default)]
        image: Option<String>,
        /// With `image`: the heights (m) of black and of white.
        #[serde(default)]
        height: Option<(f64, f64)>,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
    },
    /// A closed triangle mesh from an OBJ file, baked into a signed distance field; particles
    /// stay outside it (see [`mesh`]).
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
        /// Field cells along the mesh's longest side (4 to 128).
        #[serde(default = "default_resolution")]
        resolution: u32,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
        /// The mesh and its baked field, made by [`mesh::read_meshes`] before the checks.
        #[serde(skip)]
        baked: Option<Arc<mesh::Baked>>,
    },
    /// The surfaces the view's depth image shows, given at run time by the host (or by the
    /// scene `plume render` and `plume preview` draw); see [`scene_depth`].
    SceneDepth {
        /// How far behind a surface a particle still collides (m, > 0); farther behind, it is
        /// behind the object, not in it, and passes.
        #[serde(default = "default_thickness")]
        thickness: f64,
        /// Fraction of normal speed kept on a bounce, in [0, 1].
        restitution: f64,
        /// Fraction of tangential speed lost on a bounce, in [0, 1].
        friction: f64,
    },
}

fn default_thickness() -> f64 {
    scene_depth::DEFAULT_THICKNESS
}

fn default_resolution() -> u32 {
    mesh::DEFAULT_RESOLUTION
}

impl Collider {
    /// The variant's name as written in effect files.
    pub fn name(&self) -> &'static str {
        match self {
            Collider::Plane { .. } => "Plane",
            Collider::Sphere { .. } => "Sphere",
            Collider::Box { .. } => "Box",
            Collider::HeightField { .. } => "HeightField",
            Collider::Mesh { .. } => "Mesh",
            Collider::SceneDepth { .. } => "SceneDepth",
        }
    }

    /// Checks the collider's parameters; `path` names the variant.
    pub fn check(&self, path: &ValuePath, c: &mut Checker) {
        let (restitution, friction) = match self {
            Collider::Plane {
                point,
                normal,
                restitution,
                friction,
            } => {
                c.vec3(&path.field("point"), *point);
                c.direction(&path.field("normal"), *normal);
                (restitution, friction)
            }
            Collider::Sphere {
                center,
                radius,
                restitution,
                friction,
                ..
            } => {
                sphere::check(path, c, *center, *radius);
                (restitution, friction)
            }
            Collider::Box {
                min,
                max,
                restitution,
                friction,
                ..
            } => {
                aabb::check(path, c, *min, *max);
                (restitution, friction)
            }
            Collider::HeightField {
                min,
                max,
                heights,
                restitution,
                friction,
                ..
            } => {
                height_field::check(path, c, *min, *max, heights);
                (restitution, friction)
            }
            Collider::Mesh {
                offset,
                scale,
                rotation,
                resolution,
                restitution,
                friction,
                baked,
                ..
            } => {
                mesh::check(
                    path,
                    c,
                    (*offset, *scale, *rotation, *resolution),
                    baked.is_some(),
                );
                (restitution, friction)
            }
            Collider::SceneDepth {
                thickness,
                restitution,
                friction,
            } => {
                scene_depth::check(path, c, *thickness);
                (restitution, friction)
            }
        };
        c.within(&path.field("restitution"), *restitution, 0.0, 1.0);
        c.within(&path.field("friction"), *friction, 0.0, 1.0);
    }

    /// Lowers a checked collider to the IR.
    pub fn lower(&self) -> ColliderIr {
        let (surface, restitution, friction) = match self {
            Collider::Plane {
                point,
                normal,
                restitution,
                friction,
            } => (
                Surface::Plane(plane::PlaneIr {
                    point: point.d(),
                    normal: crate::features::forces::safe_normalize(normal.d()),
                }),
                restitution,
                friction,
            ),
            Collider::Sphere {
                center,
                radius,
                restitution,
                friction,
                inside,
            } => (
                Surface::Sphere(sphere::SphereIr {
                    center: center.d(),
                    radius: *radius,
                    inside: *inside,
                }),
                restitution,
                friction,
            ),
            Collider::Box {
                min,
                max,
                restitution,
                friction,
                inside,
            } => (
                Surface::Box(aabb::BoxIr {
                    min: min.d(),
                    max: max.d(),
                    inside: *inside,
                }),
                restitution,
                friction,
            ),
            Collider::HeightField {
                min,
                max,
                heights,
                restitution,
                friction,
                ..
            } => (
                Surface::HeightField(height_field::HeightFieldIr::new(*min, *max, heights)),
                restitution,
                friction,
            ),
            Collider::Mesh {
                file,
                offset,
                scale,
                rotation,
                restitution,
                friction,
                baked,
                ..
            } => (
                Surface::Mesh(mesh::MeshIr {
                    file: file.clone(),
                    offset: offset.d(),
                    scale: *scale,
                    rotation: mesh::rotation_matrix(*rotation),
                    baked: baked
                        .clone()
                        .expect("the checks refuse a mesh collider not read"),
                }),
                restitution,
                friction,
            ),
            Collider::SceneDepth {
                thickness,
                restitution,
                friction,
            } => (
                Surface::SceneDepth(scene_depth::SceneDepthIr {
                    thickness: *thickness,
                    image: None,
                }),
                restitution,
                friction,
            ),
        };
        ColliderIr {
            surface,
            restitution: *restitution,
            friction: *friction,
        }
    }
}

/// Path of the `i`-th collider, with its variant named.
pub fn collider_path(i: usize, c: &Collider) -> ValuePath {
    ValuePath::root()
        .field("collide")
        .index(i)
        .variant(c.name())
}
