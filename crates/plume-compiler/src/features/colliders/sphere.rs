//! `Sphere`: a ball that particles stay outside of, or (with `inside: true`) a spherical
//! container they stay in. The swept test solves |a + s (b - a) - c|² = r² for the first
//! root in [0, 1], in the cancellation-free form of the quadratic formula.

use glam::DVec3;
use serde::Deserialize;

use super::{check_bounce, ColliderIr, Hit, Surface};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// A sphere collider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereIr {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
    /// Particles are kept inside (a container) rather than outside.
    pub inside: bool,
}

/// `Sphere(...)` as effect files write it: a ball that particles stay outside of, or inside
/// with `inside: true`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (m), > 0.
    pub radius: f64,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
    /// Keep particles inside (a container) instead of outside.
    #[serde(default)]
    pub inside: bool,
}

/// The fields of [`Sphere`].
pub(crate) const FIELDS: &[&str] = &["center", "radius", "restitution", "friction", "inside"];

impl Sphere {
    /// Checks the centre, the radius (> 0) and the bounce; `path` names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("center"), self.center);
        c.positive(&path.field("radius"), self.radius);
        check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked sphere.
    pub(crate) fn lower(&self) -> ColliderIr {
        ColliderIr {
            surface: Surface::Sphere(SphereIr {
                center: self.center.d(),
                radius: self.radius,
                inside: self.inside,
            }),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// `v / |v|`, or +y when `v` is too short to normalise (a particle at the very centre).
fn direction(v: DVec3) -> DVec3 {
    let l2 = v.length_squared();
    if l2 > 1e-20 {
        v / l2.sqrt()
    } else {
        DVec3::Y
    }
}

impl SphereIr {
    /// The first contact of segment `a` -> `b`.
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let d = b - a;
        let aa = d.dot(d);
        if aa <= 0.0 {
            return None;
        }
        let m = a - self.center;
        let bb = m.dot(d);
        let cc = m.dot(m) - self.radius * self.radius;
        let s = if self.inside {
            if cc > 0.0 {
                return None;
            }
            let sq = (bb * bb - aa * cc).max(0.0).sqrt();
            if bb <= 0.0 {
                (sq - bb) / aa
            } else {
                -cc / (bb + sq)
            }
        } else {
            if cc < 0.0 || bb >= 0.0 {
                return None;
            }
            let disc = bb * bb - aa * cc;
            if disc.is_nan() || disc < 0.0 {
                return None;
            }
            cc / (disc.sqrt() - bb)
        };
        if s.is_nan() || s > 1.0 {
            return None;
        }
        let out = direction(a + d * s - self.center);
        Some(Hit {
            s,
            normal: if self.inside { -out } else { out },
        })
    }

    /// A point on the forbidden side moved onto the surface, `margin` into the allowed side.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        let m = x - self.center;
        let l2 = m.dot(m);
        let r2 = self.radius * self.radius;
        if self.inside && l2 > r2 {
            self.center + direction(m) * (self.radius - margin).max(0.0)
        } else if !self.inside && l2 < r2 {
            self.center + direction(m) * (self.radius + margin)
        } else {
            x
        }
    }

    /// Whether `x` is on the allowed side.
    pub fn allows(&self, x: DVec3) -> bool {
        let l2 = (x - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if self.inside {
            l2 <= r2
        } else {
            l2 >= r2
        }
    }

    /// The WGSL twins of [`SphereIr::hit`] and `push_out`.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let c = vec3_lit(self.center);
        let r = f32_lit(self.radius);
        let r2 = f32_lit(self.radius * self.radius);
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.line("let d = b - a;");
                w.line("let aa = dot(d, d);");
                w.block("if (aa <= 0.0)", |w| w.line("return none;"));
                w.line(format!("let m = a - {c};"));
                w.line("let bb = dot(m, d);");
                w.line(format!("let cc = dot(m, m) - {r2};"));
                w.line("var s = 2.0;");
                if self.inside {
                    w.block("if (cc > 0.0)", |w| w.line("return none;"));
                    w.line("let sq = sqrt(max(bb * bb - aa * cc, 0.0));");
                    w.line("s = select(-cc / (bb + sq), (sq - bb) / aa, bb <= 0.0);");
                } else {
                    w.block("if (cc < 0.0 || bb >= 0.0)", |w| w.line("return none;"));
                    w.line("let disc = bb * bb - aa * cc;");
                    w.block("if (!(disc >= 0.0))", |w| w.line("return none;"));
                    w.line("s = cc / (sqrt(disc) - bb);");
                }
                w.block("if (!(s <= 1.0))", |w| w.line("return none;"));
                w.line(format!("let o = a + d * s - {c};"));
                w.line("let l2 = dot(o, o);");
                w.line(
                    "let out = select(vec3<f32>(0.0, 1.0, 0.0), o * inverseSqrt(max(l2, 1e-20)), l2 > 1e-20);",
                );
                let sign = if self.inside { "-" } else { "" };
                w.line(format!("return vec4<f32>(s, {sign}out);"));
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.line(format!("let m = x - {c};"));
                w.line("let l2 = dot(m, m);");
                w.line(
                    "let dir = select(vec3<f32>(0.0, 1.0, 0.0), m * inverseSqrt(max(l2, 1e-20)), l2 > 1e-20);",
                );
                if self.inside {
                    w.line(format!(
                        "return select(x, {c} + dir * max({r} - margin, 0.0), l2 > {r2});"
                    ));
                } else {
                    w.line(format!(
                        "return select(x, {c} + dir * ({r} + margin), l2 < {r2});"
                    ));
                }
            },
        );
    }
}
