//! What an [`Effect`] tells its host: totals, particle records, live bounds, each group's
//! names and compiled effect, and the counters a host reads without waiting.

use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::{CompiledEffect, Diagnostics};

use crate::device::gpu::Gpu;
use crate::device::readback::decode_totals;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
#[cfg(feature = "tools")]
use crate::sim::graph::Events;
use crate::sim::group::Group;

impl Effect {
    /// Steps done and the counters of every group added up: alive, spawned, died, dropped
    /// (waits for the GPU). A stateless group counts from its bookkeeping.
    pub fn totals(&self) -> Result<Totals, RuntimeError> {
        let mut sum = Totals {
            steps: self.steps_done(),
            alive: 0,
            spawned: 0,
            died: 0,
            dropped: 0,
        };
        for group in &self.groups {
            let t = group.totals()?;
            sum.alive += t.alive;
            sum.spawned += t.spawned;
            sum.died += t.died;
            sum.dropped += t.dropped;
        }
        Ok(sum)
    }

    /// The live particles of every group, group by group, each in id order (velocity as the
    /// integrator knows it: Verlet's derived). Reads them back and waits.
    pub fn records(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let mut out = Vec::new();
        for group in &self.groups {
            out.extend(group.records()?);
        }
        Ok(out)
    }

    /// The box that holds every live particle of every group now (its corners in metres),
    /// measured on the GPU (a stateless effect's particles evaluated at the steps
    /// done); None when none is alive. For a host's culling, or to write a file's `bounds`
    /// (`plume run --bounds` takes the union over a run). Reads 24 bytes back and waits.
    /// [`LiveBounds`](crate::LiveBounds) has an example.
    pub fn live_bounds(&self) -> Result<Option<crate::sim::bounds::LiveBounds>, RuntimeError> {
        for group in &self.groups {
            group.evaluate_view()?;
        }
        self.bounds_probe()?.measure()
    }

    /// The groups' names, the top-level group first (one name for an effect without groups).
    pub fn group_names(&self) -> &[String] {
        &self.names
    }

    /// About how many particles the effect keeps alive unthinned, every group's together
    /// (`EffectIr::expected_alive`): what a host sharing a particle budget weighs it by.
    pub fn expected_alive(&self) -> u64 {
        self.groups
            .iter()
            .map(|g| g.effect.ir.expected_alive())
            .sum()
    }

    /// The fraction of its spawns the effect keeps ([`Effect::set_spawn_scale`]).
    pub fn spawn_scale(&self) -> f32 {
        self.groups[0].schedule.spawn_scale()
    }

    /// Group `g`'s totals (its spawned and dropped count its event spawns).
    pub fn group_totals(&self, g: usize) -> Result<Totals, RuntimeError> {
        self.group(g)?.totals()
    }

    /// Group `g`'s live particles in id order.
    pub fn group_records(&self, g: usize) -> Result<Vec<ParticleRecord>, RuntimeError> {
        self.group(g)?.records()
    }

    /// The top-level group's compiled effect (its IR: camera, render section, dt, ...).
    pub fn compiled(&self) -> &CompiledEffect {
        &self.groups[0].effect
    }

    /// Group `g`'s compiled effect.
    pub fn group_compiled(&self, g: usize) -> Result<&CompiledEffect, RuntimeError> {
        Ok(&self.group(g)?.effect)
    }

    /// The compiler's warnings about the effect (its groups' and its events').
    pub fn warnings(&self) -> &Diagnostics {
        &self.warnings
    }

    /// Steps done so far.
    pub fn steps_done(&self) -> u64 {
        self.groups[0].steps_done()
    }

    /// Simulation time of the steps done, k · dt (s, f64).
    pub fn time(&self) -> f64 {
        self.steps_done() as f64 * self.compiled().ir.dt
    }

    /// Whether every group runs stateless (no state kept; computed when read or drawn, so its
    /// steps record no GPU work).
    pub fn is_stateless(&self) -> bool {
        self.groups.iter().all(Group::is_stateless)
    }

    /// The top-level group's counters, for a host that reads totals without waiting: copy
    /// them in its encoder, map the copy, and decode it with [`Self::decode_counters`]. None
    /// for a stateless group, whose totals need no GPU.
    pub fn counters(&self) -> Option<&wgpu::Buffer> {
        self.groups[0].counters()
    }

    /// Decodes a copy of [`Self::counters`], made when `steps` steps were done, of a group
    /// of `capacity` slots, into totals.
    pub fn decode_counters(bytes: &[u8], capacity: u32, steps: u64) -> Totals {
        decode_totals(bytes, capacity, steps)
    }

    /// The device this effect runs on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Group `g`, or the error of asking for one the effect does not have.
    pub(crate) fn group(&self, g: usize) -> Result<&Group, RuntimeError> {
        self.groups.get(g).ok_or_else(|| {
            RuntimeError::Output(format!(
                "the effect has {} groups, not {}",
                self.groups.len(),
                g + 1
            ))
        })
    }

    /// Every group, the top-level one first.
    pub(crate) fn groups(&self) -> &[Group] {
        &self.groups
    }

    /// Every group, mutably (the benchmarks time their steps).
    pub(crate) fn groups_mut(&mut self) -> &mut [Group] {
        &mut self.groups
    }

    /// The event streams (None: one group that steps alone).
    #[cfg(feature = "tools")]
    pub(crate) fn events(&self) -> Option<&Events> {
        self.events.as_ref()
    }
}
