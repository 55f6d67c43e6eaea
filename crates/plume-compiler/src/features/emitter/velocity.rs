//! Spawn velocities: the schema, its checks, its lowered form, and each velocity's WGSL
//! (`VelocityIr::emit_wgsl`) beside its f64 twin (`VelocityIr::sample`). They read the VELOCITY
//! stream (3 to 5), and Radial at the shape's very centre the FALLBACK_DIRECTION stream.

use std::f64::consts::PI;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::{stream, ParticleDraws};
use crate::base::values::{safe_normalize, Range, Vec3};
use crate::base::writer::{f32_lit, vec3_lit, Writer};
use crate::expr::typed::Node;
use crate::expr::{Expr, Names};
use crate::features::emitter::expression::{self, SpawnValue, ESTIMATE_SPAWNS};
use crate::features::emitter::shape_ir::ShapeIr;
use crate::features::emitter::Basis;

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
    /// Around `axis` through the shape's centre, counter-clockwise seen from the axis's tip:
    /// along axis × (x − centre).
    Tangent {
        /// The axis turned about (any length but zero).
        axis: Vec3,
        /// Speed range (m/s); negative turns the other way.
        speed: Range,
    },
    /// A velocity written as an expression of type vec3 (`features/emitter/expression.rs`): it
    /// reads `x` (the spawn position), `t`, `rand(k)`, the params and `dt`.
    Custom(String),
}

/// Spawn velocity in the IR.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum VelocityIr {
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
    /// Around a unit axis through the shape's centre.
    Tangent {
        /// Unit axis.
        axis: DVec3,
        /// Speed range.
        speed: (f64, f64),
    },
    /// An expression of the spawn position, time and random numbers.
    Custom {
        /// The typed, folded expression.
        expr: Expr,
        /// The fastest of a sample of its spawns.
        max_speed: f64,
    },
}

impl Velocity {
    /// Records in `c` what is wrong with the velocity at `path` (the emitter's `velocity`),
    /// given the emitter's shape; `names` are what its expression may name.
    pub(crate) fn check(&self, c: &mut Checker, path: &ValuePath, on_mesh: bool, names: Names) {
        match self {
            Velocity::Custom(text) => {
                SpawnValue::Velocity.check(text, &path.variant("Custom").inner(), c, names);
            }
            Velocity::Constant(v) => {
                c.vec3(&path.variant("Constant").inner(), *v);
            }
            Velocity::Cone { axis, angle, speed } => {
                let v = path.variant("Cone");
                c.direction(&v.field("axis"), *axis);
                c.within(&v.field("angle"), *angle, 0.0, 180.0);
                check_speed(c, &v.field("speed"), *speed);
            }
            Velocity::Radial { speed } => {
                check_speed(c, &path.variant("Radial").field("speed"), *speed);
            }
            Velocity::Normal { speed } => {
                let v = path.variant("Normal");
                check_speed(c, &v.field("speed"), *speed);
                if !on_mesh {
                    c.error(
                        &v,
                        "Normal follows the surface a particle spawns on: it needs a `Mesh` shape (use Radial or Cone for other shapes)",
                    );
                }
            }
            Velocity::Tangent { axis, speed } => {
                let v = path.variant("Tangent");
                c.direction(&v.field("axis"), *axis);
                c.range(&v.field("speed"), *speed);
            }
        }
    }

