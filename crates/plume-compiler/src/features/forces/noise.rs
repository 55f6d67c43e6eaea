//! The smooth noise field N(x, t) behind Wind's `noise`: 4D value noise on a lattice of
//! `scale` metres by 1 second, periodic in time with a period of 256 s, quintic-interpolated,
//! so it is continuous (C²) in x and t and each component lies in [-1, 1].
//!
//! Lattice values come from the PCG hash, bit-identical on CPU and GPU; only interpolation
//! differs (f32 vs f64). Time enters as `t mod 256`, computed in f64 on the CPU, so the field
//! never loses precision however long an effect runs.

use glam::DVec3;

use super::ForceTerm;
use crate::base::rng::pcg;
use crate::base::writer::{f32_lit, Writer};

/// Period of the field in time (seconds); simulation time is passed to kernels modulo this.
pub(crate) const TIME_PERIOD: f64 = 256.0;

/// Coordinates (in cells) are clamped to this magnitude before conversion to integers.
const CELL_LIMIT: f64 = 1.0e9;

/// `a = amplitude * N(x / scale, t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseTerm {
    /// Amplitude (m/s²).
    pub amplitude: f64,
    /// Cell size (m).
    pub scale: f64,
    /// Hash key of this field: differs per effect seed and per source force.
    pub key: u32,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl NoiseTerm {
    /// A noise term for force `origin` of an effect with `seed`.
    pub fn new(amplitude: f64, scale: f64, seed: u32, origin: usize) -> Self {
        Self {
            amplitude,
            scale,
            key: pcg(seed ^ pcg(origin as u32 ^ 0x6e6f_6973)),
            origins: vec![origin],
        }
    }
}

/// Hash of a lattice corner to three values in [-1, 1).
fn corner(key: u32, i: [i32; 4]) -> DVec3 {
    let h = pcg(pcg(
        pcg(pcg(i[0] as u32 ^ key).wrapping_add(i[1] as u32)).wrapping_add(i[2] as u32)
    )
    .wrapping_add((i[3] & 255) as u32));
    let comp = |c: u32| f64::from(pcg(h.wrapping_add(c)) >> 8) * (1.0 / 8_388_608.0) - 1.0;
    DVec3::new(comp(0), comp(1), comp(2))
}

fn fade(f: f64) -> f64 {
    f * f * f * (f * (f * 6.0 - 15.0) + 10.0)
}

/// N(p, tau) in f64, p in cells, tau in seconds (any real; the lattice repeats every 256).
pub fn value_noise(key: u32, p: DVec3, tau: f64) -> DVec3 {
    let p = p.clamp(DVec3::splat(-CELL_LIMIT), DVec3::splat(CELL_LIMIT));
    let pf = p.floor();
    let tf = tau.floor();
    let f = p - pf;
    let ft = tau - tf;
    let u = DVec3::new(fade(f.x), fade(f.y), fade(f.z));
    let ut = fade(ft);
    let base = [
        pf.x as i32,
        pf.y as i32,
        pf.z as i32,
        tf.rem_euclid(TIME_PERIOD) as i32,
    ];
    let mut acc = DVec3::ZERO;
    for c in 0..16u32 {
        let o = [
            (c & 1) as i32,
            ((c >> 1) & 1) as i32,
            ((c >> 2) & 1) as i32,
            ((c >> 3) & 1) as i32,
        ];
        let pick = |bit: i32, u: f64| if bit == 1 { u } else { 1.0 - u };
        let w = pick(o[0], u.x) * pick(o[1], u.y) * pick(o[2], u.z) * pick(o[3], ut);
        let idx = [
            base[0] + o[0],
            base[1] + o[1],
            base[2] + o[2],
            base[3] + o[3],
        ];
        acc += w * corner(key, idx);
    }
    acc
}

