//! 3D gradient (Perlin) noise on a lattice of unit cells, hashed with PCG so that the GPU and
//! the f64 reference read the same lattice: its scalar value (`noise(p)` in expressions) and
//! the curl of a potential of three such noises (`curl(p)` in expressions, and each octave of
//! the Turbulence force), both from the analytic gradients, with their WGSL twins. Quintic
//! fades make both continuous with continuous derivatives; coordinates are clamped to
//! ±[`CELL_LIMIT`] cells so that the lattice's integers never overflow.

use glam::DVec3;

use crate::base::rng::pcg;
use crate::base::writer::{f32_lit, Writer};

/// Coordinates (in cells) are clamped to this magnitude before conversion to integers.
pub(crate) const CELL_LIMIT: f64 = 1.0e9;

/// Hash multipliers of the three lattice coordinates (odd, unrelated).
const HASH_X: u32 = 0x8da6_b343;
const HASH_Y: u32 = 0xd816_3841;
const HASH_Z: u32 = 0xcb1a_b31f;

/// The key of the noise that expressions read (`noise`, `curl`): one field for every effect,
/// whatever its seed (an author moves through it by offsetting the point).
pub(crate) const EXPRESSION_KEY: u32 = 0x6e6f_6973;

/// One of Perlin's 12 edge gradients (4 of them twice) from the low 4 bits of `h`.
fn gradient(h: u32) -> DVec3 {
    let h = h & 15;
    let u = if h < 8 { DVec3::X } else { DVec3::Y };
    let v = if h < 4 {
        DVec3::Y
    } else if h == 12 || h == 14 {
        DVec3::X
    } else {
        DVec3::Z
    };
    let su = if h & 1 == 0 { 1.0 } else { -1.0 };
    let sv = if h & 2 == 0 { 1.0 } else { -1.0 };
    su * u + sv * v
}

/// The curl of one slice's potential at q (in cells), from the analytic gradients.
pub(crate) fn curl(key: u32, q: DVec3) -> DVec3 {
    let q = q.clamp(DVec3::splat(-CELL_LIMIT), DVec3::splat(CELL_LIMIT));
    let cell = q.floor();
    let f = q - cell;
    let fade = |f: f64| f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let dfade = |f: f64| 30.0 * f * f * (f - 1.0) * (f - 1.0);
    let u = DVec3::new(fade(f.x), fade(f.y), fade(f.z));
    let du = DVec3::new(dfade(f.x), dfade(f.y), dfade(f.z));
    let base = [cell.x as i32, cell.y as i32, cell.z as i32];
    let mut g = [DVec3::ZERO; 3];
    for c in 0..8u32 {
        let o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
        let of = DVec3::new(f64::from(o[0]), f64::from(o[1]), f64::from(o[2]));
        let d = f - of;
        let pick = |bit: u32, a: f64, b: f64| if bit == 1 { a } else { b };
        let wv = DVec3::new(
            pick(o[0], u.x, 1.0 - u.x),
            pick(o[1], u.y, 1.0 - u.y),
            pick(o[2], u.z, 1.0 - u.z),
        );
        let dw = DVec3::new(
            pick(o[0], du.x, -du.x),
            pick(o[1], du.y, -du.y),
            pick(o[2], du.z, -du.z),
        );
        let w = wv.x * wv.y * wv.z;
        let gw = DVec3::new(dw.x * wv.y * wv.z, wv.x * dw.y * wv.z, wv.x * wv.y * dw.z);
        let ix = (base[0] as u32).wrapping_add(o[0]);
        let iy = (base[1] as u32).wrapping_add(o[1]);
        let iz = (base[2] as u32).wrapping_add(o[2]);
        let h =
            pcg(ix.wrapping_mul(HASH_X) ^ iy.wrapping_mul(HASH_Y) ^ iz.wrapping_mul(HASH_Z) ^ key);
        for (k, gk) in g.iter_mut().enumerate() {
            let grad = gradient(h >> (8 + 4 * k as u32));
            *gk += gw * grad.dot(d) + w * grad;
        }
    }
    DVec3::new(g[2].y - g[1].z, g[0].z - g[2].x, g[1].x - g[0].y)
}