    /// The velocity's lowered form (after [`Velocity::check`] passed), for particles that
    /// spawn on `shape` in an effect of `seed_mix`.
    pub(crate) fn lower(&self, names: Names, shape: &ShapeIr, seed_mix: u32) -> VelocityIr {
        match self {
            Velocity::Custom(text) => {
                let expr = SpawnValue::Velocity
                    .compile(text, names)
                    .expect("checked before lowering");
                // One that folds to a constant is that velocity.
                if let Node::Vector(v) = expr.node {
                    return VelocityIr::Constant(v);
                }
                // The fastest of a sample of spawns at t = 0, for the stiffness estimates.
                let max_speed = (0..ESTIMATE_SPAWNS)
                    .map(|id| {
                        let d = ParticleDraws { seed_mix, id };
                        let (x, _) = shape.sample(&d, id, (0.0, DVec3::ZERO));
                        expression::value(&expr, seed_mix, (id, 0), (0.0, DVec3::ZERO), x).length()
                    })
                    .fold(0.0, f64::max);
                VelocityIr::Custom { expr, max_speed }
            }
            Velocity::Constant(v) => VelocityIr::Constant(v.d()),
            Velocity::Cone { axis, angle, speed } => {
                let axis = safe_normalize(axis.d());
                VelocityIr::Cone {
                    axis,
                    basis: Basis::around(axis),
                    cos_angle: angle.to_radians().cos(),
                    speed: (speed.0, speed.1),
                }
            }
            Velocity::Radial { speed } => VelocityIr::Radial {
                speed: (speed.0, speed.1),
            },
            Velocity::Normal { speed } => VelocityIr::Normal {
                speed: (speed.0, speed.1),
            },
            Velocity::Tangent { axis, speed } => VelocityIr::Tangent {
                axis: safe_normalize(axis.d()),
                speed: (speed.0, speed.1),
            },
        }
    }
}

fn check_speed(c: &mut Checker, path: &ValuePath, speed: Range) {
    if c.range(path, speed) && speed.0 < 0.0 {
        c.error(
            &path.component(0, "min"),
            format!("must be >= 0 m/s, got {}", speed.0),
        );
    }
}

impl VelocityIr {
    /// The largest spawn speed.
    pub(crate) fn max_speed(&self) -> f64 {
        match self {
            VelocityIr::Constant(v) => v.length(),
            VelocityIr::Cone { speed, .. }
            | VelocityIr::Radial { speed }
            | VelocityIr::Normal { speed }
            | VelocityIr::Tangent { speed, .. } => speed.0.abs().max(speed.1.abs()),
            VelocityIr::Custom { max_speed, .. } => *max_speed,
        }
    }

    /// Emits the statements that set `s.v` inside an emitter's `emit_e(id, k, step)`, after
    /// `shape`'s, for steps of `dt`: the WGSL twin of [`Self::sample`].
    pub(crate) fn emit_wgsl(&self, w: &mut Writer, shape: &ShapeIr, dt: f64) {
        let two_pi = f32_lit(2.0 * PI);
        let pi = f32_lit(PI);
        match self {
            VelocityIr::Custom { expr, .. } => expression::emit(w, expr, "s.v", dt),
            VelocityIr::Constant(v) => w.line(format!("s.v = {};", vec3_lit(*v))),
            VelocityIr::Cone {
                axis,
                basis,
                cos_angle,
                speed,
            } => {
                w.comment("Uniform on the spherical cap: cos(theta) = 1 - w, w uniform in [0, 1 - cos(angle)];");
                w.comment("sin(theta) = sqrt(w (2 - w)) avoids the cancellation of 1 - cos².");
                w.line(format!(
                    "let w = rand_unit(id, {}u) * {};",
                    stream::VELOCITY,
                    f32_lit(1.0 - cos_angle)
                ));
                w.line("let cos_t = 1.0 - w;");
                w.line("let sin_t = sqrt(max(0.0, w * (2.0 - w)));");
                w.line(format!(
                    "let psi = {two_pi} * rand_unit(id, {}u) - {pi};",
                    stream::VELOCITY + 1
                ));
                emit_speed(w, *speed);
                w.line(format!(
                    "s.v = speed * (cos_t * {} + sin_t * (cos(psi) * {} + sin(psi) * {}));",
                    vec3_lit(*axis),
                    vec3_lit(basis.t1),
                    vec3_lit(basis.t2)
                ));
            }
            VelocityIr::Radial { speed } => {
                emit_speed(w, *speed);
                w.line(format!("let out = s.x - {};", vec3_lit(shape.center())));
                w.line("let out2 = dot(out, out);");
                w.line("var dir: vec3<f32>;");
                w.block(
                    format!("if (out2 > {})", f32_lit(shape.radial_center_eps2())),
                    |w| w.line("dir = out * inverseSqrt(out2);"),
                );
                w.block("else", |w| {
                    w.comment("At the centre itself: a uniformly random direction instead.");
                    w.line(format!(
                        "let cz = 1.0 - 2.0 * rand_unit(id, {}u);",
                        stream::FALLBACK_DIRECTION
                    ));
                    w.line(format!(
                        "let phi = {two_pi} * rand_unit(id, {}u) - {pi};",
                        stream::FALLBACK_DIRECTION + 1
                    ));
                    w.line("let sz = sqrt(max(0.0, 1.0 - cz * cz));");
                    w.line("dir = vec3<f32>(sz * cos(phi), sz * sin(phi), cz);");
                });
                w.line("s.v = speed * dir;");
            }
            VelocityIr::Normal { speed } => {
                emit_speed(w, *speed);
                w.line("s.v = speed * surface_normal;");
            }
            VelocityIr::Tangent { axis, speed } => {
                emit_speed(w, *speed);
                w.comment("On the axis itself there is no tangent: the particle starts at rest.");
                w.line(format!(
                    "let around = cross({}, s.x - {});",
                    vec3_lit(*axis),
                    vec3_lit(shape.center())
                ));
                w.line("let around2 = dot(around, around);");
                w.line(format!(
                    "s.v = select(vec3<f32>(0.0), speed * around * inverseSqrt(max(around2, 1e-30)), around2 > {});",
                    f32_lit(shape.radial_center_eps2())
                ));
            }
        }
    }

