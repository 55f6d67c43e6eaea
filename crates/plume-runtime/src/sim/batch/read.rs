//! Reading an [`EffectBatch`]'s instances back (for tests, tools and debugging): an
//! instance's counters, and its slots decoded as an effect of its capacity holds them.

use plume_compiler::passes::layout::COUNTERS_BYTES;
use plume_compiler::reference::{ParticleRecord, Totals};

use crate::device::readback::{decode_slots, decode_totals, read_buffer};
use crate::error::RuntimeError;
use crate::sim::batch::{BatchInstance, EffectBatch};

impl EffectBatch {
    /// `instance`'s totals (waits for the GPU): its counters, its own steps.
    pub fn totals(&self, instance: BatchInstance) -> Result<Totals, RuntimeError> {
        let state = self.state(instance)?;
        let group = self.group();
        let counters = group.res.counters.as_ref().expect("a batch is stateful");
        let bytes = read_buffer(&self.effect.gpu, counters)?;
        let at = instance.0 as usize * COUNTERS_BYTES as usize;
        Ok(decode_totals(
            &bytes[at..at + COUNTERS_BYTES as usize],
            self.batched.ir.capacity,
            state.schedule.steps_done(),
        ))
    }

    /// `instance`'s live particles, by id (waits for the GPU), as [`Effect::records`](crate::Effect::records) gives
    /// an effect's: ages and lifetimes in the instance's own steps.
    pub fn records(&self, instance: BatchInstance) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let state = self.state(instance)?;
        let group = self.group();
        let all = read_buffer(&self.effect.gpu, &group.chunks()?[0].buffer)?;
        let layout = &self.batched.layout;
        let (capacity, total) = (
            u64::from(self.batched.ir.capacity),
            u64::from(group.effect.ir.capacity),
        );
        // The instance's slots as an effect of its capacity holds them, with its death and
        // spawn steps moved from the batch's step index to its own.
        let words = layout.bytes_per_particle as usize / 4;
        let own = |w: usize| {
            [
                plume_compiler::passes::layout::Attribute::DeathStep,
                plume_compiler::passes::layout::Attribute::SpawnStep,
            ]
            .iter()
            .any(|a| layout.word_offset(*a) == Some(w))
        };
        let mut bytes = vec![0u8; layout.buffer_bytes(capacity) as usize];
        for i in 0..capacity {
            let slot = u64::from(instance.0) * capacity + i;
            for w in 0..words {
                let from = layout.word_byte(w, slot, total) as usize;
                let to = layout.word_byte(w, i, capacity) as usize;
                let mut word = u32::from_le_bytes(all[from..from + 4].try_into().expect("4 bytes"));
                if own(w) && word != u32::MAX {
                    word = word.wrapping_sub(state.held as u32);
                }
                bytes[to..to + 4].copy_from_slice(&word.to_le_bytes());
            }
        }
        let mut out: Vec<ParticleRecord> = decode_slots(&self.batched, &state.schedule, &[bytes])?
            .into_iter()
            .flatten()
            .collect();
        out.sort_by_key(|r| r.id);
        Ok(out)
    }
}
