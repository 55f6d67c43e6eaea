//! Spawn shapes, as written: the schema, its checks and its lowering to [`ShapeIr`] (whose
//! WGSL and f64 twin are in `shape_ir.rs`).

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::{safe_normalize, Counts, Vec3};
use crate::expr::typed::Node;
use crate::expr::Names;
use crate::features::emitter::expression::{self, SpawnValue, ESTIMATE_SPAWNS};
use crate::features::emitter::shape_ir::{box_face_thresholds, ConeIr, ShapeIr};
use crate::features::emitter::Basis;
use crate::features::mesh_emission::{place, MeshSurface};

/// Spawn positions.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// Every particle at one point.
    Point(Vec3),
    /// Uniform in the ball's volume, or on its surface.
    Sphere {
        /// Centre of the ball.
        center: Vec3,
        /// Radius (>= 0).
        radius: f64,
        /// On the sphere instead of in the ball.
        #[serde(default)]
        surface: bool,
    },
    /// Uniform in an axis-aligned box, or by area on its six faces.
    Box {
        /// Lower corner.
        min: Vec3,
        /// Upper corner.
        max: Vec3,
        /// On the faces instead of in the volume.
        #[serde(default)]
        surface: bool,
    },
    /// Uniform in a flat disc.
    Disc {
        /// Centre of the disc.
        center: Vec3,
        /// The disc's normal (any length but zero).
        normal: Vec3,
        /// Radius (>= 0).
        radius: f64,
    },
    /// Uniform by angle on a circle (a disc's edge).
    Circle {
        /// Centre of the circle.
        center: Vec3,
        /// The circle's normal (any length but zero).
        normal: Vec3,
        /// Radius (>= 0).
        radius: f64,
    },
    /// Uniform in a cone's volume, or by area on its side: a frustum from `base` along `axis`,
    /// `base_radius` wide at the base and `top_radius` at the top (0 for a pointed cone).
    Cone {
        /// Centre of the base.
        base: Vec3,
        /// From the base towards the top (any length but zero).
        axis: Vec3,
        /// Distance from the base to the top (>= 0).
        height: f64,
        /// Radius at the base (>= 0).
        base_radius: f64,
        /// Radius at the top (>= 0).
        #[serde(default)]
        top_radius: f64,
        /// On the side (not the end caps) instead of in the volume.
        #[serde(default)]
        surface: bool,
    },
    /// Uniform in a torus's volume, or by area on its surface: a ring about `axis` through
    /// `center`, its tube's centre circle `radius` wide and the tube `tube` thick (tube <
    /// radius).
    Torus {
        /// Centre of the ring.
        center: Vec3,
        /// The ring's axis (any length but zero).
        axis: Vec3,
        /// Radius of the tube's centre circle (> 0).
        radius: f64,
        /// Radius of the tube (>= 0, less than `radius`).
        tube: f64,
        /// On the surface instead of in the volume.
        #[serde(default)]
        surface: bool,
    },
    /// A position written as an expression of type vec3 (`features/emitter/expression.rs`): it
    /// reads `t` (the spawn's time), `rand(k)`, the params and `dt`.
    Custom(String),
    /// Deterministic lattice points, handed out in x-then-y-then-z order.
    Grid {
        /// First lattice corner.
        min: Vec3,
        /// Last lattice corner.
        max: Vec3,
        /// Points per axis (>= 1 each).
        counts: Counts,
    },
    /// Listed points, handed out in order.
    Points(Vec<Vec3>),
    /// Uniform by area on a mesh's surface, or in its volume (see
    /// `features::mesh_emission`).
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
        /// Spawn in the closed mesh's volume instead of on its surface.
        #[serde(default)]
        volume: bool,
        /// With `volume`: field cells along the mesh's longest side (4 to 128).
        #[serde(default = "default_resolution")]
        resolution: u32,
        /// The placed triangles, read by `read_mesh_shapes` before the checks.
        #[serde(skip)]
        surface: Option<Arc<MeshSurface>>,
    },
}

fn default_resolution() -> u32 {
    32
}