/// The gradient noise's value at q (in cells): the sum over the cell's 8 corners of the
/// corner's gradient (the first of [`curl`]'s three) dotted with the offset from it, weighted
/// by the quintic fades; within about ±1.
pub(crate) fn noise(key: u32, q: DVec3) -> f64 {
    let q = q.clamp(DVec3::splat(-CELL_LIMIT), DVec3::splat(CELL_LIMIT));
    let cell = q.floor();
    let f = q - cell;
    let fade = |f: f64| f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let u = DVec3::new(fade(f.x), fade(f.y), fade(f.z));
    let base = [cell.x as i32, cell.y as i32, cell.z as i32];
    let mut sum = 0.0;
    for c in 0..8u32 {
        let o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
        let d = f - DVec3::new(f64::from(o[0]), f64::from(o[1]), f64::from(o[2]));
        let pick = |bit: u32, a: f64| if bit == 1 { a } else { 1.0 - a };
        let w = pick(o[0], u.x) * pick(o[1], u.y) * pick(o[2], u.z);
        let ix = (base[0] as u32).wrapping_add(o[0]);
        let iy = (base[1] as u32).wrapping_add(o[1]);
        let iz = (base[2] as u32).wrapping_add(o[2]);
        let h =
            pcg(ix.wrapping_mul(HASH_X) ^ iy.wrapping_mul(HASH_Y) ^ iz.wrapping_mul(HASH_Z) ^ key);
        sum += w * gradient(h >> 8).dot(d);
    }
    sum
}

/// Emits `turb_gradient` and `turb_curl(key, q)`, the WGSL twins of [`curl`] (once per
/// module).
pub(crate) fn emit_curl_helpers(w: &mut Writer) {
    w.comment("Curl noise: the curl of a potential of three 3D gradient noises, analytic.");
    w.block("fn turb_gradient(h: u32) -> vec3<f32>", |w| {
        w.line("let b = h & 15u;");
        w.line("let u = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), b < 8u);");
        w.line("let v = select(select(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(1.0, 0.0, 0.0), b == 12u || b == 14u), vec3<f32>(0.0, 1.0, 0.0), b < 4u);");
        w.line("return select(u, -u, (b & 1u) != 0u) + select(v, -v, (b & 2u) != 0u);");
    });
    w.block("fn turb_curl(key: u32, q_in: vec3<f32>) -> vec3<f32>", |w| {
        emit_cell(w);
        w.line("let du = 30.0 * f * f * (f - 1.0) * (f - 1.0);");
        w.line("let base = bitcast<vec3<u32>>(vec3<i32>(cell));");
        w.line("var g0 = vec3<f32>(0.0);");
        w.line("var g1 = vec3<f32>(0.0);");
        w.line("var g2 = vec3<f32>(0.0);");
        w.block("for (var c = 0u; c < 8u; c++)", |w| {
            w.line("let o = vec3<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);");
            w.line("let d = f - vec3<f32>(o);");
            w.line("let on = o == vec3<u32>(1u);");
            w.line("let wv = select(vec3<f32>(1.0) - u, u, on);");
            w.line("let dw = select(-du, du, on);");
            w.line("let wt = wv.x * wv.y * wv.z;");
            w.line("let gw = vec3<f32>(dw.x * wv.y * wv.z, wv.x * dw.y * wv.z, wv.x * wv.y * dw.z);");
            w.line("let i = base + o;");
            w.line(format!(
                "let h = pcg((i.x * {HASH_X}u) ^ (i.y * {HASH_Y}u) ^ (i.z * {HASH_Z}u) ^ key);"
            ));
            w.line("let ga = turb_gradient(h >> 8u);");
            w.line("let gb = turb_gradient(h >> 12u);");
            w.line("let gc = turb_gradient(h >> 16u);");
            w.line("g0 += gw * dot(ga, d) + wt * ga;");
            w.line("g1 += gw * dot(gb, d) + wt * gb;");
            w.line("g2 += gw * dot(gc, d) + wt * gc;");
        });
        w.line("return vec3<f32>(g2.y - g1.z, g0.z - g2.x, g1.x - g0.y);");
    });
}

