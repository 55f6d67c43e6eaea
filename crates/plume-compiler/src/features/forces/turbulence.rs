//! Turbulence: curl noise (Bridson, Hourihan and Nordenstam 2007, "Curl-noise for procedural
//! fluid flow"). The acceleration is the curl of a vector potential ψ whose three components
//! are independent 3D gradient (Perlin) noises, so it is divergence-free by construction:
//! particles swirl without bunching up or thinning out.
//!
//! `a(x, t) = strength · Σ_o 2^-o · (∇ × ψ_o)(2^o x / scale)`: each octave halves the scale
//! and the weight. The curl comes from the noise's analytic gradient (no finite differences),
//! and one PCG hash per lattice corner feeds all three components (12 of its bits pick three
//! of Perlin's 12 edge gradients): 8 hashes per octave. With `evolution` > 0 the potential
//! blends between independent noise slices one 1/evolution seconds apart (quintic in time),
//! which keeps every instant divergence-free and doubles the cost.

use glam::DVec3;
use serde::Deserialize;

use super::{ForceTerm, Stiffness};
use crate::base::check::Checker;
use crate::base::gradient_noise::{curl, CELL_LIMIT};
use crate::base::path::ValuePath;
use crate::base::rng::pcg;
use crate::base::writer::{f32_lit, Writer};

/// The most octaves.
pub(crate) const MAX_OCTAVES: u32 = 8;

/// An upper bound of |∂(∇ × ψ)/∂q| (spectral norm) for one octave, measured over 100,000
/// points by the test `jacobian_bound_holds` (largest seen: 17.7); the stability pass
/// takes ω² = strength · octaves · JACOBIAN_BOUND / scale.
pub(crate) const JACOBIAN_BOUND: f64 = 20.0;

/// Golden-ratio step between the keys of time slices.
const SLICE_STEP: u32 = 0x9e37_79b9;

fn default_octaves() -> u32 {
    1
}

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["strength", "scale", "octaves", "evolution"];

/// `Turbulence(strength, scale, octaves, evolution)` as written.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Turbulence {
    /// Typical acceleration (m/s²); components reach about twice this.
    pub strength: f64,
    /// Size of the largest eddies (one noise cell, m), > 0.
    pub scale: f64,
    /// Octaves, 1 to 8 (default 1).
    #[serde(default = "default_octaves")]
    pub octaves: u32,
    /// How fast the flow changes (slices per second), >= 0; 0 (default) is a steady flow.
    #[serde(default)]
    pub evolution: f64,
}

impl Turbulence {
    /// Checks the parameters.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.finite(&path.field("strength"), self.strength);
        c.positive(&path.field("scale"), self.scale);
        if !(1..=MAX_OCTAVES).contains(&self.octaves) {
            c.error(
                &path.field("octaves"),
                format!("must be in [1, {MAX_OCTAVES}], got {}", self.octaves),
            );
        }
        c.non_negative(&path.field("evolution"), self.evolution);
    }

    /// Lowers to a term keyed by the effect's seed and the force's index.
    pub(crate) fn lower(&self, origin: usize, seed: u32) -> TurbulenceTerm {
        TurbulenceTerm {
            strength: self.strength,
            scale: self.scale,
            octaves: self.octaves,
            evolution: self.evolution,
            key: pcg(seed ^ pcg(origin as u32 ^ 0x6375_726c)),
            origins: vec![origin],
        }
    }
}

/// The IR term.
#[derive(Clone, Debug, PartialEq)]
pub struct TurbulenceTerm {
    /// Typical acceleration (m/s²).
    pub strength: f64,
    /// Largest eddy size (m).
    pub scale: f64,
    /// Octaves.
    pub octaves: u32,
    /// Slices per second (0: steady).
    pub evolution: f64,
    /// Hash key: differs per effect seed and per source force.
    pub key: u32,
    /// Source forces.
    pub origins: Vec<usize>,
}

