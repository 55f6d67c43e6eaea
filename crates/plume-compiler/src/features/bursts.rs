//! Bursts fired from code: a host asks an effect to spawn `count` more particles from one of
//! its emitters at the next step, moved by an offset and given an extra velocity (an impact,
//! a footstep, a muzzle flash). The burst's particles are the emitter's own: its shape, its
//! velocity distribution, its lifetime, drawn from the same integer hash of (seed, id, k)
//! with the emitter's spawn counter continuing, so a burst is as deterministic as the rate.
//!
//! Only an effect compiled with `CompileOptions::bursts` carries them: its step parameters
//! gain [`SLOTS`] burst entries after the emitters' (count, the emitter's counter before them,
//! the emitter, 0) and their motions (offset, added velocity), and its spawn kernel hands the
//! ids after the emitters' to them in order. Every other effect's WGSL is unchanged. An
//! effect with bursts is never stateless: a closed form of (id, age) cannot know when code
//! fired one.
//!
//! The offset and velocity are in the effect's own space: a placed effect
//! (`features::placement`) moves a burst's particles through its transform like the rest.
//! The f64 twin is [`Burst::apply`], over the same f32 values the GPU reads.

use glam::DVec3;

use crate::base::writer::Writer;

/// The most bursts one step spawns; more wait for the next step, in the order fired.
pub const SLOTS: u32 = 8;

/// Bytes the bursts add to the step parameters: per slot one entry and two motion vectors.
#[cfg(test)]
const PARAMS_BYTES: u64 = SLOTS as u64 * 48;

/// One burst: `count` particles of emitter `emitter`, spawned at the next step with `offset`
/// added to their positions and `velocity` to their velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Burst {
    /// Which of the effect's (or group's) emitters spawns them.
    pub emitter: u32,
    /// How many particles.
    pub count: u32,
    /// Added to each spawn position (m, in the effect's space).
    pub offset: [f32; 3],
    /// Added to each spawn velocity (m/s, in the effect's space).
    pub velocity: [f32; 3],
}

impl Burst {
    /// `count` particles of emitter `emitter` where and as fast as the emitter spawns them.
    pub fn new(emitter: u32, count: u32) -> Self {
        Self {
            emitter,
            count,
            offset: [0.0; 3],
            velocity: [0.0; 3],
        }
    }

    /// The burst moved by `offset` (m).
    pub fn at(mut self, offset: [f32; 3]) -> Self {
        self.offset = offset;
        self
    }

    /// The burst with `velocity` (m/s) added to each particle's.
    pub fn with_velocity(mut self, velocity: [f32; 3]) -> Self {
        self.velocity = velocity;
        self
    }

    /// Whether every coordinate is finite.
    pub fn is_finite(&self) -> bool {
        self.offset
            .iter()
            .chain(&self.velocity)
            .all(|c| c.is_finite())
    }

    /// The spawned position and velocity `(x, v)` of the emitter moved by the burst (f64 over
    /// the f32 values, the twin of the kernel's two additions).
    pub fn apply(&self, x: DVec3, v: DVec3) -> (DVec3, DVec3) {
        let f = |c: [f32; 3]| DVec3::from_array(c.map(f64::from));
        (x + f(self.offset), v + f(self.velocity))
    }
}

/// A burst a step spawns, with its emitter's spawn counter before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannedBurst {
    /// The burst (its count clipped to the ids left).
    pub burst: Burst,
    /// The emitter's own spawn counter at its first particle.
    pub k0: u32,
}

/// The bursts' words in the step parameters: [`SLOTS`] entries (count, k0, emitter, 0), then
/// [`SLOTS`] pairs (offset, 0, velocity, 0); unused slots are zero.
pub fn words(planned: &[PlannedBurst]) -> Vec<u32> {
    let mut entries = vec![0u32; SLOTS as usize * 4];
    let mut motions = vec![0u32; SLOTS as usize * 8];
    for (b, p) in planned.iter().take(SLOTS as usize).enumerate() {
        entries[b * 4..b * 4 + 3].copy_from_slice(&[p.burst.count, p.k0, p.burst.emitter]);
        let m = &mut motions[b * 8..b * 8 + 8];
        for c in 0..3 {
            m[c] = p.burst.offset[c].to_bits();
            m[4 + c] = p.burst.velocity[c].to_bits();
        }
    }
    entries.extend(motions);
    entries
}

/// Emits the step parameters' fields (after the emitters').
pub(crate) fn emit_params_fields(w: &mut Writer) {
    w.line(format!(
        "bursts: array<vec4<u32>, {SLOTS}>, // (count, emitter's counter before, emitter, 0)"
    ));
    w.line(format!(
        "burst_motion: array<vec4<f32>, {}>, // per burst: offset, then added velocity",
        SLOTS * 2
    ));
}

/// Emits the search of spawn `local` (an index past every emitter's spawns) among the bursts:
/// sets `burst` to its slot, `e` to its emitter and `k` to its emitter counter.
pub(crate) fn emit_find(w: &mut Writer) {
    w.comment("Past every emitter's spawns come the bursts fired from code, in order.");
    w.line("var b = 0u;");
    w.block(format!("for (; b < {}u; b++)", SLOTS - 1), |w| {
        w.block("if (local < params.bursts[b].x)", |w| w.line("break;"));
        w.line("local = local - params.bursts[b].x;");
    });
    w.line("burst = b;");
    w.line("e = params.bursts[b].z;");
    w.line("k = params.bursts[b].y + local;");
}

/// Emits the burst's motion applied to the spawned `s` when `burst` names a slot (the f32
/// twin of [`Burst::apply`]).
pub(crate) fn emit_apply(w: &mut Writer) {
    w.block(format!("if (burst < {SLOTS}u)"), |w| {
        w.line("s.x = s.x + params.burst_motion[2u * burst].xyz;");
        w.line("s.v = s.v + params.burst_motion[2u * burst + 1u].xyz;");
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_hold_each_slot_and_its_motion_and_zero_the_rest() {
        let planned = [PlannedBurst {
            burst: Burst::new(1, 5)
                .at([1.0, 2.0, 3.0])
                .with_velocity([0.0, 4.0, 0.0]),
            k0: 7,
        }];
        let w = words(&planned);
        assert_eq!(w.len() as u64 * 4, PARAMS_BYTES);
        assert_eq!(&w[..4], &[5, 7, 1, 0]);
        assert!(w[4..SLOTS as usize * 4].iter().all(|&x| x == 0));
        let motion = &w[SLOTS as usize * 4..];
        assert_eq!(f32::from_bits(motion[2]), 3.0);
        assert_eq!(f32::from_bits(motion[5]), 4.0);
        let (x, v) = planned[0].burst.apply(DVec3::ONE, DVec3::ZERO);
        assert_eq!(
            (x, v),
            (DVec3::new(2.0, 3.0, 4.0), DVec3::new(0.0, 4.0, 0.0))
        );
        assert!(!Burst::new(0, 1).at([f32::NAN, 0.0, 0.0]).is_finite());
    }
}