impl Shape {
    /// Reads a `Mesh` shape's file into its placed surface (relative to `base_dir`), recording
    /// what is wrong in `c` at `path` (the shape) `.file`; other shapes read nothing.
    pub(crate) fn read_mesh(&mut self, path: &ValuePath, base_dir: Option<&Path>, c: &mut Checker) {
        let Shape::Mesh {
            file,
            offset,
            scale,
            rotation,
            volume,
            resolution,
            surface,
        } = self
        else {
            return;
        };
        // A bad placement is reported by the checks, at its field.
        if !(offset.d().is_finite()
            && rotation.d().is_finite()
            && scale.is_finite()
            && *scale > 0.0)
            || (*volume && !(4..=crate::base::sdf::MAX_RESOLUTION).contains(resolution))
        {
            return;
        }
        let volume = volume.then_some(*resolution);
        match place(file, base_dir, (*offset, *scale, *rotation), volume) {
            Ok(placed) => *surface = Some(Arc::new(placed)),
            Err(message) => c.error(&path.variant("Mesh").field("file"), message),
        }
    }

    /// Records in `c` what is wrong with the shape at `path` (the emitter's `shape`); `names`
    /// are what its expression may name.
    pub(crate) fn check(&self, c: &mut Checker, path: &ValuePath, names: Names) {
        match self {
            Shape::Custom(text) => {
                SpawnValue::Position.check(text, &path.variant("Custom").inner(), c, names);
            }
            Shape::Point(p) => {
                c.vec3(&path.variant("Point").inner(), *p);
            }
            Shape::Sphere { center, radius, .. } => {
                let s = path.variant("Sphere");
                c.vec3(&s.field("center"), *center);
                c.non_negative(&s.field("radius"), *radius);
            }
            Shape::Box { min, max, .. } => c.box_corners(&path.variant("Box"), *min, *max),
            Shape::Disc {
                center,
                normal,
                radius,
            }
            | Shape::Circle {
                center,
                normal,
                radius,
            } => {
                let name = match self {
                    Shape::Disc { .. } => "Disc",
                    _ => "Circle",
                };
                let s = path.variant(name);
                c.vec3(&s.field("center"), *center);
                c.direction(&s.field("normal"), *normal);
                c.non_negative(&s.field("radius"), *radius);
            }
            Shape::Cone {
                base,
                axis,
                height,
                base_radius,
                top_radius,
                ..
            } => {
                let s = path.variant("Cone");
                c.vec3(&s.field("base"), *base);
                c.direction(&s.field("axis"), *axis);
                c.non_negative(&s.field("height"), *height);
                c.non_negative(&s.field("base_radius"), *base_radius);
                c.non_negative(&s.field("top_radius"), *top_radius);
            }
            Shape::Torus {
                center,
                axis,
                radius,
                tube,
                ..
            } => {
                let s = path.variant("Torus");
                c.vec3(&s.field("center"), *center);
                c.direction(&s.field("axis"), *axis);
                if c.positive(&s.field("radius"), *radius)
                    && c.non_negative(&s.field("tube"), *tube)
                    && tube >= radius
                {
                    c.error(
                        &s.field("tube"),
                        format!("must be less than radius ({radius}), got {tube}: a ring that thick has no hole"),
                    );
                }
            }
            Shape::Grid { min, max, counts } => {
                let s = path.variant("Grid");
                c.box_corners(&s, *min, *max);
                let n = [counts.0, counts.1, counts.2];
                if n.contains(&0) {
                    c.error(
                        &s.field("counts"),
                        format!(
                            "every count must be >= 1, got ({}, {}, {})",
                            n[0], n[1], n[2]
                        ),
                    );
                } else if n
                    .iter()
                    .try_fold(1u64, |acc, &k| acc.checked_mul(u64::from(k)))
                    .is_none_or(|total| total > u64::from(u32::MAX))
                {
                    c.error(&s.field("counts"), "holds more than 4294967295 points");
                }
            }
            Shape::Points(ps) => {
                let s = path.variant("Points");
                if ps.is_empty() {
                    c.error(&s, "must list at least one point");
                }
                for (i, p) in ps.iter().enumerate() {
                    c.vec3(&s.inner().index(i), *p);
                }
            }
            Shape::Mesh {
                offset,
                scale,
                rotation,
                volume,
                resolution,
                surface,
                ..
            } => {
                let s = path.variant("Mesh");
                let placed =
                    crate::base::mesh::check_placement(&s, c, (*offset, *scale, *rotation));
                let max = crate::base::sdf::MAX_RESOLUTION;
                if *volume && !(4..=max).contains(resolution) {
                    c.error(
                        &s.field("resolution"),
                        format!("resolution is the field cells along the mesh's longest side, 4 to {max}, got {resolution}"),
                    );
                } else if placed && *scale > 0.0 && surface.is_none() {
                    c.error(&s.field("file"), "the mesh was not read");
                }
            }
        }
    }

