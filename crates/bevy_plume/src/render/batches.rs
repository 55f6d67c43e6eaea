//! Batched instances: a game's crowd of one small effect (impacts, torches, footsteps) costs
//! the CPU one upload, a few dispatches and one draw a frame, not each of those per entity.
//! When [`BATCH_FROM`] entities or more of a file variant exist in a frame, each new one that
//! can be batched joins a Plume [`EffectBatch`] of that variant (its own place in the batch's
//! buffers: its particles, schedule, placement, params and bursts, paused and scaled on its
//! own), instead of becoming an [`Effect`](plume_runtime::Effect) of its own. A batch is drawn
//! by one transparent item per camera that sees any of its entities, and freed when its last
//! entity goes.
//!
//! What can be batched: either space (a local-space entity's particles are drawn through its
//! transform), either renderer (a batch is drawn by one: entities of a variant that draw by
//! the raster pipeline and by the compute renderer, `PlumeDraw::Compute` or `Auto` at
//! [`AUTO_COMPUTE_CAPACITY`] particles and up, are batched apart), stateful, one group without
//! events, trails, depth sort, flocking, baked fields or scene-depth colliders. A batched entity gets
//! no measured bounds (a declared `bounds` still culls it) and is sorted with its batch.

use std::collections::BTreeMap;
use std::sync::Arc;

use bevy::ecs::entity::{EntityHashMap, EntityHashSet};
use bevy::platform::collections::hash_map::Entry;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use plume_compiler::graph::CompiledGraph;
use plume_compiler::placement::Placement;
use plume_compiler::CompiledEffect;
use plume_runtime::{BatchInstance, DrawTarget, EffectBatch, EffectRenderer, Gpu};

use crate::asset::Variant;
use crate::effect::{PlumeDraw, SimulationSpace, AUTO_COMPUTE_CAPACITY};
use crate::render::extract::{ExtractedBursts, ExtractedEffect, ExtractedEffects};
use crate::render::instances::{variant_graph, BuildKey, PlumeInstances, StepClock};
use crate::render::motion;

/// Entities of one file variant from which new ones of it are batched (those already running
/// alone go on so): a few effects keep what an effect alone has (measured bounds, their own
/// place in the transparent sort); a crowd is batched.
pub const BATCH_FROM: usize = 8;

/// The most instances one batch holds.
const BATCH_ROOM: u64 = 256;

/// The most particle state one batch allocates: fewer instances of a larger effect.
const BATCH_BYTES: u64 = 32 << 20;

/// A file variant's batches: by (the file version's address, variant, how they draw).
pub(crate) type SetKey = (usize, Variant, PlumeDraw);

/// The batched entities and their batches.
#[derive(Resource, Default)]
pub(crate) struct PlumeBatches {
    /// Each file variant's batches (None: one that emptied, its place kept so indices hold).
    sets: HashMap<SetKey, BatchSet>,
    /// Each batched entity, by main-world entity.
    pub members: EntityHashMap<Member>,
}

/// One file variant's batches and its batched compile.
struct BatchSet {
    /// The file version, kept alive so its address stays its own.
    _source: Arc<CompiledGraph>,
    compiled: CompiledEffect,
    pub batches: Vec<Option<RenderBatch>>,
}

/// One batch and its draws.
pub(crate) struct RenderBatch {
    /// The instances' buffers and kernels.
    pub batch: EffectBatch,
    /// The entity in each instance's place.
    slots: Vec<Option<Entity>>,
    /// How it draws: `Raster`, `Compute`, or `Auto` (the compute renderer on a GPU adapter).
    pub draw: PlumeDraw,
    /// The compute renderer failed to draw it once (said then): the raster one does.
    pub compute_refused: bool,
    /// Its draws, by the camera's render-world entity.
    pub views: EntityHashMap<BatchView>,
    /// Each place's steps this frame in parts (`EffectBatch::advance_along`), kept from frame
    /// to frame so that recording them allocates nothing.
    parts: Vec<Vec<(u64, Option<Placement>)>>,
    /// Bytes of particle state it holds.
    pub particle_bytes: u64,
    /// Its particles alive, as last read back (`PlumeDiagnosticsPlugin` reads them).
    pub alive: u64,
}

/// A batch's draw for one camera.
pub(crate) struct BatchView {
    pub target: DrawTarget,
    /// The compute renderer's image size (None: drawn by the raster renderer).
    pub size: Option<(u32, u32)>,
    pub renderer: EffectRenderer,
    /// The frame that last queued it.
    pub frame: u64,
}

