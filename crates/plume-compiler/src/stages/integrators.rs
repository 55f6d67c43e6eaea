//! Integrators: one (sub)step of h = dt / substeps, in WGSL. Each scheme reads `x` and `v`
//! (Verlet: `d`, the displacement) and writes them back; `accel(x, v, t)` sums the force terms.
//!
//! - Euler: x' = x + v h; v' = v + a(x, v) h.
//! - SemiImplicitEuler: v' = v + a(x, v) h; x' = x + v' h.
//! - Verlet (position Verlet, displacement form): d' = d + a(x, d/h) h²; x' = x + d'.
//!   Spawn sets d = v0 h - a h²/2 so the first step is x1 = x0 + v0 h + a h²/2.
//! - Midpoint: classic RK2 on (x, v). Rk4: classic RK4 on (x, v).
//! - Exact: the closed form for constant acceleration g plus merged drag k toward u:
//!   v' = E v + Cv, x' = x + F v + Cx with E = e^{-kh}, F = (1 - e^{-kh}) / k,
//!   Cv = (1 - E) u + F g, Cx = (h - F) u + ((h - F) / k) g, all computed in f64 here
//!   (series for small kh: WGSL has no expm1, and k = 0 would be 0/0).

use glam::DVec3;

use crate::base::writer::{f32_lit, vec3_lit, Writer};
use crate::ir::EffectIr;
use crate::stages::schema::Integrator;

/// Coefficients of the Exact step: `v' = e v + cv`, `x' = x + f v + cx`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactStep {
    /// e^{-k h}.
    pub e: f64,
    /// (1 - e^{-k h}) / k (h when k = 0).
    pub f: f64,
    /// Added to velocity.
    pub cv: DVec3,
    /// Added to position.
    pub cx: DVec3,
}

impl ExactStep {
    /// The exact step of length `h` for the (folded) terms of `ir`.
    pub fn new(ir: &EffectIr, h: f64) -> Self {
        let (g, k, u) = merged_drag(ir);
        Self::for_drag(g, k, u, h)
    }

    /// Advances a state by this step: (x + f v + cx, e v + cv).
    pub fn apply(&self, x: DVec3, v: DVec3) -> (DVec3, DVec3) {
        (x + self.f * v + self.cx, self.e * v + self.cv)
    }

    /// The exact step for acceleration `g - k (v - u)` over `h`.
    pub(crate) fn for_drag(g: DVec3, k: f64, u: DVec3, h: f64) -> Self {
        let z = k * h;
        let e = (-z).exp();
        // f = (1 - e^{-z}) / k and q = (h - f) / k, by series where they would cancel.
        let (f, q) = if z < 1e-3 {
            (
                h * (1.0 - z / 2.0 + z * z / 6.0 - z * z * z / 24.0),
                h * h * (0.5 - z / 6.0 + z * z / 24.0 - z * z * z / 120.0),
            )
        } else {
            let f = -(-z).exp_m1() / k;
            (f, (h - f) / k)
        };
        Self {
            e,
            f,
            cv: (1.0 - e) * u + f * g,
            cx: (h - f) * u + q * g,
        }
    }
}

/// The Exact integrator's acceleration `g - k (v - u)`: constants summed into g, and the sum of
/// drags -k_i (v - u_i) written -k (v - u) with k = Σk_i, u = Σ(k_i u_i) / k. Returns (g, k, u).
pub(crate) fn merged_drag(ir: &EffectIr) -> (DVec3, f64, DVec3) {
    let (mut g, mut k, mut ku) = (DVec3::ZERO, 0.0, DVec3::ZERO);
    for linear in ir.terms.iter().filter_map(|t| t.as_dyn().linear()) {
        g += linear.accel;
        k += linear.k;
        ku += linear.k_fluid;
    }
    let u = if k > 0.0 { ku / k } else { DVec3::ZERO };
    (g, k, u)
}

/// Below this z = k τ the closed form's coefficients are summed as series: the direct
/// `1 - exp(-z)` cancels (WGSL has no expm1), and past it the alternating series does.
/// At z = 1 both lose under 3 ulps of f32.
pub(crate) const SERIES_BELOW: f64 = 1.0;

