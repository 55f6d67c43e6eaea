//! The f64 oracle of stateless effects: every live particle straight from the closed form at
//! its age, with no stepping at all, so it is exact (to f64) at any t, t = 10^6 s included.
//! It reads the same spawn draws and the same segment bookkeeping as the GPU's `evaluate`.

use glam::DVec3;

use super::spawn::spawn;
use super::ParticleRecord;
use crate::base::lifetime::NEVER;
use crate::ir::EffectIr;
use crate::stages::integrators::{merged_drag, ExactStep};
use crate::stages::schedule::{LiveSegments, Schedule};

/// The closed form at one age τ (s) under the Exact integrator's forces: the exact step of
/// length τ, and the sizes of its terms.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AtAge {
    step: ExactStep,
    /// (τ - F) |u|.
    wind: f64,
    /// Q |g|, Q = (τ - F) / k (τ²/2 when k = 0).
    gravity: f64,
}

impl AtAge {
    /// The closed form of `ir`'s forces at age `tau`.
    pub(crate) fn new(ir: &EffectIr, tau: f64) -> Self {
        let (g, k, u) = merged_drag(ir);
        let step = ExactStep::for_drag(g, k, u, tau);
        let q = if k > 0.0 {
            (tau - step.f) / k
        } else {
            0.5 * tau * tau
        };
        Self {
            step,
            wind: (tau - step.f) * u.length(),
            gravity: q * g.length(),
        }
    }

    /// A particle's position and velocity at this age, from its spawn state.
    pub(crate) fn state(&self, x0: DVec3, v0: DVec3) -> (DVec3, DVec3) {
        self.step.apply(x0, v0)
    }

    /// The size of the closed form's terms: X + F|v0| + (τ - F)|u| + Q|g|, where X is the size
    /// of the spawn position's own computation (`x0_size`: the larger of |x0| and the spawn
    /// shape's extent, since a point drawn in a box from -2 to 2 carries the rounding of 2
    /// even where it lands near 0). A position computed in f32 is accurate relative to this;
    /// it is |x| unless terms cancel.
    pub(crate) fn term_scale(&self, x0_size: f64, v0: DVec3) -> f64 {
        x0_size + self.step.f * v0.length() + self.wind + self.gravity
    }
}

/// The live particles after the steps `segments` has recorded, in id order, each with the
/// scale of its closed form's terms. `schedule` must have planned the same steps (for ages).
pub fn records(
    ir: &EffectIr,
    segments: &LiveSegments,
    schedule: &Schedule,
) -> Vec<(ParticleRecord, f64)> {
    let done = segments.steps_done();
    let mut out = Vec::new();
    for seg in segments.iter() {
        let age_steps = done - seg.step;
        let tau = age_steps as f64 * ir.dt;
        let closed = AtAge::new(ir, tau);
        let extent = ir.emitters[seg.emitter].shape.extent();
        for j in 0..seg.count {
            let id = seg.first_id + j;
            let s = spawn(ir, seg.emitter, id, seg.k_base + j, seg.step);
            if s.die_at != NEVER {
                let lives = u64::from(s.die_at.wrapping_sub(seg.step as u32)) + 1;
                if age_steps >= lives {
                    continue;
                }
            }
            let (x, v) = closed.state(s.x, s.v);
            out.push((
                ParticleRecord {
                    id,
                    position: x,
                    velocity: v,
                    age: tau,
                    lifetime: schedule.lifetime(id, s.die_at),
                    tint: crate::features::looks::tint::own(ir.tint(), id),
                    // A stateless effect keeps no attributes.
                    attributes: Default::default(),
                },
                closed.term_scale(s.x.length().max(extent), s.v),
            ));
        }
    }
    out.sort_by_key(|(r, _)| r.id);
    out
}