/// The key of octave `o` of time slice `slice`.
fn slice_key(key: u32, slice: i32, o: u32) -> u32 {
    pcg(key
        .wrapping_add((slice as u32).wrapping_mul(SLICE_STEP))
        .wrapping_add(o))
}

impl TurbulenceTerm {
    /// The octaves' curl sum at q (cells) for the slice pair around tau (slices).
    fn field(&self, q: DVec3, tau: f64) -> DVec3 {
        let octaves = |slice: i32| {
            (0..self.octaves)
                .map(|o| {
                    let k = f64::from(1u32 << o);
                    curl(slice_key(self.key, slice, o), q * k) / k
                })
                .sum::<DVec3>()
        };
        if self.evolution == 0.0 {
            return octaves(0);
        }
        let s = tau.floor();
        let f = tau - s;
        let b = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
        let s = s.clamp(-CELL_LIMIT, CELL_LIMIT) as i64 as i32;
        octaves(s) * (1.0 - b) + octaves(s.wrapping_add(1)) * b
    }
}

/// Emits the octave / slice sum `turb_octaves` (once per module), which calls the curl's
/// helpers ([`super::CURL_HELPERS`], the WGSL twins of `base::gradient_noise::curl`).
pub(crate) fn emit_helpers(w: &mut Writer) {
    w.block(
        "fn turb_octaves(key: u32, slice: i32, q: vec3<f32>, octaves: u32) -> vec3<f32>",
        |w| {
            w.line("var acc = vec3<f32>(0.0);");
            w.line("var k = 1.0;");
            w.block("for (var o = 0u; o < octaves; o++)", |w| {
                w.line(format!(
                    "let key_o = pcg(key + bitcast<u32>(slice) * {SLICE_STEP}u + o);"
                ));
                w.line("acc += turb_curl(key_o, q * k) / k;");
                w.line("k = k * 2.0;");
            });
            w.line("return acc;");
        },
    );
    w.block(
        "fn turbulence(key: u32, q: vec3<f32>, tau: f32, octaves: u32) -> vec3<f32>",
        |w| {
            w.line("let s = floor(tau);");
            w.line("let f = tau - s;");
            w.line("let b = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);");
            w.line(format!(
                "let slice = i32(clamp(s, {}, {}));",
                f32_lit(-CELL_LIMIT),
                f32_lit(CELL_LIMIT)
            ));
            w.line("return turb_octaves(key, slice, q, octaves) * (1.0 - b) + turb_octaves(key, slice + 1, q, octaves) * b;");
        },
    );
}