/// Emits `advance(s, tau)`, the Exact closed form for any age `tau` (s), in f32:
/// x = x0 + F v0 + (τ - F) u + Q g and v = e v0 + (1 - e) u + F g, with e = e^{-kτ},
/// F = (1 - e)/k and Q = (τ - F)/k (so τ - F = k Q and 1 - e = k F). The stateless kernel
/// calls it once per particle with its age, so nothing accumulates: no drift at any t.
pub(crate) fn emit_advance(w: &mut Writer, ir: &EffectIr) {
    let (g, k, u) = merged_drag(ir);
    w.comment("The Exact closed form at age tau: gravity g plus drag k toward u (integrators.rs).");
    w.block("fn advance(s: Spawned, tau: f32) -> Spawned", |w| {
        w.line("var out = s;");
        if k == 0.0 {
            // No drag: F = τ, Q = τ²/2, e = 1.
            w.line(format!(
                "out.x = s.x + s.v * tau + {} * (0.5 * tau * tau);",
                vec3_lit(g)
            ));
            w.line(format!("out.v = s.v + {} * tau;", vec3_lit(g)));
            w.line("return out;");
            return;
        }
        w.line(format!("let z = {} * tau;", f32_lit(k)));
        w.line("var f: f32;");
        w.line("var q: f32;");
        w.line("var decay: f32;");
        w.block(format!("if (z < {})", f32_lit(SERIES_BELOW)), |w| {
            // F/τ = Σ (-z)^n/(n+1)! = 1 - z/2 (1 - z/3 (1 - ...)), Q/τ² = (1 - z/3 (...))/2:
            // nested from 1/14 down, the remainder is below 2^-24 for z < 1.
            w.comment("Series in nested (Horner) form: F/tau = 1 - z/2 P3, Q/tau^2 = P3 / 2.");
            w.line("var p = 1.0;");
            for m in (3..=14).rev() {
                w.line(format!(
                    "p = 1.0 - z * {} * p;",
                    f32_lit(1.0 / f64::from(m))
                ));
            }
            w.line("let p2 = 1.0 - z * 0.5 * p;");
            w.line("f = tau * p2;");
            w.line("q = tau * tau * (0.5 * p);");
            w.line("decay = z * p2;");
        });
        w.block("else", |w| {
            w.line("decay = 1.0 - exp(-z);");
            w.line(format!("f = decay * {};", f32_lit(1.0 / k)));
            w.line(format!("q = (tau - f) * {};", f32_lit(1.0 / k)));
        });
        // Terms with a zero vector (no wind, or drag with no gravity) are left out.
        let with = |base: &str, terms: [(String, DVec3); 2]| {
            let mut e = base.to_string();
            for (coef, vector) in terms {
                if vector != DVec3::ZERO {
                    e += &format!(" + {coef} * {}", vec3_lit(vector));
                }
            }
            e
        };
        w.line(
            with(
                "out.x = s.x + f * s.v",
                [(format!("({} * q)", f32_lit(k)), u), ("q".into(), g)],
            ) + ";",
        );
        w.line(
            with(
                "out.v = (1.0 - decay) * s.v",
                [("decay".into(), u), ("f".into(), g)],
            ) + ";",
        );
        w.line("return out;");
    });
}