/// One batched entity.
pub(crate) struct Member {
    key: BuildKey,
    set: SetKey,
    /// Its batch in the set's list, and its place there.
    pub batch: usize,
    pub instance: BatchInstance,
    clock: StepClock,
    world_from_local: Mat4,
    placed_at: Option<Mat4>,
    /// The entity's render-world twin.
    pub render_entity: Entity,
    params: BTreeMap<String, f32>,
}

impl Member {
    /// The entity's world transform this frame.
    pub(crate) fn world_from_local(&self) -> Mat4 {
        self.world_from_local
    }
}

impl PlumeBatches {
    /// The batch `entity` is in.
    pub(crate) fn batch_of(&self, entity: Entity) -> Option<&RenderBatch> {
        let member = self.members.get(&entity)?;
        self.sets
            .get(&member.set)?
            .batches
            .get(member.batch)?
            .as_ref()
    }

    /// The batch `entity` is in, by (its set, its place in the set).
    pub(crate) fn batch_id(&self, entity: Entity) -> Option<(SetKey, usize)> {
        self.members.get(&entity).map(|m| (m.set, m.batch))
    }

    /// The batch at `id`.
    pub(crate) fn batch_mut(&mut self, id: (SetKey, usize)) -> Option<&mut RenderBatch> {
        self.sets.get_mut(&id.0)?.batches.get_mut(id.1)?.as_mut()
    }

    /// Every batch.
    pub(crate) fn batches_mut(&mut self) -> impl Iterator<Item = &mut RenderBatch> {
        self.sets
            .values_mut()
            .flat_map(|s| s.batches.iter_mut().flatten())
    }

    /// Batches there are now.
    pub(crate) fn count(&self) -> usize {
        self.sets
            .values()
            .map(|s| s.batches.iter().flatten().count())
            .sum()
    }

    /// Bytes of particle state every batch holds.
    pub(crate) fn particle_bytes(&self) -> u64 {
        let batches = self.sets.values().flat_map(|s| s.batches.iter().flatten());
        batches.map(|b| b.particle_bytes).sum()
    }
}

/// Brings the batches in line with this frame's effect entities, before the instances are: a
/// batched entity's changes go to its batch (a restart restarts its place, a new file version
/// or variant moves it), a new entity that can be batched joins a batch when its variant has
/// [`BATCH_FROM`] entities or more, gone ones leave (a batch that empties is freed). The batched
/// entities and their bursts are then taken out of this frame's lists, which the instances
/// see next.
pub(crate) fn sync_batches(
    mut batches: ResMut<PlumeBatches>,
    mut extracted: ResMut<ExtractedEffects>,
    mut bursts: ResMut<ExtractedBursts>,
    mut store: ResMut<PlumeInstances>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let batches = &mut *batches;
    let gpu = store.gpu(&device, &queue);
    // Entities of each variant this frame, alone, batched or new.
    let keys: Vec<BuildKey> = extracted.effects.iter().map(BuildKey::of).collect();
    let mut crowds: HashMap<SetKey, usize> = HashMap::new();
    for (e, key) in extracted.effects.iter().zip(&keys) {
        if can_batch(e) {
            *crowds.entry(set_key(key, e)).or_default() += 1;
        }
    }
    let delta = extracted.delta;
    let mut alive = EntityHashSet::with_capacity(batches.members.len());
    for (e, key) in extracted.effects.iter().zip(keys) {
        // One that can no longer be batched (now timed on its own), or draws another way than
        // its batch, leaves: the instances make it an effect of its own.
        let leaves = |m: &Member| !can_batch(e) || m.set.2 != batch_draw(e);
        if batches.members.get(&e.main).is_some_and(leaves) {
            batches.leave(e.main);
        }
        // How the entity's build differs from its batch place's: not at all (Some(true)), by
        // its generation alone (Some(false)), by more (None); not batched: no entry.
        let change = batches.members.get(&e.main).map(|m| {
            let place = Arc::ptr_eq(&m.key.graph, &key.graph) && m.key.variant == key.variant;
            place.then_some(m.key.generation == key.generation)
        });
        match change {
            Some(Some(true)) => {}
            // A restart: the same place, started again.
            Some(Some(false)) => {
                if let Some((batch, member)) = batches.lookup_mut(e.main) {
                    if let Err(err) = batch.batch.restart(member.instance) {
                        error!("{}: {err}", e.asset.path);
                    }
                    member.key = key.clone();
                    member.clock = StepClock::new(e.asset.dt(), e.control.warm_up);
                    member.placed_at = None;
                }
            }
            // A new file version or variant: it leaves, and joins again below.
            Some(None) => batches.leave(e.main),
            None => {}
        }
        if !batches.members.contains_key(&e.main) && !store.instances.contains_key(&e.main) {
            let crowd = crowds.get(&set_key(&key, e)).copied().unwrap_or(0);
            if crowd >= BATCH_FROM && can_batch(e) {
                let joined = batches.join(&gpu, e, key.clone(), crowd, &mut store.variants);
                if let Err(message) = joined {
                    warn_once!("{message}: it runs alone");
                }
            }
        }
        let Some((batch, member)) = batches.lookup_mut(e.main) else {
            continue;
        };
        alive.insert(e.main);
        member.world_from_local = e.world_from_local;
        member.render_entity = e.render;
        // In local space its particles are drawn through its transform (world space: they
        // were placed when spawned, and its transform stays the identity).
        if e.control.space == SimulationSpace::Local {
            let cols = e.world_from_local.to_cols_array();
            if let Err(err) = batch.batch.set_transform(member.instance, cols) {
                warn_once!("{}: {err}", e.asset.path);
            }
        }
        if let Err(err) = batch.batch.set_spawn_scale(member.instance, e.spawn_scale) {
            warn_once!("{}: {err}", e.asset.path);
        }
        for (param, &value) in &e.control.params {
            if member.params.get(param) != Some(&value) {
                member.params.insert(param.clone(), value);
                if let Err(err) = batch.batch.set_param(member.instance, param, value) {
                    warn!("{}: {err}", e.asset.path);
                }
            }
        }
        member.clock.advance_time(e.effect_time(delta));
    }
    for (entity, fired) in &bursts.0 {
        let Some((batch, member)) = batches.lookup_mut(*entity) else {
            continue;
        };
        for burst in fired {
            if let Err(err) = batch.batch.burst(member.instance, burst.to_runtime()) {
                warn_once!("a burst was refused: {err}");
            }
        }
    }
    let gone: Vec<Entity> = batches
        .members
        .keys()
        .filter(|&e| !alive.contains(e))
        .copied()
        .collect();
    for entity in gone {
        batches.leave(entity);
    }
    extracted.effects.retain(|e| !alive.contains(&e.main));
    bursts.0.retain(|(entity, _)| !alive.contains(entity));
}