/// Emits the WGSL twin of [`value_noise`] (once per module, shared by all noise terms).
pub(crate) fn emit_helpers(w: &mut Writer) {
    w.comment("4D value noise, periodic in time (256 s); lattice values from the PCG hash.");
    w.block("fn noise_corner(key: u32, i: vec4<i32>) -> vec3<f32>", |w| {
        w.line("let h = pcg(pcg(pcg(pcg(bitcast<u32>(i.x) ^ key) + bitcast<u32>(i.y)) + bitcast<u32>(i.z)) + bitcast<u32>(i.w & 255));");
        w.line("let c = vec3<u32>(pcg(h), pcg(h + 1u), pcg(h + 2u));");
        w.line("return vec3<f32>(c >> vec3<u32>(8u)) * 1.1920929e-7 - vec3<f32>(1.0);");
    });
    w.block("fn value_noise(key: u32, p_in: vec3<f32>, tau: f32) -> vec3<f32>", |w| {
        w.line(format!(
            "let p = clamp(p_in, vec3<f32>({lim}), vec3<f32>({lim2}));",
            lim = f32_lit(-CELL_LIMIT),
            lim2 = f32_lit(CELL_LIMIT)
        ));
        w.line("let pf = floor(p);");
        w.line("let tf = floor(tau);");
        w.line("let f = p - pf;");
        w.line("let ft = tau - tf;");
        w.line("let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);");
        w.line("let ut = ft * ft * ft * (ft * (ft * 6.0 - 15.0) + 10.0);");
        w.line("let base = vec4<i32>(vec3<i32>(pf), i32(tf) & 255);");
        w.line("var acc = vec3<f32>(0.0);");
        w.block("for (var c = 0u; c < 16u; c++)", |w| {
            w.line("let o = vec4<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u, (c >> 3u) & 1u);");
            w.line("let s = select(vec4<f32>(1.0) - vec4<f32>(u, ut), vec4<f32>(u, ut), o == vec4<u32>(1u));");
            w.line("acc += (s.x * s.y * s.z * s.w) * noise_corner(key, base + vec4<i32>(o));");
        });
        w.line("return acc;");
    });
}

impl ForceTerm for NoiseTerm {
    fn wgsl_helpers(&self) -> Vec<super::WgslHelpers> {
        vec![super::WgslHelpers {
            key: "noise",
            emit: emit_helpers,
        }]
    }
    fn closed_form_blocker(&self) -> String {
        "has noise".into()
    }
    fn bakeable(&self) -> bool {
        true
    }
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Noise amplitude = {} scale = {} m key = {:#010x}",
            self.amplitude, self.scale, self.key
        )
    }
    fn can_act(&self) -> bool {
        self.amplitude != 0.0
    }
    fn uses_time(&self) -> bool {
        true
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.line(format!(
            "a += {} * value_noise({}u, x * {}, t);",
            f32_lit(self.amplitude),
            self.key,
            f32_lit(1.0 / self.scale)
        ));
    }
    fn accel(&self, x: DVec3, _v: DVec3, t: f64) -> DVec3 {
        self.amplitude * value_noise(self.key, x / self.scale, t.rem_euclid(TIME_PERIOD))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounded_continuous_and_periodic() {
        let key = 1234;
        let mut prev = value_noise(key, DVec3::new(0.3, -1.2, 5.0), 0.0);
        for i in 1..2000 {
            let s = i as f64 * 1e-3;
            let n = value_noise(key, DVec3::new(0.3 + s, -1.2, 5.0 - s), s * 0.7);
            assert!(n.abs().max_element() <= 1.0);
            // Quintic interpolation: the step between nearby samples is small.
            assert!((n - prev).length() < 0.05, "jump at {s}");
            prev = n;
        }
        let a = value_noise(key, DVec3::new(1.5, 2.5, 3.5), 10.25);
        let b = value_noise(key, DVec3::new(1.5, 2.5, 3.5), 10.25 + TIME_PERIOD);
        assert!((a - b).length() < 1e-12);
    }
}
