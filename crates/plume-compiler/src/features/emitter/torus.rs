//! A torus spawn shape: uniform in a ring's volume, or by area on its surface, about an axis.
//! Its WGSL (`TorusIr::emit_wgsl`, inside an emitter's `emit_E`) and its f64 twin
//! (`TorusIr::sample`) read the same three POSITION draws.
//!
//! A point is at angle φ about the axis, distance ρ from the tube's centre circle and angle θ
//! around the tube: `centre + (R + ρ cos θ) d(φ) + ρ sin θ n`. The volume's element is
//! ρ (R + ρ cos θ) dρ dθ dφ and the surface's (ρ = r) r (R + r cos θ) dθ dφ, so φ is uniform,
//! ρ² is uniform in [0, r²] (in the volume), and θ has density ∝ 1 + k cos θ with k = ρ / R < 1:
//! its distribution function (θ + π + k sin θ) / 2π is inverted by Newton's method from
//! θ = 2π u − π, eight steps (Kepler's equation; k < 1 keeps the slope above 1 − k), so the outer
//! side of the ring gets its larger share exactly rather than by rejection.

use std::f64::consts::PI;

use glam::DVec3;

use crate::base::rng::{stream, wgsl_unit3, ParticleDraws};
use crate::base::writer::{f32_lit, vec3_lit, Writer};
use crate::features::emitter::Basis;

/// Newton steps that invert θ's distribution function.
const NEWTON_STEPS: u32 = 8;

/// A torus's spawn volume or surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TorusIr {
    /// Centre of the ring.
    pub center: DVec3,
    /// Unit axis (the ring lies in the plane it is normal to).
    pub axis: DVec3,
    /// Tangents of that plane.
    pub basis: Basis,
    /// Radius of the tube's centre circle (R).
    pub radius: f64,
    /// Radius of the tube (r < R).
    pub tube: f64,
    /// On the surface instead of in the volume.
    pub surface: bool,
}

impl TorusIr {
    /// Emits the statements that set `s.x`: the WGSL twin of [`Self::sample`].
    pub(crate) fn emit_wgsl(&self, w: &mut Writer) {
        let (two_pi, pi) = (f32_lit(2.0 * PI), f32_lit(PI));
        w.line(format!("let u = {};", wgsl_unit3(stream::POSITION)));
        w.line(format!("let phi = {two_pi} * u.x - {pi};"));
        match self.surface {
            true => w.line(format!("let rho = {};", f32_lit(self.tube))),
            false => w.line(format!("let rho = {} * sqrt(u.y);", f32_lit(self.tube))),
        }
        w.comment("θ: density ∝ 1 + k cos θ, its distribution inverted by Newton's method.");
        w.line(format!("let bend = rho / {};", f32_lit(self.radius)));
        w.line(format!("let goal = {two_pi} * u.z - {pi};"));
        w.line("var theta = goal;");
        w.block(format!("for (var n = 0u; n < {NEWTON_STEPS}u; n++)"), |w| {
            w.line(format!(
                "theta = clamp(theta - (theta + bend * sin(theta) - goal) / (1.0 + bend * cos(theta)), -{pi}, {pi});"
            ));
        });
        w.line(format!(
            "s.x = {} + ({} + rho * cos(theta)) * (cos(phi) * {} + sin(phi) * {}) + rho * sin(theta) * {};",
            vec3_lit(self.center),
            f32_lit(self.radius),
            vec3_lit(self.basis.t1),
            vec3_lit(self.basis.t2),
            vec3_lit(self.axis)
        ));
    }

    /// The spawn position of the particle drawing `d`.
    pub(crate) fn sample(&self, d: &ParticleDraws) -> DVec3 {
        let u = d.unit3(stream::POSITION);
        let phi = 2.0 * PI * u.x - PI;
        let rho = match self.surface {
            true => self.tube,
            false => self.tube * u.y.sqrt(),
        };
        let k = rho / self.radius;
        let a = 2.0 * PI * u.z - PI;
        let mut theta = a;
        for _ in 0..NEWTON_STEPS {
            theta =
                (theta - (theta + k * theta.sin() - a) / (1.0 + k * theta.cos())).clamp(-PI, PI);
        }
        self.center
            + (self.radius + rho * theta.cos())
                * (phi.cos() * self.basis.t1 + phi.sin() * self.basis.t2)
            + rho * theta.sin() * self.axis
    }
}