/// The batches of `key`'s file variant that `e` may join.
fn set_key(key: &BuildKey, e: &ExtractedEffect) -> SetKey {
    (Arc::as_ptr(&key.graph) as usize, key.variant, batch_draw(e))
}

/// How a batch of `e` draws: as `e` would alone, `Auto` below [`AUTO_COMPUTE_CAPACITY`]
/// particles being the raster renderer.
fn batch_draw(e: &ExtractedEffect) -> PlumeDraw {
    match e.control.draw {
        PlumeDraw::Auto if e.asset.graph.capacity() < AUTO_COMPUTE_CAPACITY => PlumeDraw::Raster,
        draw => draw,
    }
}

/// Whether `e` may join a batch (before its file is looked at): not timed on its own
/// ([`crate::PlumeGpuTime`]).
fn can_batch(e: &ExtractedEffect) -> bool {
    !e.timed
}

impl PlumeBatches {
    fn lookup_mut(&mut self, entity: Entity) -> Option<(&mut RenderBatch, &mut Member)> {
        let member = self.members.get_mut(&entity)?;
        let batch = self
            .sets
            .get_mut(&member.set)?
            .batches
            .get_mut(member.batch)?
            .as_mut()?;
        Some((batch, member))
    }

    /// Puts `e` in a batch of its variant with room (a new batch, with room for a `crowd` of
    /// entities, when none has), at its start; it runs alone when its effect cannot be batched
    /// (Ok), or the batch could not start (the error).
    fn join(
        &mut self,
        gpu: &Gpu,
        e: &ExtractedEffect,
        key: BuildKey,
        crowd: usize,
        variants: &mut crate::render::instances::Variants,
    ) -> Result<(), String> {
        let id = set_key(&key, e);
        let set = match self.sets.entry(id) {
            Entry::Occupied(set) => set.into_mut(),
            Entry::Vacant(place) => {
                let graph = variant_graph(e, &key, variants)?;
                if graph.groups.len() != 1 || !graph.streams.is_empty() {
                    return Ok(());
                }
                let effect = &graph.groups[0].effect;
                if plume_compiler::batch::unbatchable(effect).is_some() {
                    return Ok(());
                }
                let compiled = plume_compiler::batch::compile_batched(effect)
                    .map_err(|err| format!("{}: {err}", e.asset.path))?;
                place.insert(BatchSet {
                    _source: key.graph.clone(),
                    compiled,
                    batches: Vec::new(),
                })
            }
        };
        let room = set
            .batches
            .iter()
            .position(|b| b.as_ref().is_some_and(|b| b.batch.len() < b.slots.len()));
        let at = match room {
            Some(at) => at,
            None => {
                let layout = &set.compiled.layout;
                let per_instance =
                    u64::from(set.compiled.ir.capacity) * u64::from(layout.bytes_per_particle);
                // Room for the crowd there is (from `BATCH_FROM`, doubling), within the bytes.
                let wanted = (crowd as u64)
                    .next_power_of_two()
                    .clamp(BATCH_FROM as u64, BATCH_ROOM);
                let instances = (BATCH_BYTES / per_instance.max(1)).clamp(1, wanted) as u32;
                let batch = EffectBatch::new(gpu, &set.compiled, instances)
                    .map_err(|err| format!("{}: a batch could not start: {err}", e.asset.path))?;
                let made = RenderBatch {
                    batch,
                    slots: vec![None; instances as usize],
                    draw: id.2,
                    compute_refused: false,
                    views: EntityHashMap::default(),
                    parts: vec![Vec::new(); instances as usize],
                    particle_bytes: per_instance * u64::from(instances),
                    alive: 0,
                };
                match set.batches.iter().position(Option::is_none) {
                    Some(free) => {
                        set.batches[free] = Some(made);
                        free
                    }
                    None => {
                        set.batches.push(Some(made));
                        set.batches.len() - 1
                    }
                }
            }
        };
        let batch = set.batches[at].as_mut().expect("a batch with room");
        let instance = batch.batch.add().expect("a batch with room");
        batch.slots[instance.0 as usize] = Some(e.main);
        self.members.insert(
            e.main,
            Member {
                key,
                set: id,
                batch: at,
                instance,
                clock: StepClock::new(e.asset.dt(), e.control.warm_up),
                world_from_local: e.world_from_local,
                placed_at: None,
                render_entity: e.render,
                params: BTreeMap::new(),
            },
        );
        Ok(())
    }

