//! An effect's totals read back without waiting (`Effect::watch_totals`, in `watch.rs`): every
//! stateful group's counters copied into one reading in the host's encoder, taken a frame or
//! two later, and added to the stateless groups' counts, which the CPU keeps.

use std::sync::Mutex;

use plume_compiler::reference::Totals;

use crate::device::async_read::AsyncRead;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sim::group::Group;

/// The reading of every stateful group's counters, and the steps done when it was copied.
pub(crate) struct TotalsWatch {
    reading: AsyncRead,
    /// The steps done at the last copy.
    copied_at: Mutex<u64>,
}

/// A stateful group's counters buffer and its size.
fn counters(group: &Group) -> Option<(&wgpu::Buffer, u64)> {
    group.counters().map(|c| (c, c.size()))
}

impl TotalsWatch {
    /// The reading of `groups`' counters.
    pub(crate) fn new(gpu: &Gpu, groups: &[Group]) -> Self {
        let bytes = groups
            .iter()
            .filter_map(counters)
            .map(|(_, n)| n)
            .sum::<u64>();
        Self {
            // A zero-sized buffer is not allowed: an effect of stateless groups copies nothing.
            reading: AsyncRead::new(gpu, "totals reading", bytes.max(4)),
            copied_at: Mutex::new(0),
        }
    }

    /// Takes a reading that came back (the totals at its copy, the stateless groups' as of
    /// `steps`), and records the next copy into `encoder` when the last was taken.
    pub(crate) fn watch(
        &self,
        groups: &[Group],
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<Option<Totals>, RuntimeError> {
        let taken = self.reading.poll()?;
        let mut copied_at = self.copied_at.lock().unwrap_or_else(|p| p.into_inner());
        let totals = match taken {
            Some(bytes) => {
                let mut sum = Totals {
                    steps: *copied_at,
                    alive: 0,
                    spawned: 0,
                    died: 0,
                    dropped: 0,
                };
                let mut at = 0;
                for group in groups {
                    let t = match counters(group) {
                        Some((_, n)) => {
                            let part = &bytes[at as usize..(at + n) as usize];
                            at += n;
                            group.decode_counters(part, *copied_at)
                        }
                        None => group.totals()?,
                    };
                    sum.alive += t.alive;
                    sum.spawned += t.spawned;
                    sum.died += t.died;
                    sum.dropped += t.dropped;
                }
                Some(sum)
            }
            None => None,
        };
        let parts: Vec<(&wgpu::Buffer, u64)> = groups.iter().filter_map(counters).collect();
        if self.reading.record_copies(encoder, &parts) {
            *copied_at = steps;
        }
        Ok(totals)
    }
}
