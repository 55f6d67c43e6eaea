//! `Plane`: a half-space boundary. The segment enters the forbidden side where its signed
//! distance to the plane changes from >= 0 to < 0.

use glam::DVec3;
use serde::Deserialize;

use super::{check_bounce, ColliderIr, Hit, Surface};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{vec3_lit, Writer};

/// `Plane(...)` as effect files write it: a half-space boundary; particles live on the side
/// the normal points to.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    /// Any point on the plane.
    pub point: Vec3,
    /// Points into the allowed side (any length but zero).
    pub normal: Vec3,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
}

/// The fields of [`Plane`].
pub(crate) const FIELDS: &[&str] = &["point", "normal", "restitution", "friction"];

impl Plane {
    /// Checks the point, the normal (not zero) and the bounce; `path` names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("point"), self.point);
        c.direction(&path.field("normal"), self.normal);
        check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked plane (its normal made unit).
    pub(crate) fn lower(&self) -> ColliderIr {
        ColliderIr {
            surface: Surface::Plane(PlaneIr {
                point: self.point.d(),
                normal: crate::features::forces::safe_normalize(self.normal.d()),
            }),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// A collision plane with a unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneIr {
    /// A point on the plane.
    pub point: DVec3,
    /// Unit normal, into the allowed side.
    pub normal: DVec3,
}

impl PlaneIr {
    /// Signed distance of `x` from the plane (positive on the allowed side).
    pub fn distance(&self, x: DVec3) -> f64 {
        (x - self.point).dot(self.normal)
    }

    /// The crossing of segment `a` -> `b` from the allowed side.
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let (d0, d1) = (self.distance(a), self.distance(b));
        (d0 >= 0.0 && d1 < 0.0).then(|| Hit {
            s: d0 / (d0 - d1),
            normal: self.normal,
        })
    }

    /// A point behind the plane moved onto it, `margin` in front.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        let d = self.distance(x);
        if d < 0.0 {
            x + (margin - d) * self.normal
        } else {
            x
        }
    }

    /// The WGSL twins of [`PlaneIr::hit`] and `push_out`.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let (p, n) = (vec3_lit(self.point), vec3_lit(self.normal));
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line(format!("let d0 = dot(a - {p}, {n});"));
                w.line(format!("let d1 = dot(b - {p}, {n});"));
                w.block("if (d0 >= 0.0 && d1 < 0.0)", |w| {
                    w.line(format!("return vec4<f32>(d0 / (d0 - d1), {n});"));
                });
                w.line(format!("return vec4<f32>(2.0, {n});"));
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.line(format!("let d = dot(x - {p}, {n});"));
                w.line(format!(
                    "return select(x, x + (margin - d) * {n}, d < 0.0);"
                ));
            },
        );
    }
}
