//! The thesis's vortex, with its bugs fixed. â = normalize(axis), rel = x - center,
//! h = rel·â, radial = rel - h â, ρ = |radial|, r̂ = radial / ρ (0 when ρ = 0).
//! Only 0 < h < height feels it. range_h = range ((height - h) / height)^curve,
//! w = clamp((range_h - ρ) / range_h, 0, 1) (0 when range_h = 0),
//! a = w (spin (â × r̂) - pull r̂ + down â). Positive spin is counter-clockwise seen from +axis.

use glam::DVec3;
use serde::Deserialize;

use super::{safe_normalize, ForceTerm, Stiffness};
use crate::check::Checker;
use crate::path::ValuePath;
use crate::schema::Vec3;
use crate::wgsl::writer::{f32_lit, vec3_lit, Writer};

/// Below this squared radial distance (m²) the radial direction is undefined (r̂ = 0).
pub const AXIS_EPS2: f64 = 1e-24;
/// Below this funnel radius (m) the vortex has closed (w = 0).
pub const RANGE_EPS: f64 = 1e-12;

/// `Vortex(...)` as written.
/// Field names, as written in effect files.
pub const FIELDS: &[&str] = &[
    "center", "axis", "range", "height", "spin", "pull", "down", "curve",
];

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vortex {
    /// A point on the axis, at the funnel's base.
    pub center: Vec3,
    /// Axis direction (any length but zero).
    pub axis: Vec3,
    /// Funnel radius at the base (m), > 0.
    pub range: f64,
    /// Funnel height along the axis (m), > 0.
    pub height: f64,
    /// Tangential acceleration (m/s²); positive is counter-clockwise seen from +axis.
    pub spin: f64,
    /// Acceleration toward the axis (m/s²).
    #[serde(default)]
    pub pull: f64,
    /// Acceleration along +axis (m/s²); negative sucks down.
    #[serde(default)]
    pub down: f64,
    /// Funnel shape exponent (>= 0): 0 a cylinder, 1 a cone.
    #[serde(default = "one")]
    pub curve: f64,
}

fn one() -> f64 {
    1.0
}

impl Vortex {
    /// Checks geometry (> 0 range and height, non-zero axis) and finite strengths.
    pub fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("center"), self.center);
        c.direction(&path.field("axis"), self.axis);
        c.positive(&path.field("range"), self.range);
        c.positive(&path.field("height"), self.height);
        c.finite(&path.field("spin"), self.spin);
        c.finite(&path.field("pull"), self.pull);
        c.finite(&path.field("down"), self.down);
        c.non_negative(&path.field("curve"), self.curve);
    }

    /// Lowers to a vortex term with a unit axis.
    pub fn lower(&self, origin: usize) -> VortexTerm {
        VortexTerm {
            center: self.center.d(),
            axis: safe_normalize(self.axis.d()),
            range: self.range,
            height: self.height,
            spin: self.spin,
            pull: self.pull,
            down: self.down,
            curve: self.curve,
            origins: vec![origin],
        }
    }
}

