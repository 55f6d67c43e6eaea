//! f64 twins of the update kernel's pieces (integrators.rs, wgsl/update.rs): one substep of each
//! integrator and the speed clamp (collisions: crate::features::colliders::resolve).

use glam::DVec3;

use crate::features::forces::flock::Frozen;
use crate::features::forces::ParticleCtx;
use crate::ir::EffectIr;
use crate::stages::integrators::ExactStep;
use crate::stages::schema::Integrator;

/// Sum of the force terms at (x, v, t) for particle `p`. With a baked field, `baked` holds its
/// nodes (baked at the step's time) and the bakeable terms are sampled from them instead of
/// evaluated.
pub fn accel(
    ir: &EffectIr,
    baked: Option<&[DVec3]>,
    p: &ParticleCtx,
    x: DVec3,
    v: DVec3,
    t: f64,
) -> DVec3 {
    match (&ir.field, baked) {
        (Some(field), Some(nodes)) => {
            let rest: DVec3 = ir
                .terms
                .iter()
                .filter(|term| !term.as_dyn().bakeable())
                .map(|term| term.as_dyn().accel_at(x, v, t, p))
                .sum();
            rest + field
                .sample(nodes, x)
                .unwrap_or_else(|| crate::features::field::baked_sum(&ir.terms, x, t))
        }
        _ => ir
            .terms
            .iter()
            .map(|term| term.as_dyn().accel_at(x, v, t, p))
            .sum(),
    }
}

fn clamp(v: DVec3, limit: Option<f64>) -> DVec3 {
    match limit {
        Some(s) if v.length_squared() > s * s => v * (s / v.length()),
        _ => v,
    }
}

/// One substep of length h = ir.h() at time t. `v` holds Verlet's displacement for Verlet.
/// `flock` is the particle's frozen flock values for this step, when the effect flocks; `p`
/// what custom forces read about the particle.
#[allow(clippy::too_many_arguments)]
pub fn substep(
    ir: &EffectIr,
    exact: Option<&ExactStep>,
    baked: Option<&[DVec3]>,
    flock: Option<&Frozen>,
    p: &ParticleCtx,
    x: &mut DVec3,
    v: &mut DVec3,
    t: f64,
) {
    let h = ir.h();
    let a = |x: DVec3, v: DVec3, t: f64| {
        let own = accel(ir, baked, p, x, v, t);
        match (&ir.flock, flock) {
            (Some(f), Some(frozen)) => own + f.accel(frozen, x, v),
            _ => own,
        }
    };
    match ir.integrator {
        Integrator::Euler => {
            let acc = a(*x, *v, t);
            *x += *v * h;
            *v = clamp(*v + acc * h, ir.max_speed);
        }
        Integrator::SemiImplicitEuler | Integrator::Auto => {
            *v = clamp(*v + a(*x, *v, t) * h, ir.max_speed);
            *x += *v * h;
        }
        Integrator::Verlet => {
            let d = *v + a(*x, *v / h, t) * (h * h);
            *v = clamp(d, ir.max_speed.map(|s| s * h));
            *x += *v;
        }
        Integrator::Midpoint => {
            let a1 = a(*x, *v, t);
            let xm = *x + *v * (0.5 * h);
            let vm = *v + a1 * (0.5 * h);
            let a2 = a(xm, vm, t + 0.5 * h);
            *x += vm * h;
            *v = clamp(*v + a2 * h, ir.max_speed);
        }
        Integrator::Rk4 => {
            let k1 = a(*x, *v, t);
            let (x2, v2) = (*x + *v * (0.5 * h), *v + k1 * (0.5 * h));
            let k2 = a(x2, v2, t + 0.5 * h);
            let (x3, v3) = (*x + v2 * (0.5 * h), *v + k2 * (0.5 * h));
            let k3 = a(x3, v3, t + 0.5 * h);
            let (x4, v4) = (*x + v3 * h, *v + k3 * h);
            let k4 = a(x4, v4, t + h);
            *x += (*v + 2.0 * (v2 + v3) + v4) * (h / 6.0);
            *v = clamp(*v + (k1 + 2.0 * (k2 + k3) + k4) * (h / 6.0), ir.max_speed);
        }
        Integrator::Exact => {
            let s = exact.expect("Exact needs its coefficients");
            *x += s.f * *v + s.cx;
            *v = s.e * *v + s.cv;
        }
    }
}