    /// The shape's lowered form (after [`Shape::check`] passed), for an effect of `seed_mix`.
    pub(crate) fn lower(&self, names: Names, seed_mix: u32) -> ShapeIr {
        match self {
            Shape::Custom(text) => {
                let expr = SpawnValue::Position
                    .compile(text, names)
                    .expect("checked before lowering");
                // One that folds to a constant is that point.
                if let Node::Vector(p) = expr.node {
                    return ShapeIr::Point(p);
                }
                // Its extent, for the precision warnings and the stiffness estimates: the
                // farthest of a sample of spawns at t = 0.
                let extent = (0..ESTIMATE_SPAWNS)
                    .map(|id| {
                        expression::value(
                            &expr,
                            seed_mix,
                            (id, id),
                            (0.0, DVec3::ZERO),
                            DVec3::ZERO,
                        )
                    })
                    .map(|x| x.abs().max_element())
                    .fold(0.0, f64::max);
                ShapeIr::Custom { expr, extent }
            }
            Shape::Point(p) => ShapeIr::Point(p.d()),
            Shape::Sphere {
                center,
                radius,
                surface: false,
            } => ShapeIr::Sphere {
                center: center.d(),
                radius: *radius,
            },
            Shape::Sphere {
                center,
                radius,
                surface: true,
            } => ShapeIr::SphereSurface {
                center: center.d(),
                radius: *radius,
            },
            Shape::Box { min, max, surface } => {
                let (min, max) = (min.d(), max.d());
                match box_face_thresholds(min, max).filter(|_| *surface) {
                    Some(thresholds) => ShapeIr::BoxSurface {
                        min,
                        max,
                        thresholds,
                    },
                    None => ShapeIr::Box { min, max },
                }
            }
            Shape::Disc {
                center,
                normal,
                radius,
            }
            | Shape::Circle {
                center,
                normal,
                radius,
            } => {
                let (center, radius) = (center.d(), *radius);
                let basis = Basis::around(safe_normalize(normal.d()));
                match self {
                    Shape::Disc { .. } => ShapeIr::Disc {
                        center,
                        radius,
                        basis,
                    },
                    _ => ShapeIr::Circle {
                        center,
                        radius,
                        basis,
                    },
                }
            }
            Shape::Torus {
                center,
                axis,
                radius,
                tube,
                surface,
            } => {
                let axis = safe_normalize(axis.d());
                ShapeIr::Torus(super::torus::TorusIr {
                    center: center.d(),
                    axis,
                    basis: Basis::around(axis),
                    radius: *radius,
                    tube: *tube,
                    surface: *surface,
                })
            }
            Shape::Cone {
                base,
                axis,
                height,
                base_radius,
                top_radius,
                surface,
            } => {
                let axis = safe_normalize(axis.d());
                let wide = base_radius.max(*top_radius);
                ShapeIr::Cone(ConeIr {
                    base: base.d(),
                    axis,
                    basis: Basis::around(axis),
                    height: *height,
                    wide,
                    ratio: match wide > 0.0 {
                        true => base_radius.min(*top_radius) / wide,
                        false => 1.0,
                    },
                    narrow_top: top_radius < base_radius,
                    surface: *surface,
                })
            }
            Shape::Grid { min, max, counts } => {
                let n = [counts.0, counts.1, counts.2];
                let (lo, hi) = (min.d().to_array(), max.d().to_array());
                let mut origin = [0.0; 3];
                let mut step = [0.0; 3];
                for a in 0..3 {
                    if n[a] == 1 {
                        origin[a] = 0.5 * (lo[a] + hi[a]);
                    } else {
                        origin[a] = lo[a];
                        step[a] = (hi[a] - lo[a]) / f64::from(n[a] - 1);
                    }
                }
                ShapeIr::Grid {
                    origin: DVec3::from_array(origin),
                    step: DVec3::from_array(step),
                    counts: n,
                }
            }
            Shape::Points(ps) => ShapeIr::Points(ps.iter().map(|p| p.d()).collect()),
            Shape::Mesh { surface, .. } => ShapeIr::Mesh(
                surface
                    .clone()
                    .expect("the checks refuse a Mesh shape whose file was not read"),
            ),
        }
    }
}
