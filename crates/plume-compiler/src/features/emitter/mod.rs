//! Emitters: where and how fast particles spawn. The schema (`Emitter`, `Shape`, `Velocity`)
//! and its lowered form (`EmitterIr`, `ShapeIr`, `VelocityIr`), which events reuse for the
//! particles they spawn and custom forces read for their stiffness estimates.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::lifetime::LifetimeSteps;
use crate::base::path::ValuePath;
use crate::base::values::{Counts, Range, Vec3};
use crate::features::mesh_emission::{place, MeshSurface};

/// One particle source.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Emitter {
    /// Particles spawned once, at step 0.
    #[serde(default)]
    pub burst: u32,
    /// Particles per second; the fractional remainder carries to the next step.
    #[serde(default)]
    pub rate: f64,
    /// Where particles start.
    pub shape: Shape,
    /// How fast and where they start moving.
    pub velocity: Velocity,
    /// Lifetime range in seconds; `None` lives forever.
    #[serde(default)]
    pub lifetime: Option<Range>,
}

/// Spawn positions.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// Every particle at one point.
    Point(Vec3),
    /// Uniform in the ball's volume.
    Sphere {
        /// Centre of the ball.
        center: Vec3,
        /// Radius (>= 0).
        radius: f64,
    },
    /// Uniform in an axis-aligned box.
    Box {
        /// Lower corner.
        min: Vec3,
        /// Upper corner.
        max: Vec3,
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
    /// [`crate::features::mesh_emission`]).
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
        /// The placed triangles, read by [`read_mesh_shapes`] before the checks.
        #[serde(skip)]
        surface: Option<Arc<MeshSurface>>,
    },
}

fn default_resolution() -> u32 {
    32
}

/// Spawn velocities.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Velocity {
    /// The same velocity for every particle.
    Constant(Vec3),
    /// Uniform directions within a cone around `axis`.
    Cone {
        /// Cone axis (any length but zero).
        axis: Vec3,
        /// Half-angle in degrees, in [0, 180].
        angle: f64,
        /// Speed range (m/s).
        speed: Range,
    },
    /// Away from the shape's centre.
    Radial {
        /// Speed range (m/s).
        speed: Range,
    },
    /// Along the surface's normal where the particle spawns (a `Mesh` shape only).
    Normal {
        /// Speed range (m/s); negative goes inward.
        speed: Range,
    },
}

/// One emitter.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterIr {
    /// Spawned at step 0.
    pub burst: u32,
    /// Per second.
    pub rate: f64,
    /// Spawn position.
    pub shape: ShapeIr,
    /// Spawn velocity.
    pub velocity: VelocityIr,
    /// Lifetime range (s).
    pub lifetime: Option<(f64, f64)>,
    /// The lifetime as whole steps (see [`crate::base::lifetime`]).
    pub lifetime_steps: Option<LifetimeSteps>,
}

/// An orthonormal pair spanning the plane perpendicular to a unit vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// First tangent.
    pub t1: DVec3,
    /// Second tangent (`n × t1`).
    pub t2: DVec3,
}

impl Basis {
    /// A right-handed basis around unit `n`.
    pub fn around(n: DVec3) -> Self {
        let helper = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
        let t1 = n.cross(helper).normalize();
        let t2 = n.cross(t1);
        Self { t1, t2 }
    }
}

/// Spawn shape in the IR.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeIr {
    /// One point.
    Point(DVec3),
    /// Uniform in a ball.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// Uniform in a box.
    Box {
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
    },
    /// Uniform in a disc.
    Disc {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Tangents of the disc's plane.
        basis: Basis,
    },
    /// Lattice: point (ix, iy, iz) is `origin + i * step` per axis.
    Grid {
        /// Position of lattice point (0, 0, 0).
        origin: DVec3,
        /// Spacing per axis (0 on an axis with one point).
        step: DVec3,
        /// Points per axis.
        counts: [u32; 3],
    },
    /// Listed points, in order.
    Points(Vec<DVec3>),
    /// On a mesh's surface or in its volume.
    Mesh(Arc<MeshSurface>),
}

