//! The thesis's gravity point with a soft core: d = center - x, r = |d|,
//! a = strength * clamp((range - r) / range, 0, 1) * d / max(r, core).
//!
//! Why a core: the thesis's pull has constant magnitude right up to the centre, so it flips
//! direction within one step as a particle passes through, and every fixed-step integrator gains
//! or loses energy at each pass (without a core, a particle released at half range escapes
//! within 60 s at every step size tried). Inside `core` the pull falls linearly to zero instead,
//! so the field is Lipschitz with constant strength / core, the centre is a harmonic well with
//! ω = sqrt(strength / core), and the integrators' ω*h limits are real limits.

use glam::DVec3;
use serde::Deserialize;

use super::{CoreWell, ForceTerm, Stiffness};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// The default core radius is `range / DEFAULT_CORE_DIVISOR`.
pub(crate) const DEFAULT_CORE_DIVISOR: f64 = 10.0;

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["center", "range", "strength", "core"];

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attractor {
    /// The point particles are pulled toward.
    pub center: Vec3,
    /// Distance (m) at which the pull fades to zero; > 0.
    pub range: f64,
    /// Pull at the core's edge (m/s²); negative repels.
    pub strength: f64,
    /// Radius (m) inside which the pull falls linearly to 0 at the centre; in (0, range].
    /// Defaults to range / 10.
    #[serde(default, deserialize_with = "crate::base::values::plain_some")]
    pub core: Option<f64>,
}

impl Attractor {
    /// Checks a finite centre, `range > 0`, a finite strength and `0 < core <= range`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.vec3(&path.field("center"), self.center);
        c.positive(&path.field("range"), self.range);
        c.finite(&path.field("strength"), self.strength);
        if let Some(core) = self.core {
            c.core_radius(&path.field("core"), core, self.range);
        }
    }

    /// The core radius, written or defaulted.
    pub fn core(&self) -> f64 {
        self.core.unwrap_or(self.range / DEFAULT_CORE_DIVISOR)
    }

    /// Lowers to an attractor term.
    pub(crate) fn lower(&self, origin: usize) -> AttractorTerm {
        AttractorTerm {
            center: self.center.d(),
            range: self.range,
            strength: self.strength,
            core: self.core(),
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
    /// Core radius (m), in (0, range].
    pub core: f64,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl ForceTerm for AttractorTerm {
    fn bakeable(&self) -> bool {
        true
    }
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Attractor center = ({}, {}, {}) range = {} strength = {} core = {}",
            self.center.x, self.center.y, self.center.z, self.range, self.strength, self.core
        )
    }
    fn can_act(&self) -> bool {
        self.strength != 0.0
    }
    fn stiffness(&self) -> Stiffness {
        // The steepest the field gets is strength / core per metre, at the centre and on the
        // core's edge (tangentially). A repeller has no oscillation: its linearisation grows
        // exponentially in the physics itself, and the integrators follow that growth.
        if self.strength > 0.0 {
            Stiffness::Oscillation((self.strength / self.core).sqrt())
        } else {
            Stiffness::None
        }
    }
    fn core_well(&self) -> Option<CoreWell> {
        (self.strength > 0.0).then(|| CoreWell::of(self.strength, self.core, self.range))
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.block("", |w| {
            w.line(format!("let d = {} - x;", vec3_lit(self.center)));
            w.line("let r = length(d);");
            w.line(format!(
                "let fall = clamp(({} - r) * {}, 0.0, 1.0);",
                f32_lit(self.range),
                f32_lit(1.0 / self.range)
            ));
            // The divisor stays > 0 even at the centre (core is floored at the smallest normal
            // f32), and d / max(r, core) has length <= 1, so a huge strength cannot overflow
            // into inf * 0.
            w.line(format!(
                "a += ({} * fall) * (d / max(r, {}));",
                f32_lit(self.strength),
                f32_lit(self.core.max(f64::from(f32::MIN_POSITIVE)))
            ));
        });
    }
    fn accel(&self, x: DVec3, _v: DVec3, _t: f64) -> DVec3 {
        let d = self.center - x;
        let r = d.length();
        let fall = ((self.range - r) / self.range).clamp(0.0, 1.0);
        self.strength * fall * (d / r.max(self.core))
    }
}