/// Emits one substep of `ir.integrator` (x, v or d, and t in scope as `var`s / `let`).
pub(crate) fn emit_step(w: &mut Writer, ir: &EffectIr) {
    let h = ir.h();
    let hh = f32_lit(h);
    let half = f32_lit(0.5 * h);
    match ir.integrator {
        Integrator::Euler => {
            w.line("let a = accel(x, v, t);");
            w.line(format!("x = x + v * {hh};"));
            w.line(format!("v = v + a * {hh};"));
            emit_clamp_v(w, ir);
        }
        Integrator::SemiImplicitEuler | Integrator::Auto => {
            w.line(format!("v = v + accel(x, v, t) * {hh};"));
            emit_clamp_v(w, ir);
            w.line(format!("x = x + v * {hh};"));
        }
        Integrator::Verlet => {
            w.line(format!(
                "d = d + accel(x, d * {}, t) * {};",
                f32_lit(1.0 / h),
                f32_lit(h * h)
            ));
            if let Some(s) = ir.max_speed {
                // |d / h| <= max_speed  <=>  |d| <= max_speed * h.
                emit_clamp(w, "d", s * h);
            }
            w.line("x = x + d;");
        }
        Integrator::Midpoint => {
            w.line("let a1 = accel(x, v, t);");
            w.line(format!("let xm = x + v * {half};"));
            w.line(format!("let vm = v + a1 * {half};"));
            w.line(format!("let a2 = accel(xm, vm, t + {half});"));
            w.line(format!("x = x + vm * {hh};"));
            w.line(format!("v = v + a2 * {hh};"));
            emit_clamp_v(w, ir);
        }
        Integrator::Rk4 => {
            w.line("let k1 = accel(x, v, t);");
            w.line(format!("let x2 = x + v * {half};"));
            w.line(format!("let v2 = v + k1 * {half};"));
            w.line(format!("let k2 = accel(x2, v2, t + {half});"));
            w.line(format!("let x3 = x + v2 * {half};"));
            w.line(format!("let v3 = v + k2 * {half};"));
            w.line(format!("let k3 = accel(x3, v3, t + {half});"));
            w.line(format!("let x4 = x + v3 * {hh};"));
            w.line(format!("let v4 = v + k3 * {hh};"));
            w.line(format!("let k4 = accel(x4, v4, t + {hh});"));
            w.line(format!(
                "x = x + (v + 2.0 * (v2 + v3) + v4) * {};",
                f32_lit(h / 6.0)
            ));
            w.line(format!(
                "v = v + (k1 + 2.0 * (k2 + k3) + k4) * {};",
                f32_lit(h / 6.0)
            ));
            emit_clamp_v(w, ir);
        }
        Integrator::Exact => {
            let s = ExactStep::new(ir, h);
            // Position first: it uses the velocity at the start of the step.
            w.line(format!(
                "x = x + {} * v + {};",
                f32_lit(s.f),
                vec3_lit(s.cx)
            ));
            w.line(format!("v = {} * v + {};", f32_lit(s.e), vec3_lit(s.cv)));
        }
    }
}

fn emit_clamp_v(w: &mut Writer, ir: &EffectIr) {
    if let Some(s) = ir.max_speed {
        emit_clamp(w, "v", s);
    }
}

/// Clamps the length of vector `var` to `limit` (the branch guards the division).
fn emit_clamp(w: &mut Writer, var: &str, limit: f64) {
    w.block("", |w| {
        w.line(format!("let len2 = dot({var}, {var});"));
        w.block(format!("if (len2 > {})", f32_lit(limit * limit)), |w| {
            w.line(format!(
                "{var} = {var} * ({} * inverseSqrt(len2));",
                f32_lit(limit)
            ));
        });
    });
}

/// True when the integrator needs the `accel` function (all but Exact).
pub(crate) fn needs_accel(i: Integrator) -> bool {
    i != Integrator::Exact
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_step_matches_closed_form_and_gravity_limit() {
        let g = DVec3::new(0.0, -9.81, 0.0);
        let u = DVec3::new(1.0, 0.0, 0.0);
        let (k, h) = (0.4, 0.1);
        let s = ExactStep::for_drag(g, k, u, h);
        let v0 = DVec3::new(2.0, 5.0, 0.0);
        let v_inf = u + g / k;
        let v_exact = v_inf + (v0 - v_inf) * (-k * h).exp();
        let x_exact = v_inf * h + (v0 - v_inf) * (1.0 - (-k * h).exp()) / k;
        assert!((s.e * v0 + s.cv - v_exact).length() < 1e-12);
        assert!((s.f * v0 + s.cx - x_exact).length() < 1e-12);
        // k -> 0: constant acceleration, no 0/0.
        let s0 = ExactStep::for_drag(g, 0.0, DVec3::ZERO, h);
        assert!((s0.cx - g * h * h / 2.0).length() < 1e-15);
        assert!((s0.cv - g * h).length() < 1e-15);
        assert_eq!(s0.f, h);
        // The series branch (z < 1e-3) agrees with the direct formula evaluated in f64.
        let k = 0.999e-3 / h;
        let a = ExactStep::for_drag(g, k, u, h);
        let f = -(-k * h).exp_m1() / k;
        let cx_direct = (h - f) * u + ((h - f) / k) * g;
        assert!((a.cx - cx_direct).length() < 1e-9 * cx_direct.length());
        assert!((a.f - f).abs() < 1e-15);
    }
}