impl ForceTerm for TurbulenceTerm {
    fn wgsl_helpers(&self) -> Vec<super::WgslHelpers> {
        let own = super::WgslHelpers {
            key: "turbulence",
            emit: emit_helpers,
        };
        vec![super::CURL_HELPERS, own]
    }
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Turbulence strength = {} scale = {} m octaves = {} evolution = {}/s key = {:#010x}",
            self.strength, self.scale, self.octaves, self.evolution, self.key
        )
    }
    fn can_act(&self) -> bool {
        self.strength != 0.0
    }
    fn uses_time(&self) -> bool {
        self.evolution != 0.0
    }
    fn reads_whole_time(&self) -> bool {
        // Slices follow t * evolution, which has no period in common with the noise's 256 s.
        self.evolution != 0.0
    }
    fn bakeable(&self) -> bool {
        true
    }
    fn closed_form_blocker(&self) -> String {
        "is turbulence".into()
    }
    fn stiffness(&self) -> Stiffness {
        let w2 = self.strength.abs() * f64::from(self.octaves) * JACOBIAN_BOUND / self.scale;
        Stiffness::Oscillation(w2.sqrt())
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        let q = format!("x * {}", f32_lit(1.0 / self.scale));
        if self.evolution == 0.0 {
            w.line(format!(
                "a += {} * turb_octaves({}u, 0, {q}, {}u);",
                f32_lit(self.strength),
                self.key,
                self.octaves
            ));
        } else {
            w.line(format!(
                "a += {} * turbulence({}u, {q}, t * {}, {}u);",
                f32_lit(self.strength),
                self.key,
                f32_lit(self.evolution),
                self.octaves
            ));
        }
    }
    fn accel(&self, x: DVec3, _v: DVec3, t: f64) -> DVec3 {
        self.strength * self.field(x / self.scale, t * self.evolution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn term(octaves: u32, evolution: f64) -> TurbulenceTerm {
        Turbulence {
            strength: 1.0,
            scale: 1.0,
            octaves,
            evolution,
        }
        .lower(0, 7)
    }

    /// Central-difference Jacobian of the f64 field.
    fn jacobian(t: &TurbulenceTerm, x: DVec3, time: f64, h: f64) -> [DVec3; 3] {
        let mut j = [DVec3::ZERO; 3];
        for (i, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
            j[i] = (t.accel(x + e * h, DVec3::ZERO, time) - t.accel(x - e * h, DVec3::ZERO, time))
                / (2.0 * h);
        }
        j
    }

    #[test]
    fn divergence_free() {
        // j[i] = ∂a/∂x_i; the divergence is Σ ∂a_i/∂x_i, the rotation's size |∇ × a|.
        for (octaves, evolution) in [(1, 0.0), (3, 0.0), (2, 0.7)] {
            let t = term(octaves, evolution);
            let (mut worst, mut curl_sum) = (0.0_f64, 0.0);
            for n in 0..2000 {
                let r = |k: u32| crate::base::rng::unit(pcg(n * 3 + k)) * 20.0 - 10.0;
                let x = DVec3::new(r(0), r(1), r(2));
                let j = jacobian(&t, x, 1.3 + f64::from(n) * 0.01, 1e-5);
                let div = j[0].x + j[1].y + j[2].z;
                let rot = DVec3::new(j[1].z - j[2].y, j[2].x - j[0].z, j[0].y - j[1].x);
                worst = worst.max(div.abs());
                curl_sum += rot.length();
            }
            let mean_curl = curl_sum / 2000.0;
            assert!(mean_curl > 1.0, "the field barely rotates: {mean_curl}");
            // Central differences with h = 1e-5 are exact to ~1e-9 here.
            assert!(
                worst < 1e-6 * mean_curl,
                "octaves {octaves}: divergence {worst:e} against a mean curl {mean_curl}"
            );
        }
    }

    #[test]
    fn jacobian_bound_holds() {
        let t = term(1, 0.0);
        let mut worst: f64 = 0.0;
        for n in 0..100_000u32 {
            let r = |k: u32| crate::base::rng::unit(pcg(n * 3 + k)) * 64.0 - 32.0;
            let x = DVec3::new(r(0), r(1), r(2));
            let j = jacobian(&t, x, 0.0, 1e-5);
            let m = glam::DMat3::from_cols(j[0], j[1], j[2]);
            // Spectral norm from the largest eigenvalue of MᵀM by power iteration.
            let mtm = m.transpose() * m;
            let mut v = DVec3::new(1.0, 0.7, 0.3);
            for _ in 0..50 {
                v = (mtm * v).normalize_or_zero();
            }
            worst = worst.max((mtm * v).length().sqrt());
        }
        eprintln!("largest spectral norm {worst}");
        assert!(worst <= JACOBIAN_BOUND, "spectral norm {worst}");
        assert!(worst > 0.5 * JACOBIAN_BOUND, "the bound is loose: {worst}");
    }

    #[test]
    fn evolves_continuously_and_stays_bounded() {
        let t = term(2, 2.0);
        let x = DVec3::new(0.3, 1.7, -2.2);
        let mut prev = t.accel(x, DVec3::ZERO, 0.0);
        for i in 1..4000 {
            let a = t.accel(x, DVec3::ZERO, f64::from(i) * 1e-3);
            assert!(a.is_finite() && a.length() < 10.0);
            assert!((a - prev).length() < 0.05, "jump at step {i}");
            prev = a;
        }
        // Far from the origin it is still finite.
        assert!(t.accel(DVec3::splat(1e12), DVec3::ZERO, 1e9).is_finite());
    }
}
