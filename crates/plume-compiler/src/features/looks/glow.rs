//! `render.glow`: bloom in `plume render`'s images. The schema lives here; the runtime's
//! glow pass (HDR target, threshold, blur, composite) reads it.

use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;

/// Bloom in `plume render`'s images (`render.glow`); an embedding host does its own
/// post-processing.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Glow {
    /// Light above this level (per channel, in the HDR image) glows.
    #[serde(default = "default_glow_threshold")]
    pub threshold: f64,
    /// How much of the blurred light is added back.
    #[serde(default = "default_glow_strength")]
    pub strength: f64,
    /// The blur's standard deviation, as a fraction of the image height.
    #[serde(default = "default_glow_radius")]
    pub radius: f64,
    /// Light above this level (per channel) blooms as this level does (the bloom's clamp):
    /// where thousands of additive layers pile up, the halo spreads no wider than light at
    /// this level would. The image shows no light past 1 anyway, so the compute renderer stops
    /// adding light into a pixel once every channel reaches it. The default, f16's largest
    /// finite value, is the HDR image's own limit: no clamp of its own.
    #[serde(default = "default_glow_clamp")]
    pub clamp: f64,
}

impl Glow {
    /// Checks the threshold and strength (>= 0), the blur's radius (a wider one costs 6 σ
    /// texel reads a pixel in each direction) and the clamp (below 1 it would dim the image
    /// itself; past f16's largest value the HDR image clamps anyway); `path` names
    /// `render.glow`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.non_negative(&path.field("threshold"), self.threshold);
        c.non_negative(&path.field("strength"), self.strength);
        c.within(&path.field("radius"), self.radius, 1e-4, 0.05);
        c.within(&path.field("clamp"), self.clamp, 1.0, GLOW_CLAMP_MOST);
    }
}

fn default_glow_threshold() -> f64 {
    0.8
}

fn default_glow_strength() -> f64 {
    1.0
}

fn default_glow_radius() -> f64 {
    0.01
}

/// The default `clamp`: f16's largest finite value, the most an HDR image pixel holds.
pub(crate) const GLOW_CLAMP_MOST: f64 = 65504.0;

fn default_glow_clamp() -> f64 {
    GLOW_CLAMP_MOST
}