impl ShapeIr {
    /// The centre that radial velocities point away from.
    pub fn center(&self) -> DVec3 {
        match self {
            ShapeIr::Point(p) => *p,
            ShapeIr::Sphere { center, .. } | ShapeIr::Disc { center, .. } => *center,
            ShapeIr::Box { min, max } => (*min + *max) * 0.5,
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let n = DVec3::new(
                    f64::from(counts[0] - 1),
                    f64::from(counts[1] - 1),
                    f64::from(counts[2] - 1),
                );
                *origin + *step * n * 0.5
            }
            ShapeIr::Points(ps) => ps.iter().copied().sum::<DVec3>() / ps.len().max(1) as f64,
            ShapeIr::Mesh(m) => m.center,
        }
    }

    /// Below this squared distance (m²) from the shape's centre, a Radial velocity has no
    /// direction and draws a random one. Relative to the shape's size, so that the GPU's f32
    /// positions (off by a few ulps of the coordinates) and the reference's f64 ones make the
    /// same choice: a Grid or Points spawn at the centre itself is never pushed by f32 rounding.
    pub fn radial_center_eps2(&self) -> f64 {
        (4e-6 * self.extent().max(1.0)).powi(2)
    }

    /// The farthest any spawn position lies from the origin (for precision warnings).
    pub fn extent(&self) -> f64 {
        match self {
            ShapeIr::Point(p) => p.abs().max_element(),
            ShapeIr::Sphere { center, radius } | ShapeIr::Disc { center, radius, .. } => {
                center.abs().max_element() + radius
            }
            ShapeIr::Box { min, max } => min.abs().max(max.abs()).max_element(),
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let last = *origin
                    + *step
                        * DVec3::new(
                            f64::from(counts[0] - 1),
                            f64::from(counts[1] - 1),
                            f64::from(counts[2] - 1),
                        );
                origin.abs().max(last.abs()).max_element()
            }
            ShapeIr::Points(ps) => ps.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max),
            ShapeIr::Mesh(m) => m.extent,
        }
    }
}

/// Spawn velocity in the IR.
#[derive(Clone, Debug, PartialEq)]
pub enum VelocityIr {
    /// Fixed velocity.
    Constant(DVec3),
    /// Uniform in a cone: cos θ uniform in [cos angle, 1].
    Cone {
        /// Unit axis.
        axis: DVec3,
        /// Tangents of the axis.
        basis: Basis,
        /// Cosine of the half-angle.
        cos_angle: f64,
        /// Speed range.
        speed: (f64, f64),
    },
    /// Away from the shape's centre.
    Radial {
        /// Speed range.
        speed: (f64, f64),
    },
    /// Along the spawn surface's normal.
    Normal {
        /// Speed range.
        speed: (f64, f64),
    },
}

impl VelocityIr {
    /// The largest spawn speed.
    pub fn max_speed(&self) -> f64 {
        match self {
            VelocityIr::Constant(v) => v.length(),
            VelocityIr::Cone { speed, .. }
            | VelocityIr::Radial { speed }
            | VelocityIr::Normal { speed } => speed.0.abs().max(speed.1.abs()),
        }
    }
}

/// Reads every `Mesh` spawn shape's file into its placed surface (files relative to
/// `base_dir`), recording what is wrong in `c` at the shape's `file`.
pub fn read_mesh_shapes(emitters: &mut [Emitter], base_dir: Option<&Path>, c: &mut Checker) {
    for (i, emitter) in emitters.iter_mut().enumerate() {
        let Shape::Mesh {
            file,
            offset,
            scale,
            rotation,
            volume,
            resolution,
            surface,
        } = &mut emitter.shape
        else {
            continue;
        };
        // A bad placement is reported by the checks, at its field.
        if !(offset.d().is_finite()
            && rotation.d().is_finite()
            && scale.is_finite()
            && *scale > 0.0)
            || (*volume && !(4..=crate::base::sdf::MAX_RESOLUTION).contains(resolution))
        {
            continue;
        }
        let volume = volume.then_some(*resolution);
        match place(file, base_dir, (*offset, *scale, *rotation), volume) {
            Ok(placed) => *surface = Some(Arc::new(placed)),
            Err(message) => c.error(
                &ValuePath::root()
                    .field("emitters")
                    .index(i)
                    .field("shape")
                    .variant("Mesh")
                    .field("file"),
                message,
            ),
        }
    }
}

/// Where emitter `e`'s mesh surface starts in the `spawn_data` binding (the surfaces of the
/// emitters before it come first).
pub fn spawn_data_offset(emitters: &[EmitterIr], e: usize) -> u32 {
    emitters[..e]
        .iter()
        .map(|em| match &em.shape {
            ShapeIr::Mesh(m) => m.data_len(),
            _ => 0,
        })
        .sum()
}

/// The `spawn_data` binding's contents: every mesh surface's thresholds and triangles, in
/// emitter order; None when no emitter spawns on a mesh.
pub fn spawn_data(emitters: &[EmitterIr]) -> Option<Vec<u32>> {
    let mut out = Vec::new();
    let mut any = false;
    for em in emitters {
        if let ShapeIr::Mesh(m) = &em.shape {
            out.extend(m.data());
            any = true;
        }
    }
    any.then_some(out)
}
