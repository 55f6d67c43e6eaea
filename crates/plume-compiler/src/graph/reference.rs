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

    /// Keeps `scale` of every group's own spawns from the next step on (see
    /// [`ReferenceSim::set_spawn_scale`]); children fed by events follow their parents.
    pub fn set_spawn_scale(&mut self, scale: f32) {
        for g in &mut self.groups {
            g.set_spawn_scale(scale);
        }
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

/// Steps the f64 run looks for a parent's first firing before giving up (20 s at 60 Hz).
pub const SAMPLE_SEARCH_STEPS: u64 = 1_200;

/// The sample burst of group `g`, fed by events alone (`EffectSpec::sample_burst`): a burst of
/// `particles` of the spawn rule of the first event into it, at the position of its parent's
/// first firing in an f64 run of `graph` and with the share of that parent's velocity the event
/// passes on. None when no event feeds `g` or none fires within [`SAMPLE_SEARCH_STEPS`].
pub fn sample_burst(
    graph: &CompiledGraph,
    g: usize,
    particles: u32,
) -> Option<crate::features::bursts::Burst> {
    let (s, stream) = graph
        .streams
        .iter()
        .enumerate()
        .find(|(_, s)| s.child == g)?;
    let input = graph.groups[g]
        .effect
        .ir
        .event_inputs
        .iter()
        .find(|i| i.stream == s)?
        .clone();
    let mut run = ReferenceGraph::new(graph);
    for _ in 0..SAMPLE_SEARCH_STEPS {
        run.step();
        if let Some(f) = run.group(stream.parent).fired(stream.out_slot).first() {
            let v = input.inherit_velocity * f.v;
            return Some(crate::features::bursts::Burst {
                emitter: input.emitter as u32,
                count: particles,
                offset: f.x.as_vec3().to_array(),
                velocity: v.as_vec3().to_array(),
            });
        }
    }
    None
}

/// Group `g` of `groups` (the file's groups as effects of their own, `graph::group_effects`),
/// fed by events alone, made measurable alone: its events left out, the spawn rule of the first
/// event into it as its one emitter, and a [`sample_burst`] of `particles` of it
/// (`EffectSpec::sample_burst`, which the budget check and `plume accuracy`'s sweep fire at their first
/// step). None when no event into it fires within [`SAMPLE_SEARCH_STEPS`].
pub fn sampled_group(
    groups: &[crate::stages::schema::EffectSpec],
    graph: &CompiledGraph,
    g: usize,
    particles: u32,
) -> Option<crate::stages::schema::EffectSpec> {
    let burst = sample_burst(graph, g, particles)?;
    let stream = graph.streams.iter().find(|s| s.child == g)?;
    let event = &groups[stream.parent].events[stream.out_slot];
    let mut group = groups[g].clone();
    group.events.clear();
    group.emitters = vec![event.as_emitter()];
    group.bursts = true;
    group.sample_burst = Some(crate::features::bursts::Burst {
        emitter: 0,
        ..burst
    });
    Some(group)
}
