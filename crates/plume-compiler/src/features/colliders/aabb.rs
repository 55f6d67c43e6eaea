//! `Box`: an axis-aligned box that particles stay outside of, or (with `inside: true`) a box
//! container they stay in. The swept test is the slab test: the segment enters the solid box
//! at the latest of its per-axis entry times and leaves the container at the earliest of its
//! per-axis exit times. Ties go to the lower axis, in f64 and WGSL alike.

use glam::DVec3;
use serde::Deserialize;

use super::{check_bounce, ColliderIr, Hit, Surface};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// A displacement component at most this small does not cross a slab.
const TINY: f64 = 1e-30;

/// A box collider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxIr {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
    /// Particles are kept inside (a container) rather than outside.
    pub inside: bool,
}

/// `Box(...)` as effect files write it: an axis-aligned box that particles stay outside of,
/// or inside with `inside: true`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner (greater than `min` on every axis).
    pub max: Vec3,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
    /// Keep particles inside (a container) instead of outside.
    #[serde(default)]
    pub inside: bool,
}

/// The fields of [`Aabb`].
pub(crate) const FIELDS: &[&str] = &["min", "max", "restitution", "friction", "inside"];

impl Aabb {
    /// Checks the corners and the bounce; `path` names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        check_corners(path, c, self.min, self.max);
        check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked box.
    pub(crate) fn lower(&self) -> ColliderIr {
        ColliderIr {
            surface: Surface::Box(BoxIr {
                min: self.min.d(),
                max: self.max.d(),
                inside: self.inside,
            }),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// Checks the corners: finite and `min < max` on every axis (a flat box has no inside).
fn check_corners(path: &ValuePath, c: &mut Checker, min: Vec3, max: Vec3) {
    let ok = c.vec3(&path.field("min"), min) & c.vec3(&path.field("max"), max);
    if ok && (min.0 >= max.0 || min.1 >= max.1 || min.2 >= max.2) {
        c.error(
            &path.field("min"),
            format!(
                "min must be < max on every axis, got min ({}, {}, {}) and max ({}, {}, {})",
                min.0, min.1, min.2, max.0, max.1, max.2
            ),
        );
    }
}

fn axis(i: usize, sign: f64) -> DVec3 {
    let mut n = DVec3::ZERO;
    n[i] = sign;
    n
}

impl BoxIr {
    fn contains(&self, x: DVec3) -> bool {
        x.cmpge(self.min).all() && x.cmple(self.max).all()
    }

    /// The first contact of segment `a` -> `b`.
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let d = b - a;
        if self.inside {
            if !self.contains(a) {
                return None;
            }
            let mut exit = f64::INFINITY;
            let mut normal = None;
            for i in 0..3 {
                if d[i].abs() <= TINY {
                    continue;
                }
                let wall = if d[i] > 0.0 { self.max[i] } else { self.min[i] };
                let t = (wall - a[i]) / d[i];
                if t < exit {
                    exit = t;
                    normal = Some(axis(i, -d[i].signum()));
                }
            }
            let normal = normal?;
            (exit <= 1.0).then_some(Hit { s: exit, normal })
        } else {
            let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
            let mut normal = None;
            for i in 0..3 {
                if d[i].abs() <= TINY {
                    if a[i] < self.min[i] || a[i] > self.max[i] {
                        return None;
                    }
                    continue;
                }
                let t1 = (self.min[i] - a[i]) / d[i];
                let t2 = (self.max[i] - a[i]) / d[i];
                if t1.min(t2) > enter {
                    enter = t1.min(t2);
                    normal = Some(axis(i, -d[i].signum()));
                }
                exit = exit.min(t1.max(t2));
            }
            let normal = normal?;
            (enter <= exit && (0.0..=1.0).contains(&enter)).then_some(Hit { s: enter, normal })
        }
    }

    /// A point on the forbidden side moved onto the nearest face, `margin` beyond it.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        if self.inside {
            if self.contains(x) {
                return x;
            }
            let centre = 0.5 * (self.min + self.max);
            let lo = (self.min + DVec3::splat(margin)).min(centre);
            let hi = (self.max - DVec3::splat(margin)).max(centre);
            x.clamp(lo, hi)
        } else {
            if !(x.cmpgt(self.min).all() && x.cmplt(self.max).all()) {
                return x;
            }
            // The face of least penetration, lower axis and min face first on ties.
            let mut best = (f64::INFINITY, 0, false);
            for i in 0..3 {
                for (depth, to_max) in [(x[i] - self.min[i], false), (self.max[i] - x[i], true)] {
                    if depth < best.0 {
                        best = (depth, i, to_max);
                    }
                }
            }
            let mut out = x;
            let (_, i, to_max) = best;
            out[i] = if to_max {
                self.max[i] + margin
            } else {
                self.min[i] - margin
            };
            out
        }
    }

