//! The reference run of an effect graph: every group's [`ReferenceSim`], and the events between
//! them delivered as the GPU delivers them (crate::features::events): at the start of each step, every
//! stream in order spawns the children of the last step's firings, then every group steps.

use crate::graph::{CompiledGraph, Stream};
use crate::reference::{ParticleRecord, ReferenceSim, Totals};

/// Runs a compiled graph on the CPU in f64.
#[derive(Clone, Debug)]
pub struct ReferenceGraph {
    groups: Vec<ReferenceSim>,
    streams: Vec<Stream>,
}

impl ReferenceGraph {
    /// A run at step 0 with no particles.
    pub fn new(graph: &CompiledGraph) -> Self {
        Self {
            groups: graph
                .groups
                .iter()
                .map(|g| ReferenceSim::new(&g.effect.ir))
                .collect(),
            streams: graph.streams.clone(),
        }
    }

    /// One step of every group, after the spawns of the last step's events.
    pub fn step(&mut self) {
        for s in &self.streams {
            let fired = self.groups[s.parent].fired(s.out_slot).to_vec();
            self.groups[s.child].spawn_events(s.in_slot, &fired);
        }
        for g in &mut self.groups {
            g.step();
        }
    }

    /// Places every group's emitters by `placement` from the next step on (a placed effect).
    pub fn set_placement(&mut self, placement: crate::features::placement::Placement) {
        for g in &mut self.groups {
            g.set_placement(placement);
        }
    }

    /// Gives every group's `SceneDepth` collider the depth image (see
    /// [`ReferenceSim::set_scene_depth`]).
    pub fn set_scene_depth(
        &mut self,
        image: &std::sync::Arc<crate::features::colliders::scene_depth::DepthImage>,
    ) {
        for g in &mut self.groups {
            g.set_scene_depth(image);
        }
    }

    /// Sets live param `name` in every group (see [`ReferenceSim::set_param`]).
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), String> {
        for g in &mut self.groups {
            g.set_param(name, value)?;
        }
        Ok(())
    }

    /// Queues a burst fired from code in group `group` (see [`ReferenceSim::burst`]).
    pub fn burst(
        &mut self,
        group: usize,
        burst: crate::features::bursts::Burst,
    ) -> Result<(), String> {
        let count = self.groups.len();
        self.groups
            .get_mut(group)
            .ok_or_else(|| format!("a burst in group {group}, but the effect has {count}"))?
            .burst(burst)
    }

    /// Runs `n` steps.
    pub fn run(&mut self, n: u64) {
        for _ in 0..n {
            self.step();
        }
    }

    /// Group `g`'s simulation.
    pub fn group(&self, g: usize) -> &ReferenceSim {
        &self.groups[g]
    }

    /// Group `g`'s live particles in id order.
    pub fn records(&self, g: usize) -> Vec<ParticleRecord> {
        self.groups[g].records()
    }

    /// Group `g`'s totals.
    pub fn totals(&self, g: usize) -> Totals {
        self.groups[g].totals()
    }
}
