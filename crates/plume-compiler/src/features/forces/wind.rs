//! Wind: `a = strength * normalize(direction) + noise * N(x, t)`, N a smooth noise field with
//! components in [-1, 1]. Lowers to a constant term plus, when noise != 0, a [`NoiseTerm`].

use serde::Deserialize;

use super::constant::ConstantTerm;
use super::noise::NoiseTerm;
use super::{safe_normalize, Term};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;

fn default_noise_scale() -> f64 {
    2.0
}

/// `Wind(direction, strength, noise)` as written (`noise_scale` is an optional extension).
/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["direction", "strength", "noise", "noise_scale"];

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wind {
    /// Direction the wind blows toward (any length but zero).
    pub direction: Vec3,
    /// Steady acceleration along `direction` (m/s²).
    pub strength: f64,
    /// Amplitude of the noise acceleration (m/s²), >= 0; 0 means none.
    #[serde(default)]
    pub noise: f64,
    /// Size of one noise cell in metres (> 0); default 2.
    #[serde(default = "default_noise_scale")]
    pub noise_scale: f64,
}

impl Wind {
    /// Checks the direction, strength and noise parameters.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.direction(&path.field("direction"), self.direction);
        c.finite(&path.field("strength"), self.strength);
        c.non_negative(&path.field("noise"), self.noise);
        c.positive(&path.field("noise_scale"), self.noise_scale);
    }

    /// Lowers to a constant push and, when `noise != 0`, a noise term.
    pub fn lower(&self, origin: usize, seed: u32) -> Vec<Term> {
        let mut terms = vec![Term::Constant(ConstantTerm {
            accel: self.strength * safe_normalize(self.direction.d()),
            origins: vec![origin],
        })];
        if self.noise != 0.0 {
            terms.push(Term::Noise(NoiseTerm::new(
                self.noise,
                self.noise_scale,
                seed,
                origin,
            )));
        }
        terms
    }
}