/// The lines both helpers open with: `q_in` clamped, its cell, the offset in it and the fades.
fn emit_cell(w: &mut Writer) {
    w.line(format!(
        "let q = clamp(q_in, vec3<f32>({}), vec3<f32>({}));",
        f32_lit(-CELL_LIMIT),
        f32_lit(CELL_LIMIT)
    ));
    w.line("let cell = floor(q);");
    w.line("let f = q - cell;");
    w.line("let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);");
}

/// Emits `grad_noise(key, q)`, the WGSL twin of [`noise`] (after [`emit_curl_helpers`], whose
/// `turb_gradient` it reads).
pub(crate) fn emit_noise_helper(w: &mut Writer) {
    w.comment("Gradient noise: the value of the first of the curl's three noises.");
    w.block("fn grad_noise(key: u32, q_in: vec3<f32>) -> f32", |w| {
        emit_cell(w);
        w.line("let base = bitcast<vec3<u32>>(vec3<i32>(cell));");
        w.line("var sum = 0.0;");
        w.block("for (var c = 0u; c < 8u; c++)", |w| {
            w.line("let o = vec3<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);");
            w.line("let d = f - vec3<f32>(o);");
            w.line("let wv = select(vec3<f32>(1.0) - u, u, o == vec3<u32>(1u));");
            w.line("let i = base + o;");
            w.line(format!(
                "let h = pcg((i.x * {HASH_X}u) ^ (i.y * {HASH_Y}u) ^ (i.z * {HASH_Z}u) ^ key);"
            ));
            w.line("sum += wv.x * wv.y * wv.z * dot(turb_gradient(h >> 8u), d);");
        });
        w.line("return sum;");
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_zero_on_the_lattice_bounded_and_continuous() {
        // At a lattice point only its own corner weighs, and its offset is zero.
        for p in [DVec3::ZERO, DVec3::new(3.0, -7.0, 12.0), DVec3::splat(-1.0)] {
            assert_eq!(noise(EXPRESSION_KEY, p), 0.0);
        }
        let mut h = 0x1234_5678u32;
        let mut next = || {
            h = pcg(h);
            f64::from(h) / f64::from(u32::MAX) * 40.0 - 20.0
        };
        let (mut sum, mut most, n) = (0.0, 0.0f64, 20_000);
        for _ in 0..n {
            let p = DVec3::new(next(), next(), next());
            let v = noise(EXPRESSION_KEY, p);
            sum += v;
            most = most.max(v.abs());
            // Continuous: a step of 1e-6 cells moves it by at most its gradient's bound
            // (the 8 corners' |g| = √2 through fades whose slope is at most 1.875) times it.
            let d = (noise(EXPRESSION_KEY, p + DVec3::splat(1e-6)) - v).abs();
            assert!(d < 1e-5, "{p}: {d}");
        }
        assert!(most <= 1.5, "{most}");
        // Its mean over 20000 points is near 0 (the gradients are symmetric).
        assert!((sum / f64::from(n)).abs() < 0.02, "{}", sum / f64::from(n));
    }

    #[test]
    fn curl_is_divergence_free() {
        let h = 1e-4;
        for i in 0..200 {
            let p = DVec3::new(
                0.37 * f64::from(i),
                1.3 - 0.11 * f64::from(i),
                0.05 * f64::from(i),
            );
            let div: f64 = [DVec3::X, DVec3::Y, DVec3::Z]
                .iter()
                .enumerate()
                .map(|(k, e)| {
                    (curl(EXPRESSION_KEY, p + *e * h)[k] - curl(EXPRESSION_KEY, p - *e * h)[k])
                        / (2.0 * h)
                })
                .sum();
            assert!(div.abs() < 1e-5, "{p}: {div}");
        }
    }
}
