//! `render.glow`: bloom in `plume render`'s images. The schema lives here; the runtime's
//! glow pass (HDR target, threshold, blur, composite) reads it.

use serde::Deserialize;

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
