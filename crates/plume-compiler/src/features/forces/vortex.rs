//! The thesis's vortex, with its bugs fixed. â = normalize(axis), rel = x - center,
//! h = rel·â, radial = rel - h â, ρ = |radial|. Only 0 < h < height feels it.
//! range_h = max(range ((height - h) / height)^curve, core), w = clamp((range_h - ρ) / range_h, 0, 1),
//! a = w (spin (â × radial) - pull radial) / max(ρ, core) + w down â.
//! Positive spin is counter-clockwise seen from +axis.
//!
//! Why a core (as for the attractor): the thesis's spin and pull keep full strength up to the
//! axis, so they flip direction within a step as a particle crosses it. Inside `core` they fall
//! linearly to 0 on the axis, and the funnel never narrows below the core, so the field's slope is
//! bounded by max(|spin|, |pull|) / core everywhere.

use glam::DVec3;
use serde::Deserialize;

use super::{safe_normalize, CoreWell, ForceTerm, Stiffness};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// The default core radius is `range / DEFAULT_CORE_DIVISOR`.
pub(crate) const DEFAULT_CORE_DIVISOR: f64 = 10.0;

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &[
    "center", "axis", "range", "height", "spin", "pull", "down", "curve", "core",
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
    /// Radius (m) inside which spin and pull fall linearly to 0 on the axis, and below which the
    /// funnel does not narrow; in (0, range]. Defaults to range / 10.
    #[serde(default, deserialize_with = "crate::base::values::plain_some")]
    pub core: Option<f64>,
}

fn one() -> f64 {
    1.0
}

impl Vortex {
    /// Checks geometry (> 0 range and height, non-zero axis) and finite strengths.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("center"), self.center);
        c.direction(&path.field("axis"), self.axis);
        c.positive(&path.field("range"), self.range);
        c.positive(&path.field("height"), self.height);
        c.finite(&path.field("spin"), self.spin);
        c.finite(&path.field("pull"), self.pull);
        c.finite(&path.field("down"), self.down);
        c.non_negative(&path.field("curve"), self.curve);
        if let Some(core) = self.core {
            c.core_radius(&path.field("core"), core, self.range);
        }
    }

    /// The core radius, written or defaulted.
    pub fn core(&self) -> f64 {
        self.core.unwrap_or(self.range / DEFAULT_CORE_DIVISOR)
    }

    /// Lowers to a vortex term with a unit axis.
    pub(crate) fn lower(&self, origin: usize) -> VortexTerm {
        VortexTerm {
            center: self.center.d(),
            axis: safe_normalize(self.axis.d()),
            range: self.range,
            height: self.height,
            spin: self.spin,
            pull: self.pull,
            down: self.down,
            curve: self.curve,
            core: self.core(),
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
    /// Core radius (m), in (0, range].
    pub core: f64,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl VortexTerm {
    /// The core as written into WGSL: floored at the smallest normal f32 so it stays > 0.
    fn core_f32(&self) -> f64 {
        self.core.max(f64::from(f32::MIN_POSITIVE))
    }

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
        format!(
            "max({} * {scaled}, {})",
            f32_lit(self.range),
            f32_lit(self.core_f32())
        )
    }
}

impl ForceTerm for VortexTerm {
    fn bakeable(&self) -> bool {
        true
    }
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Vortex center = ({}, {}, {}) axis = ({}, {}, {}) range = {} height = {} spin = {} pull = {} down = {} curve = {} core = {}",
            self.center.x, self.center.y, self.center.z, self.axis.x, self.axis.y, self.axis.z,
            self.range, self.height, self.spin, self.pull, self.down, self.curve, self.core
        )
    }
    fn can_act(&self) -> bool {
        self.spin != 0.0 || self.pull != 0.0 || self.down != 0.0
    }
    fn stiffness_field(&self) -> &'static str {
        "pull"
    }
    fn stiffness(&self) -> Stiffness {
        // Only a positive pull makes an oscillation: inside the core it is a harmonic well
        // across the axis with ω² = pull / core. Spin is a rotation field with no oscillating
        // mode: its linearisation grows in the physics itself (at sqrt(spin / 2 core)), and the
        // integrators follow that growth at any step (docs/accuracy.md), so it sets no limit.
        if self.pull > 0.0 {
            Stiffness::Oscillation((self.pull / self.core).sqrt())
        } else {
            Stiffness::None
        }
    }
    fn core_well(&self) -> Option<CoreWell> {
        // Across the axis at the funnel's base, where the well is widest and deepest.
        (self.pull > 0.0).then(|| CoreWell::of(self.pull, self.core, self.range))
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.block("", |w| {
            w.line(format!("let rel = x - {};", vec3_lit(self.center)));
            w.line(format!("let axis = {};", vec3_lit(self.axis)));
            w.line("let h = dot(rel, axis);");
            w.block(
                format!("if (h > 0.0 && h < {})", f32_lit(self.height)),
                |w| {
                    // range_h >= core > 0 and max(rho, core) > 0: no division by zero, and
                    // radial / max(rho, core) has length <= 1, so huge strengths cannot make
                    // inf * 0.
                    w.line(format!("let range_h = {};", self.funnel_wgsl()));
                    w.line("let radial = rel - h * axis;");
                    w.line("let rho = length(radial);");
                    w.line("let wgt = clamp((range_h - rho) / range_h, 0.0, 1.0);");
                    w.line(format!(
                        "let r_in = radial / max(rho, {});",
                        f32_lit(self.core_f32())
                    ));
                    w.line(format!(
                        "a += wgt * ({} * cross(axis, r_in) - {} * r_in + {} * axis);",
                        f32_lit(self.spin),
                        f32_lit(self.pull),
                        f32_lit(self.down)
                    ));
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
        let range_h =
            (self.range * ((self.height - h) / self.height).powf(self.curve)).max(self.core);
        let radial = rel - h * self.axis;
        let rho = radial.length();
        let w = ((range_h - rho) / range_h).clamp(0.0, 1.0);
        let r_in = radial / rho.max(self.core);
        w * (self.spin * self.axis.cross(r_in) - self.pull * r_in + self.down * self.axis)
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
            core: None,
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
