//! The thesis's gravity point: d = center - x, r = |d|,
//! a = strength * clamp((range - r) / range, 0, 1) * d / r, and 0 at r = 0.

use glam::DVec3;
use serde::Deserialize;

use super::{ForceTerm, Stiffness};
use crate::check::Checker;
use crate::path::ValuePath;
use crate::schema::Vec3;
use crate::wgsl::writer::{f32_lit, vec3_lit, Writer};

/// Below this squared distance (m²) the direction is undefined and the force is zero.
pub const CENTER_EPS2: f64 = 1e-24;

/// `Attractor(center, range, strength)` as written.
/// Field names, as written in effect files.
pub const FIELDS: &[&str] = &["center", "range", "strength"];

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attractor {
    /// The point particles are pulled toward.
    pub center: Vec3,
    /// Distance (m) at which the pull fades to zero; > 0.
    pub range: f64,
    /// Pull at the centre (m/s²); negative repels.
    pub strength: f64,
}

impl Attractor {
    /// Checks a finite centre, `range > 0` and a finite strength.
    pub fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("center"), self.center);
        c.positive(&path.field("range"), self.range);
        c.finite(&path.field("strength"), self.strength);
    }

    /// Lowers to an attractor term.
    pub fn lower(&self, origin: usize) -> AttractorTerm {
        AttractorTerm {
            center: self.center.d(),
            range: self.range,
            strength: self.strength,
            origins: vec![origin],
        }
    }
}

/// The attractor in the IR.
#[derive(Clone, Debug, PartialEq)]
pub struct AttractorTerm {
    /// Centre (m).
    pub center: DVec3,
    /// Range (m), > 0.
    pub range: f64,
    /// Strength (m/s²).
    pub strength: f64,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl ForceTerm for AttractorTerm {
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Attractor center = ({}, {}, {}) range = {} strength = {}",
            self.center.x, self.center.y, self.center.z, self.range, self.strength
        )
    }
    fn can_act(&self) -> bool {
        self.strength != 0.0
    }
    fn stiffness(&self) -> Stiffness {
        // Linearised: the pull grows by strength/range per metre toward the centre.
        Stiffness::Oscillation((self.strength.abs() / self.range).sqrt())
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.block("", |w| {
            w.line(format!("let d = {} - x;", vec3_lit(self.center)));
            w.line("let r2 = dot(d, d);");
            w.block(format!("if (r2 > {})", f32_lit(CENTER_EPS2)), |w| {
                w.line("let r = sqrt(r2);");
                w.line(format!(
                    "let fall = clamp(({} - r) * {}, 0.0, 1.0);",
                    f32_lit(self.range),
                    f32_lit(1.0 / self.range)
                ));
                w.line(format!("a += ({} * fall / r) * d;", f32_lit(self.strength)));
            });
        });
    }
    fn accel(&self, x: DVec3, _v: DVec3, _t: f64) -> DVec3 {
        let d = self.center - x;
        let r2 = d.length_squared();
        if r2 <= CENTER_EPS2 {
            return DVec3::ZERO;
        }
        let r = r2.sqrt();
        let fall = ((self.range - r) / self.range).clamp(0.0, 1.0);
        self.strength * fall / r * d
    }
}
