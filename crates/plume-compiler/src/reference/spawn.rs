//! A spawned particle's starting state in f64: the emitter's own twins of its shape and
//! velocity (`features/emitter`) and the lifetime's integer draw, as the spawn kernel
//! (`stages/wgsl/spawn.rs`) draws them.

use glam::DVec3;

use crate::base::lifetime::NEVER;
use crate::base::rng::{rand_u32, stream};
use crate::ir::EffectIr;

/// A particle's starting state: position, velocity and the step whose update kills it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spawned {
    /// Position (m).
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Step index whose update kills it (`NEVER` when immortal).
    pub die_at: u32,
    /// Its starting age in whole steps (`Emitter::age`; 0 without one).
    pub start: u32,
}

/// The state of particle `id`, the `k`-th of emitter `e`, spawned at `step` (an emitter's:
/// its spawn frame at the origin).
pub fn spawn(ir: &EffectIr, e: usize, id: u32, k: u32, step: u64) -> Spawned {
    spawn_at(ir, e, (id, k), step, DVec3::ZERO)
}

/// [`spawn`] in a frame at `origin` (an event's spawn: the firing particle's position).
pub(crate) fn spawn_at(
    ir: &EffectIr,
    e: usize,
    (id, k): (u32, u32),
    step: u64,
    origin: DVec3,
) -> Spawned {
    let em = &ir.emitters[e];
    let (x, v) = em.sample(ir.seed_mix, (id, k), step, origin);
    let start = em
        .age_steps
        .map_or(0, |a| a.draw(rand_u32(ir.seed_mix, id, stream::START_AGE)));
    let die_at = match em.lifetime_steps {
        Some(l) => {
            let n = l.draw(rand_u32(ir.seed_mix, id, stream::LIFETIME));
            (step as u32)
                .wrapping_sub(start)
                .wrapping_add(n)
                .wrapping_sub(1)
        }
        None => NEVER,
    };
    Spawned {
        x,
        v,
        die_at,
        start,
    }
}