    /// Takes `entity` out of its batch (its particles go before the next step); a batch left
    /// empty is freed, and a set left without batches goes.
    fn leave(&mut self, entity: Entity) {
        let Some(member) = self.members.remove(&entity) else {
            return;
        };
        let Some(set) = self.sets.get_mut(&member.set) else {
            return;
        };
        if let Some(Some(batch)) = set.batches.get_mut(member.batch) {
            let _ = batch.batch.remove(member.instance);
            batch.slots[member.instance.0 as usize] = None;
            if batch.batch.is_empty() {
                set.batches[member.batch] = None;
            }
        }
        if set.batches.iter().all(Option::is_none) {
            self.sets.remove(&member.set);
        }
    }

    /// Records every batch's steps for this frame into `encoder`: each entity's steps along
    /// its motion since the last frame, as a world-space effect alone steps.
    pub(crate) fn record_steps(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let members = &mut self.members;
        for set in self.sets.values_mut() {
            for batch in set.batches.iter_mut().flatten() {
                for (slot, parts) in batch.slots.iter().zip(&mut batch.parts) {
                    parts.clear();
                    if let Some(member) = slot.and_then(|e| members.get_mut(&e)) {
                        path(member, parts);
                    }
                }
                if let Err(err) = batch.batch.advance_along(encoder, &batch.parts) {
                    error!("{}: {err}", set.compiled.ir.name);
                }
            }
        }
    }
}

/// Appends to `parts` `member`'s steps this frame, taken from its clock, along its motion
/// since the last frame (as a world-space effect alone steps: `motion::parts`).
fn path(member: &mut Member, parts: &mut Vec<(u64, Option<Placement>)>) {
    let steps = std::mem::take(&mut member.clock.steps);
    let to = member.world_from_local;
    // In local space the emitters stay in the entity's own space: nothing to place.
    if !member.key.variant.placed || !to.is_finite() {
        // Its emitters stay where they were.
        parts.push((steps, None));
        return;
    }
    let from = member.placed_at.replace(to).unwrap_or(to);
    let placed = |at: Mat4| Placement::from_cols(at.to_cols_array());
    match steps {
        0 => {}
        // One place for every step: what `motion::parts` gives too, without its interpolation.
        _ if steps == 1 || from == to => parts.push((steps, placed(to))),
        _ => parts.extend(
            motion::parts(steps, from, to)
                .into_iter()
                .map(|(n, at)| (n, placed(at))),
        ),
    }
}
