//! f64 twins of the spawn kernel's draws (wgsl/spawn.rs): the same hash streams, the same
//! formulas, evaluated in f64.

use std::f64::consts::PI;

use glam::DVec3;

use crate::base::lifetime::NEVER;
use crate::base::rng::{rand_u32, stream, unit};
use crate::ir::{EffectIr, ShapeIr, VelocityIr};

/// A particle's starting state: position, velocity and the step whose update kills it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spawned {
    /// Position (m).
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Step index whose update kills it ([`NEVER`] when immortal).
    pub die_at: u32,
}

struct Draw {
    seed_mix: u32,
    id: u32,
}

impl Draw {
    fn u(&self, s: u32) -> f64 {
        unit(rand_u32(self.seed_mix, self.id, s))
    }
    fn u3(&self, base: u32) -> DVec3 {
        DVec3::new(self.u(base), self.u(base + 1), self.u(base + 2))
    }
}

/// The state of particle `id`, the `k`-th of emitter `e`, spawned at `step`.
pub fn spawn(ir: &EffectIr, e: usize, id: u32, k: u32, step: u64) -> Spawned {
    let em = &ir.emitters[e];
    let d = Draw {
        seed_mix: ir.seed_mix,
        id,
    };
    let (x, normal) = position(&d, &em.shape, k);
    let v = velocity(&d, &em.shape, &em.velocity, x, normal);
    let die_at = match em.lifetime_steps {
        Some(l) => {
            let n = l.draw(rand_u32(ir.seed_mix, id, stream::LIFETIME));
            (step as u32).wrapping_add(n).wrapping_sub(1)
        }
        None => NEVER,
    };
    Spawned { x, v, die_at }
}

/// The spawn position and, on a mesh, the surface's normal there (zero elsewhere).
fn position(d: &Draw, shape: &ShapeIr, k: u32) -> (DVec3, DVec3) {
    if let ShapeIr::Mesh(m) = shape {
        return m.spawn(
            rand_u32(d.seed_mix, d.id, stream::MESH_PICK),
            d.u3(stream::POSITION),
        );
    }
    let x = match shape {
        ShapeIr::Point(p) => *p,
        ShapeIr::Sphere { center, radius } => {
            let u = d.u3(stream::POSITION);
            let cz = 1.0 - 2.0 * u.x;
            let phi = 2.0 * PI * u.y - PI;
            let sz = (1.0 - cz * cz).max(0.0).sqrt();
            let r = radius * u.z.max(1e-30).cbrt();
            *center + r * DVec3::new(sz * phi.cos(), sz * phi.sin(), cz)
        }
        ShapeIr::Box { min, max } => *min + (*max - *min) * d.u3(stream::POSITION),
        ShapeIr::Disc {
            center,
            radius,
            basis,
        } => {
            let u = d.u3(stream::POSITION);
            let r = radius * u.x.sqrt();
            let phi = 2.0 * PI * u.y - PI;
            *center + r * (phi.cos() * basis.t1 + phi.sin() * basis.t2)
        }
        ShapeIr::Grid {
            origin,
            step,
            counts,
        } => {
            let [nx, ny, nz] = *counts;
            let g = k % nx.wrapping_mul(ny).wrapping_mul(nz);
            let gi = DVec3::new(
                f64::from(g % nx),
                f64::from((g / nx) % ny),
                f64::from(g / (nx * ny)),
            );
            *origin + gi * *step
        }
        ShapeIr::Points(ps) => ps[(k % ps.len() as u32) as usize],
        ShapeIr::Mesh(_) => unreachable!("sampled above"),
    };
    (x, DVec3::ZERO)
}

fn velocity(d: &Draw, shape: &ShapeIr, vel: &VelocityIr, x: DVec3, normal: DVec3) -> DVec3 {
    let speed = |s: (f64, f64)| s.0 + (s.1 - s.0) * d.u(stream::VELOCITY + 2);
    match vel {
        VelocityIr::Constant(v) => *v,
        VelocityIr::Cone {
            axis,
            basis,
            cos_angle,
            speed: s,
        } => {
            let w = d.u(stream::VELOCITY) * (1.0 - cos_angle);
            let cos_t = 1.0 - w;
            let sin_t = (w * (2.0 - w)).max(0.0).sqrt();
            let psi = 2.0 * PI * d.u(stream::VELOCITY + 1) - PI;
            speed(*s) * (cos_t * *axis + sin_t * (psi.cos() * basis.t1 + psi.sin() * basis.t2))
        }
        VelocityIr::Radial { speed: s } => {
            let out = x - shape.center();
            let out2 = out.length_squared();
            let dir = if out2 > shape.radial_center_eps2() {
                out / out2.sqrt()
            } else {
                let cz = 1.0 - 2.0 * d.u(stream::FALLBACK_DIRECTION);
                let phi = 2.0 * PI * d.u(stream::FALLBACK_DIRECTION + 1) - PI;
                let sz = (1.0 - cz * cz).max(0.0).sqrt();
                DVec3::new(sz * phi.cos(), sz * phi.sin(), cz)
            };
            speed(*s) * dir
        }
        VelocityIr::Normal { speed: s } => speed(*s) * normal,
    }
}