    /// The spawn velocity of the particle drawing `d`, spawned at `x` on `shape` at time `t`
    /// in a frame at `origin` (`normal`: the surface's normal there, zero off a mesh): the
    /// f64 twin of `emit_wgsl`.
    pub(crate) fn sample(
        &self,
        d: &ParticleDraws,
        shape: &ShapeIr,
        (x, normal): (DVec3, DVec3),
        (t, origin): (f64, DVec3),
    ) -> DVec3 {
        let speed = |s: (f64, f64)| s.0 + (s.1 - s.0) * d.unit(stream::VELOCITY + 2);
        match self {
            VelocityIr::Custom { expr, .. } => {
                expression::value(expr, d.seed_mix, (d.id, 0), (t, origin), x)
            }
            VelocityIr::Constant(v) => *v,
            VelocityIr::Cone {
                axis,
                basis,
                cos_angle,
                speed: s,
            } => {
                let w = d.unit(stream::VELOCITY) * (1.0 - cos_angle);
                let cos_t = 1.0 - w;
                let sin_t = (w * (2.0 - w)).max(0.0).sqrt();
                let psi = 2.0 * PI * d.unit(stream::VELOCITY + 1) - PI;
                speed(*s) * (cos_t * *axis + sin_t * (psi.cos() * basis.t1 + psi.sin() * basis.t2))
            }
            VelocityIr::Radial { speed: s } => {
                let out = x - shape.center();
                let out2 = out.length_squared();
                let dir = if out2 > shape.radial_center_eps2() {
                    out / out2.sqrt()
                } else {
                    let cz = 1.0 - 2.0 * d.unit(stream::FALLBACK_DIRECTION);
                    let phi = 2.0 * PI * d.unit(stream::FALLBACK_DIRECTION + 1) - PI;
                    let sz = (1.0 - cz * cz).max(0.0).sqrt();
                    DVec3::new(sz * phi.cos(), sz * phi.sin(), cz)
                };
                speed(*s) * dir
            }
            VelocityIr::Normal { speed: s } => speed(*s) * normal,
            VelocityIr::Tangent { axis, speed: s } => {
                let around = axis.cross(x - shape.center());
                let around2 = around.length_squared();
                match around2 > shape.radial_center_eps2() {
                    true => speed(*s) * around / around2.sqrt(),
                    false => DVec3::ZERO,
                }
            }
        }
    }
}

fn emit_speed(w: &mut Writer, speed: (f64, f64)) {
    w.line(format!(
        "let speed = {} + {} * rand_unit(id, {}u);",
        f32_lit(speed.0),
        f32_lit(speed.1 - speed.0),
        stream::VELOCITY + 2
    ));
}