    /// Whether `x` is on the allowed side.
    pub fn allows(&self, x: DVec3) -> bool {
        if self.inside {
            self.contains(x)
        } else {
            !(x.cmpgt(self.min).all() && x.cmplt(self.max).all())
        }
    }

    /// The WGSL twins of [`BoxIr::hit`] and `push_out`.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let (mn, mx) = (vec3_lit(self.min), vec3_lit(self.max));
        let tiny = f32_lit(TINY);
        const AXES: [&str; 3] = ["x", "y", "z"];
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.line("let d = b - a;");
                w.line(format!("let lo = {mn};"));
                w.line(format!("let hi = {mx};"));
                w.line("var n = vec3<f32>(0.0);");
                if self.inside {
                    w.block("if (any(a < lo) || any(a > hi))", |w| w.line("return none;"));
                    w.line("var exit = 3.0e38;");
                    for (k, c) in AXES.iter().enumerate() {
                        w.block(format!("if (abs(d.{c}) > {tiny})"), |w| {
                            w.line(format!(
                                "let t = (select(lo.{c}, hi.{c}, d.{c} > 0.0) - a.{c}) / d.{c};"
                            ));
                            w.block("if (t < exit)", |w| {
                                w.line("exit = t;");
                                w.line(format!(
                                    "n = vec3<f32>(0.0); n[{k}] = -sign(d.{c});"
                                ));
                            });
                        });
                    }
                    w.block("if (exit > 1.0 || all(n == vec3<f32>(0.0)))", |w| {
                        w.line("return none;")
                    });
                    w.line("return vec4<f32>(exit, n);");
                } else {
                    w.line("var enter = -3.0e38;");
                    w.line("var exit = 3.0e38;");
                    for (k, c) in AXES.iter().enumerate() {
                        w.block(format!("if (abs(d.{c}) <= {tiny})"), |w| {
                            w.block(format!("if (a.{c} < lo.{c} || a.{c} > hi.{c})"), |w| {
                                w.line("return none;")
                            });
                        });
                        w.block("else", |w| {
                            w.line(format!("let t1 = (lo.{c} - a.{c}) / d.{c};"));
                            w.line(format!("let t2 = (hi.{c} - a.{c}) / d.{c};"));
                            w.block("if (min(t1, t2) > enter)", |w| {
                                w.line("enter = min(t1, t2);");
                                w.line(format!(
                                    "n = vec3<f32>(0.0); n[{k}] = -sign(d.{c});"
                                ));
                            });
                            w.line("exit = min(exit, max(t1, t2));");
                        });
                    }
                    w.block(
                        "if (all(n == vec3<f32>(0.0)) || enter > exit || enter < 0.0 || enter > 1.0)",
                        |w| w.line("return none;"),
                    );
                    w.line("return vec4<f32>(enter, n);");
                }
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.line(format!("let lo = {mn};"));
                w.line(format!("let hi = {mx};"));
                if self.inside {
                    w.block("if (all(x >= lo) && all(x <= hi))", |w| w.line("return x;"));
                    w.line(format!(
                        "let centre = {};",
                        vec3_lit(0.5 * (self.min + self.max))
                    ));
                    w.line("return clamp(x, min(lo + vec3<f32>(margin), centre), max(hi - vec3<f32>(margin), centre));");
                } else {
                    w.block("if (!(all(x > lo) && all(x < hi)))", |w| w.line("return x;"));
                    w.line("var best = 3.0e38;");
                    w.line("var out = x;");
                    for (k, c) in AXES.iter().enumerate() {
                        w.block(format!("if (x.{c} - lo.{c} < best)"), |w| {
                            w.line(format!("best = x.{c} - lo.{c};"));
                            w.line(format!("out = x; out[{k}] = lo.{c} - margin;"));
                        });
                        w.block(format!("if (hi.{c} - x.{c} < best)"), |w| {
                            w.line(format!("best = hi.{c} - x.{c};"));
                            w.line(format!("out = x; out[{k}] = hi.{c} + margin;"));
                        });
                    }
                    w.line("return out;");
                }
            },
        );
    }
}
