//! Integer-hash random numbers (PCG family), identical on the CPU and the GPU.
//!
//! Every random draw is `hash(seed, id, stream)`: a function of the effect's seed, the particle's
//! id and the purpose of the draw. Integer hashes are bit-identical everywhere, so the CPU
//! reference starts particle `k` exactly where the GPU does. `fract(sin(..))` is never used.

use crate::base::writer::Writer;

/// The PCG hash (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering").
pub fn pcg(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The per-effect constant mixed into every draw.
pub fn seed_mix(seed: u32) -> u32 {
    pcg(seed ^ 0x5bd1_e995)
}

/// The golden-ratio increment that separates streams.
const STREAM_STEP: u32 = 0x9e37_79b9;

/// The raw 32-bit draw for particle `id` and purpose `stream`.
pub fn rand_u32(seed_mix: u32, id: u32, stream: u32) -> u32 {
    pcg(pcg(id ^ seed_mix).wrapping_add(stream.wrapping_mul(STREAM_STEP)))
}

/// A uniform number in [0, 1): the top 24 bits, so it is exact in f32 and f64 alike.
pub fn unit(h: u32) -> f64 {
    f64::from(h >> 8) * (1.0 / 16_777_216.0)
}

/// Draw streams: one per random purpose, so adding a purpose never shifts another's numbers.
pub mod stream {
    /// Three draws for the spawn position.
    pub const POSITION: u32 = 0;
    /// Three draws for the spawn velocity.
    pub const VELOCITY: u32 = 3;
    /// One draw for the lifetime.
    pub const LIFETIME: u32 = 6;
    /// Three draws for a fallback direction (radial velocity from the exact centre).
    pub(crate) const FALLBACK_DIRECTION: u32 = 7;
    /// One draw for a flipbook's first frame (`render.texture.random_start`).
    pub(crate) const FLIPBOOK: u32 = 10;
    /// One draw for a sprite's starting angle (`render.rotation.angle`).
    pub(crate) const ROTATION_ANGLE: u32 = 11;
    /// One draw for a sprite's spin (`render.rotation.spin`).
    pub(crate) const ROTATION_SPIN: u32 = 12;
    /// One draw for a particle's palette colour (`render.palette`).
    pub(crate) const PALETTE: u32 = 13;
    /// One draw for the triangle (or the field cell) a mesh spawn shape picks.
    pub(crate) const MESH_PICK: u32 = 14;
    /// One draw for the face a box's surface picks (`Box(surface: true)`).
    pub(crate) const FACE_PICK: u32 = 15;
    /// One draw for a particle's starting age (an emitter's `age`).
    pub(crate) const START_AGE: u32 = 16;
    /// `rand(k)` in custom expressions draws from stream CUSTOM + k (k <= 255).
    pub(crate) const CUSTOM: u32 = 64;
}

/// One particle's draws, as the f64 twins of the spawn read them: the same words as the WGSL's
/// `rand_u32(id, stream)` and `rand_unit(id, stream)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ParticleDraws {
    /// The effect's [`seed_mix`].
    pub seed_mix: u32,
    /// The particle's id.
    pub id: u32,
}

impl ParticleDraws {
    /// The raw 32-bit word of `stream`.
    pub(crate) fn word(&self, stream: u32) -> u32 {
        rand_u32(self.seed_mix, self.id, stream)
    }

    /// The uniform number in [0, 1) of `stream`.
    pub(crate) fn unit(&self, stream: u32) -> f64 {
        unit(self.word(stream))
    }

    /// Three uniform numbers from streams `base`, `base + 1` and `base + 2`.
    pub(crate) fn unit3(&self, base: u32) -> glam::DVec3 {
        glam::DVec3::new(self.unit(base), self.unit(base + 1), self.unit(base + 2))
    }
}

/// The WGSL of three uniform numbers from streams `base` to `base + 2` of particle `id`: the twin
/// of [`ParticleDraws::unit3`].
pub(crate) fn wgsl_unit3(base: u32) -> String {
    format!(
        "vec3<f32>(rand_unit(id, {}u), rand_unit(id, {}u), rand_unit(id, {}u))",
        base,
        base + 1,
        base + 2
    )
}

/// Emits the WGSL twin of [`pcg`] as a function called `name` (a module that needs the hash
/// for two purposes, e.g. draws and the flock's grid, names each its own).
pub(crate) fn emit_pcg(w: &mut Writer, name: &str) {
    w.block(format!("fn {name}(x: u32) -> u32"), |w| {
        w.line("let state = x * 747796405u + 2891336453u;");
        w.line("let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;");
        w.line("return (word >> 22u) ^ word;");
    });
}

/// Emits the WGSL twins of [`pcg`], [`rand_u32`] and [`unit()`].
pub(crate) fn emit_wgsl(w: &mut Writer) {
    w.comment("PCG hash (integer, bit-identical to the CPU reference).");
    emit_pcg(w, "pcg");
    w.block("fn rand_u32(id: u32, stream: u32) -> u32", |w| {
        w.line(format!(
            "return pcg(pcg(id ^ SEED_MIX) + stream * {}u);",
            STREAM_STEP
        ));
    });
    w.comment("Uniform in [0, 1): top 24 bits, exact in f32.");
    w.block("fn rand_unit(id: u32, stream: u32) -> f32", |w| {
        w.line("return f32(rand_u32(id, stream) >> 8u) * 5.9604645e-8;");
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_known_values_and_unit_range() {
        // pcg(0) computed independently with a Python transcription of the same formula.
        assert_eq!(pcg(0), 129_708_002);
        assert_ne!(pcg(1), pcg(2));
        assert!(unit(u32::MAX) < 1.0);
        assert_eq!(unit(0), 0.0);
        assert_ne!(rand_u32(1, 5, 0), rand_u32(1, 5, 1));
    }
}