/// The vortex in the IR (axis normalised).
#[derive(Clone, Debug, PartialEq)]
pub struct VortexTerm {
    /// Base point (m).
    pub center: DVec3,
    /// Unit axis.
    pub axis: DVec3,
    /// Base radius (m).
    pub range: f64,
    /// Height (m).
    pub height: f64,
    /// Tangential acceleration (m/s²).
    pub spin: f64,
    /// Inward acceleration (m/s²).
    pub pull: f64,
    /// Axial acceleration (m/s²).
    pub down: f64,
    /// Funnel exponent.
    pub curve: f64,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl VortexTerm {
    fn funnel_wgsl(&self) -> String {
        let ratio = format!(
            "(({} - h) * {})",
            f32_lit(self.height),
            f32_lit(1.0 / self.height)
        );
        let scaled = if self.curve == 0.0 {
            String::from("1.0")
        } else if self.curve == 1.0 {
            ratio
        } else {
            // The base is > 0 here (h < height), so pow is well defined.
            format!("pow({ratio}, {})", f32_lit(self.curve))
        };
        format!("{} * {scaled}", f32_lit(self.range))
    }
}

impl ForceTerm for VortexTerm {
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Vortex center = ({}, {}, {}) axis = ({}, {}, {}) range = {} height = {} spin = {} pull = {} down = {} curve = {}",
            self.center.x, self.center.y, self.center.z, self.axis.x, self.axis.y, self.axis.z,
            self.range, self.height, self.spin, self.pull, self.down, self.curve
        )
    }
    fn can_act(&self) -> bool {
        self.spin != 0.0 || self.pull != 0.0 || self.down != 0.0
    }
    fn stiffness_field(&self) -> &'static str {
        if self.pull.abs() > self.spin.abs() {
            "pull"
        } else {
            "spin"
        }
    }
    fn stiffness(&self) -> Stiffness {
        // Spin and pull both change by about their size over one funnel radius.
        Stiffness::Oscillation((self.spin.abs().max(self.pull.abs()) / self.range).sqrt())
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.block("", |w| {
            w.line(format!("let rel = x - {};", vec3_lit(self.center)));
            w.line(format!("let axis = {};", vec3_lit(self.axis)));
            w.line("let h = dot(rel, axis);");
            w.block(
                format!("if (h > 0.0 && h < {})", f32_lit(self.height)),
                |w| {
                    w.line(format!("let range_h = {};", self.funnel_wgsl()));
                    w.block(format!("if (range_h > {})", f32_lit(RANGE_EPS)), |w| {
                        w.line("let radial = rel - h * axis;");
                        w.line("let rho2 = dot(radial, radial);");
                        w.line("var r_hat = vec3<f32>(0.0);");
                        w.line("var rho = 0.0;");
                        w.block(format!("if (rho2 > {})", f32_lit(AXIS_EPS2)), |w| {
                            w.line("rho = sqrt(rho2);");
                            w.line("r_hat = radial / rho;");
                        });
                        w.line("let wgt = clamp((range_h - rho) / range_h, 0.0, 1.0);");
                        w.line(format!(
                            "a += wgt * ({} * cross(axis, r_hat) - {} * r_hat + {} * axis);",
                            f32_lit(self.spin),
                            f32_lit(self.pull),
                            f32_lit(self.down)
                        ));
                    });
                },
            );
        });
    }
    fn accel(&self, x: DVec3, _v: DVec3, _t: f64) -> DVec3 {
        let rel = x - self.center;
        let h = rel.dot(self.axis);
        if !(h > 0.0 && h < self.height) {
            return DVec3::ZERO;
        }
        let range_h = self.range * ((self.height - h) / self.height).powf(self.curve);
        if range_h <= RANGE_EPS {
            return DVec3::ZERO;
        }
        let radial = rel - h * self.axis;
        let rho2 = radial.length_squared();
        let (rho, r_hat) = if rho2 > AXIS_EPS2 {
            let rho = rho2.sqrt();
            (rho, radial / rho)
        } else {
            (0.0, DVec3::ZERO)
        };
        let w = ((range_h - rho) / range_h).clamp(0.0, 1.0);
        w * (self.spin * self.axis.cross(r_hat) - self.pull * r_hat + self.down * self.axis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positive_spin_is_counter_clockwise_from_above() {
        let v = Vortex {
            center: Vec3(0.0, 0.0, 0.0),
            axis: Vec3(0.0, 2.0, 0.0),
            range: 2.0,
            height: 4.0,
            spin: 1.0,
            pull: 0.0,
            down: 0.0,
            curve: 1.0,
        }
        .lower(0);
        // At +x, counter-clockwise seen from +y means moving toward -z.
        let a = v.accel(DVec3::new(0.5, 1.0, 0.0), DVec3::ZERO, 0.0);
        assert!(a.z < 0.0 && a.x.abs() < 1e-12);
        // On the axis: no spin, no NaN.
        let a = v.accel(DVec3::new(0.0, 1.0, 0.0), DVec3::ZERO, 0.0);
        assert_eq!(a, DVec3::ZERO);
        // Outside the height band: nothing.
        assert_eq!(
            v.accel(DVec3::new(0.5, 5.0, 0.0), DVec3::ZERO, 0.0),
            DVec3::ZERO
        );
    }
}
