//! The render world's effect instances: one Plume [`Effect`] per effect entity, made on Bevy's
//! render device, rebuilt when its file changes (hot reload), its seed or its generation
//! (restart), and dropped (with its GPU buffers) when the entity goes. Each instance keeps one
//! [`EffectRenderer`] per camera that draws it. A variant of a file (a seed, world space) is
//! compiled on Bevy's async compute task pool, not on the render thread: the entity draws
//! nothing until it is ready (an older version of it goes on drawing meanwhile), then starts
//! with the time it waited caught up.

use std::collections::BTreeMap;
use std::sync::Arc;

use bevy::ecs::entity::{EntityHashMap, EntityHashSet};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::tasks::{AsyncComputeTaskPool, Task};
use plume_compiler::graph::CompiledGraph;
use plume_runtime::{DrawTarget, Effect, EffectRenderer, Gpu};

use crate::asset::Variant;
use crate::effect::{PlumeBurst, PlumeDraw, SimulationSpace};
use crate::render::extract::{ExtractedBursts, ExtractedEffect, ExtractedEffects};
use crate::render::renderer_choice::renderer_or_raster;

/// At most this much effect time is stepped in one frame; a longer frame (a stall, a
/// breakpoint) drops the rest rather than stepping ever more to catch up.
const MAX_CATCH_UP_SECONDS: f64 = 0.25;

/// Steps are counted from the pending time over `dt` plus this fraction of a step, so that
/// rounding never holds back a step that a frame's time covers.
const STEP_SLACK: f64 = 1e-6;

/// What an instance was built from: a change of any part rebuilds it.
#[derive(Clone)]
pub(crate) struct BuildKey {
    /// The file's compiled version (compared by address: a hot reload makes a new one).
    pub graph: Arc<CompiledGraph>,
    pub variant: Variant,
    pub generation: u32,
}

impl BuildKey {
    pub(crate) fn of(effect: &ExtractedEffect) -> Self {
        let control = &effect.control;
        Self {
            graph: effect.asset.graph.clone(),
            variant: Variant {
                seed: control.seed,
                placed: control.space == SimulationSpace::World,
                bursts: control.takes_bursts,
                live_params: !control.params.is_empty(),
            },
            generation: control.generation,
        }
    }

    pub(crate) fn same(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.graph, &other.graph)
            && self.variant == other.variant
            && self.generation == other.generation
    }
}

/// One camera's draw of an instance.
pub(crate) struct ViewDraw {
    /// The target the renderer was made for (the camera's format, samples and depth).
    pub target: DrawTarget,
    /// The target's size, for the compute renderer (None: the raster one).
    pub size: Option<(u32, u32)>,
    /// The draw.
    pub renderer: EffectRenderer,
    /// The frame it was last queued in (a camera that stops seeing it drops it).
    pub frame: u64,
    /// Its GPU time, where the entity's is asked for ([`crate::PlumeGpuTime`]) and the
    /// diagnostics read back.
    pub timing: Option<DrawTiming>,
}

/// The timers of one camera's draw of a timed entity: its preparation (the compute work
/// before Bevy's transparent pass: depth sort, culling, the compute renderer's passes) and
/// its draw inside that pass. Each reading is a frame or two old.
pub(crate) struct DrawTiming {
    /// Between empty compute passes around the preparation (None: no timestamp queries).
    prepare: Option<plume_runtime::GpuTimer>,
    /// Inside Bevy's pass around the draw (None: no timestamps inside passes).
    pub pass: Option<plume_runtime::GpuTimer>,
    /// Nanoseconds of the last timed preparation and pass.
    prepare_ns: Option<u64>,
    pass_ns: Option<u64>,
}

impl DrawTiming {
    /// The timers on `gpu`, whichever it has.
    pub(crate) fn new(gpu: &plume_runtime::Gpu) -> Self {
        Self {
            prepare: plume_runtime::GpuTimer::new(gpu),
            pass: plume_runtime::GpuTimer::in_passes(gpu),
            prepare_ns: None,
            pass_ns: None,
        }
    }

    /// Before the preparation: takes its last reading and stamps its start.
    pub(crate) fn begin_prepare(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(timer) = &mut self.prepare {
            match timer.begin(encoder) {
                Ok(taken) => self.prepare_ns = taken.or(self.prepare_ns),
                Err(err) => warn_once!("plume draw timer: {err}"),
            }
        }
    }

    /// After the preparation: stamps its end.
    pub(crate) fn end_prepare(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(timer) = &mut self.prepare {
            timer.end(encoder);
        }
    }

    /// Before Bevy's pass: takes the pass timer's last reading and times this frame's draw.
    pub(crate) fn begin_pass(&mut self) {
        if let Some(timer) = &mut self.pass {
            match timer.begin_in_pass() {
                Ok(taken) => self.pass_ns = taken.or(self.pass_ns),
                Err(err) => warn_once!("plume draw timer: {err}"),
            }
        }
    }

    /// After Bevy's pass: records the copy of the draw's stamps.
    pub(crate) fn end_pass(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(timer) = &mut self.pass {
            timer.end_after_pass(encoder);
        }
    }

    /// The draw's last GPU time, its preparation's and its pass's, once both were read.
    pub(crate) fn ns(&self) -> Option<u64> {
        Some(self.prepare_ns? + self.pass_ns?)
    }
}

/// One effect entity's simulation and draws.
pub(crate) struct Instance {
    key: BuildKey,
    /// The effect on Bevy's device.
    pub effect: Effect,
    /// Its steps from the app's time.
    pub clock: StepClock,
    /// The entity's world transform: where a world-space effect's emitters spawn, or what
    /// every draw of a local-space one is seen through.
    pub world_from_local: Mat4,
    /// Where its particles live.
    pub space: SimulationSpace,
    /// Which renderer draws it.
    pub draw: PlumeDraw,
    /// Whether the compute renderer was refused (said once; the raster one draws then).
    compute_refused: bool,
    /// Particles it can hold, over every group.
    pub capacity: u64,
    /// The transform its last world-space steps spawned at (None before the first).
    pub placed_at: Option<Mat4>,
    /// The entity's render-world twin.
    pub render_entity: Entity,
    /// Its draws, by the camera's render-world entity.
    pub views: EntityHashMap<ViewDraw>,
    /// The kernels that pick the lights its particles give off (`render.light`; empty when
    /// they give off none), made on its first frame.
    pub particle_lights: Option<plume_runtime::ParticleLights>,
    /// Its particles' counts last read back (`PlumeDiagnosticsPlugin` reads them; None before).
    pub counts: Option<plume_compiler::reference::Totals>,
    /// Bytes of particle state it holds on the GPU.
    particle_bytes: u64,
    /// Targets its draw could not be made for (the error was logged).
    undrawable: Vec<DrawTarget>,
    /// The params' values the effect holds now (a refused one too, so it is said once).
    params: BTreeMap<String, f32>,
    /// Whether a refused burst was reported (said once per instance).
    burst_refused: bool,
    /// Whether its steps' GPU time is asked for ([`crate::PlumeGpuTime`]): its steps are then
    /// recorded apart, between the timestamps of `timer`.
    pub timed: bool,
    /// The timer of its steps, made on its first timed frame where the device has timestamp
    /// queries.
    pub timer: Option<plume_runtime::GpuTimer>,
    /// Nanoseconds of its last timed frame of steps.
    pub step_gpu_ns: Option<u64>,
}

/// An instance's steps from the app's time: whole steps of `dt` a frame, the rest carried.
pub(crate) struct StepClock {
    /// Seconds per step.
    dt: f64,
    /// Effect time not yet stepped.
    pending_time: f64,
    /// Steps to record this frame.
    pub steps: u64,
}

impl StepClock {
    /// A clock of `dt` seconds a step with `warm_up` seconds of steps due at once.
    pub(crate) fn new(dt: f64, warm_up: f32) -> Self {
        let warm_up = f64::from(warm_up.max(0.0));
        Self {
            dt,
            pending_time: 0.0,
            steps: (warm_up / dt).round() as u64,
        }
    }

    /// Adds `seconds` of effect time; whole steps of it are recorded this frame.
    pub(crate) fn advance_time(&mut self, seconds: f64) {
        let max_steps = (MAX_CATCH_UP_SECONDS / self.dt).ceil().max(1.0);
        self.pending_time += seconds.max(0.0);
        // A frame of exactly `dt` is one step: without the slack, 1/60 s over a dt of 1/60 s
        // can round to 0.99999, and a 60 Hz app would step 0, 2, 0, 2 ... times a frame.
        let steps = (self.pending_time / self.dt + STEP_SLACK)
            .floor()
            .min(max_steps);
        self.pending_time = (self.pending_time - steps * self.dt).clamp(0.0, self.dt);
        self.steps += steps as u64;
    }
}

/// Compiled variants of effect files, by (the file version's address, variant): the file
/// version (kept alive so the address stays its own) and the variant.
pub(crate) type Variants = HashMap<(usize, Variant), (Arc<CompiledGraph>, Arc<CompiledGraph>)>;

/// Variants being compiled on Bevy's async compute task pool, by the same key as
/// [`Variants`]: the file version and the task.
pub(crate) type Compiling =
    HashMap<(usize, Variant), (Arc<CompiledGraph>, Task<Result<CompiledGraph, String>>)>;

/// What the plugin holds in the render world, for a game's diagnostics and the tests: read it
/// with `app.sub_app(RenderApp).world().resource::<PlumeRenderStats>()`.
#[derive(Resource, Default, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlumeRenderStats {
    /// Effect instances running (one per effect entity whose file has loaded).
    pub instances: usize,
    /// Bytes of particle state they hold on the GPU (capacity times bytes per particle, trail
    /// history included, over every group of every instance).
    pub particle_bytes: u64,
    /// Camera draws of an effect queued this frame (an effect culled by its bounds has none).
    pub draws: usize,
    /// Of those, the ones the compute renderer makes (the rest are raster ones; see
    /// `PlumeDraw`).
    pub compute_draws: usize,
    /// Batches of instances running (a crowd of one file's effects shares one; see
    /// `bevy_plume::BATCH_FROM`). Their instances are counted in `instances`.
    pub batches: usize,
    /// Particles alive in every instance and batch, as last read back (a frame or two old);
    /// counted only with `PlumeDiagnosticsPlugin` added, else 0.
    pub live_particles: u64,
    /// GPU time of the last timed frame's steps (every instance's and batch's, with the
    /// readbacks recorded beside them), in nanoseconds; None without `PlumeDiagnosticsPlugin`
    /// or where the device has no timestamp queries.
    pub step_gpu_ns: Option<u64>,
}

/// Every instance, by main-world entity, and the device they run on.
#[derive(Resource, Default)]
pub(crate) struct PlumeInstances {
    /// Bevy's render device as Plume's [`Gpu`] (made on first use).
    pub gpu: Option<Gpu>,
    /// The instances.
    pub instances: EntityHashMap<Instance>,
    /// Builds that failed, by entity, so an error is logged once, not every frame.
    failed: EntityHashMap<BuildKey>,
    /// The files' variants compiled for a seed or for world space, so that a thousand
    /// instances of one file compile it once: by (the file version's address, seed, placed),
    /// with that version kept alive beside it (dropped once no instance uses it).
    pub variants: Variants,
    /// Variants being compiled off the render thread.
    compiling: Compiling,
    /// Effect time (s) that entities waiting for their variant have let pass, caught up by
    /// their instance's first frame, so that it runs as if it had started when spawned.
    waiting: EntityHashMap<f64>,
    /// Frames seen (ages views' draws).
    pub frame: u64,
}

impl PlumeInstances {
    /// Bevy's render device as Plume's [`Gpu`], made on first use.
    pub(crate) fn gpu(&mut self, device: &RenderDevice, queue: &RenderQueue) -> Gpu {
        self.gpu
            .get_or_insert_with(|| Gpu::from_device(device.wgpu_device(), queue))
            .clone()
    }
}

/// Brings the instances in line with this frame's effect entities: new ones built, changed
/// ones rebuilt (a failed rebuild logs why and keeps the last good one running), gone ones
/// dropped; then how many steps each records this frame.
pub(crate) fn sync_instances(
    mut store: ResMut<PlumeInstances>,
    mut stats: ResMut<PlumeRenderStats>,
    extracted: Res<ExtractedEffects>,
    bursts: Res<ExtractedBursts>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let store = &mut *store;
    store.frame += 1;
    let gpu = store.gpu(&device, &queue);
    let mut alive = EntityHashSet::with_capacity(extracted.effects.len());
    for e in &extracted.effects {
        alive.insert(e.main);
        let key = BuildKey::of(e);
        let current = store
            .instances
            .get(&e.main)
            .is_some_and(|i| i.key.same(&key));
        let known_bad = store.failed.get(&e.main).is_some_and(|k| k.same(&key));
        if !current && !known_bad {
            let graph = variant_graph_soon(e, &key, &mut store.variants, &mut store.compiling);
            match graph.and_then(|g| g.map(|g| build(&gpu, e, key.clone(), g)).transpose()) {
                Ok(Some(mut instance)) => {
                    store.failed.remove(&e.main);
                    if let Some(waited) = store.waiting.remove(&e.main) {
                        instance.clock.advance_time(waited);
                    }
                    store.instances.insert(e.main, instance);
                }
                // Still compiling: a running instance of an older key goes on meanwhile.
                Ok(None) => {
                    *store.waiting.entry(e.main).or_default() += e.effect_time(extracted.delta);
                }
                Err(message) => {
                    error!("{message}");
                    store.waiting.remove(&e.main);
                    store.failed.insert(e.main, key);
                }
            }
        }
        if let Some(instance) = store.instances.get_mut(&e.main) {
            instance.world_from_local = e.world_from_local;
            instance.space = e.control.space;
            instance.draw = e.control.draw;
            instance.render_entity = e.render;
            instance.timed = e.timed;
            if !e.timed {
                instance.timer = None;
                instance.step_gpu_ns = None;
            }
            instance.control_from_code(e);
            instance.clock.advance_time(e.effect_time(extracted.delta));
        }
    }
    for (entity, fired) in &bursts.0 {
        if let Some(instance) = store.instances.get_mut(entity) {
            instance.fire(fired);
        }
    }
    store.instances.retain(|entity, _| alive.contains(entity));
    store.failed.retain(|entity, _| alive.contains(entity));
    store.waiting.retain(|entity, _| alive.contains(entity));
    // A variant whose file version no asset or instance holds any more goes (a task
    // dropped is cancelled).
    store
        .variants
        .retain(|_, (source, _)| Arc::strong_count(source) > 1);
    store
        .compiling
        .retain(|_, (source, _)| Arc::strong_count(source) > 1);
    *stats = PlumeRenderStats {
        instances: store.instances.len(),
        particle_bytes: store.instances.values().map(|i| i.particle_bytes).sum(),
        // Counted as the draws are queued.
        draws: 0,
        compute_draws: 0,
        batches: 0,
        // Read back after the steps (`render::counts`).
        live_particles: 0,
        step_gpu_ns: None,
    };
}

/// `e`'s file compiled for `key`'s variant: the file as written, or its variant (compiled
/// once, then shared).
pub(crate) fn variant_graph(
    e: &ExtractedEffect,
    key: &BuildKey,
    variants: &mut Variants,
) -> Result<Arc<CompiledGraph>, String> {
    Ok(match key.variant {
        as_written if as_written == Variant::default() => e.asset.graph.clone(),
        wanted => {
            let id = (Arc::as_ptr(&e.asset.graph) as usize, wanted);
            match variants.get(&id) {
                Some((_, variant)) => variant.clone(),
                None => {
                    let variant = Arc::new(e.asset.compile_with(wanted)?);
                    variants.insert(id, (e.asset.graph.clone(), variant.clone()));
                    variant
                }
            }
        }
    })
}

/// [`variant_graph`] without waiting: a variant not compiled yet is compiled on Bevy's async
/// compute task pool (at once where there is none), and None says it is not ready this frame.
fn variant_graph_soon(
    e: &ExtractedEffect,
    key: &BuildKey,
    variants: &mut Variants,
    compiling: &mut Compiling,
) -> Result<Option<Arc<CompiledGraph>>, String> {
    let wanted = key.variant;
    let id = (Arc::as_ptr(&e.asset.graph) as usize, wanted);
    if wanted == Variant::default() || variants.contains_key(&id) {
        return variant_graph(e, key, variants).map(Some);
    }
    let Some(pool) = AsyncComputeTaskPool::try_get() else {
        return variant_graph(e, key, variants).map(Some);
    };
    match compiling.get_mut(&id) {
        Some((_, task)) if task.is_finished() => {
            let Some((source, task)) = compiling.remove(&id) else {
                return Ok(None);
            };
            let variant = Arc::new(bevy::tasks::block_on(task)?);
            variants.insert(id, (source, variant.clone()));
            Ok(Some(variant))
        }
        Some(_) => Ok(None),
        None => {
            let asset = e.asset.clone();
            let task = pool.spawn(async move { asset.compile_with(wanted) });
            compiling.insert(id, (e.asset.graph.clone(), task));
            Ok(None)
        }
    }
}

/// A new instance of `e`'s effect on `gpu` running `graph` (the file as written, or its
/// variant for the instance's seed and space), with its warm-up steps due this frame.
fn build(
    gpu: &Gpu,
    e: &ExtractedEffect,
    key: BuildKey,
    graph: Arc<CompiledGraph>,
) -> Result<Instance, String> {
    let graph = (*graph).clone();
    let particle_bytes = graph
        .groups
        .iter()
        .map(|g| {
            let layout = &g.effect.layout;
            let per_particle = layout.state_bytes_per_particle() + layout.trail_bytes_per_particle;
            u64::from(g.effect.ir.capacity) * u64::from(per_particle)
        })
        .sum();
    let capacity = graph.capacity();
    let effect = Effect::from_graph(gpu, graph)
        .map_err(|err| format!("{}: the effect could not start: {err}", e.asset.path))?;
    Ok(Instance {
        key,
        effect,
        clock: StepClock::new(e.asset.dt(), e.control.warm_up),
        world_from_local: e.world_from_local,
        space: e.control.space,
        draw: e.control.draw,
        compute_refused: false,
        capacity,
        placed_at: None,
        render_entity: e.render,
        views: EntityHashMap::default(),
        particle_lights: None,
        counts: None,
        particle_bytes,
        undrawable: Vec::new(),
        params: BTreeMap::new(),
        burst_refused: false,
        timed: e.timed,
        timer: None,
        step_gpu_ns: None,
    })
}

impl Instance {
    /// Applies the frame's spawn scale and the params whose value game code changed. What the
    /// effect refuses is logged, once per value.
    fn control_from_code(&mut self, e: &ExtractedEffect) {
        self.effect.set_spawn_scale(e.spawn_scale);
        let name = &e.asset.path;
        for (param, &value) in &e.control.params {
            if self.params.get(param) == Some(&value) {
                continue;
            }
            self.params.insert(param.clone(), value);
            if let Err(err) = self.effect.set_param(param, value) {
                warn!("{name}: {err}");
            }
        }
    }

    /// Queues the bursts game code fired for the instance's next step. A refused one is
    /// logged, once per instance.
    fn fire(&mut self, bursts: &[PlumeBurst]) {
        for burst in bursts {
            if let Err(err) = self.effect.burst(burst.group, burst.to_runtime()) {
                if !self.burst_refused {
                    self.burst_refused = true;
                    let fix = match self.key.variant.bursts {
                        true => "",
                        false => " (spawn it with PlumeEffect::with_bursts())",
                    };
                    let name = &self.effect.compiled().ir.name;
                    warn!("{name}: a burst was refused: {err}{fix}");
                }
            }
        }
    }

    /// Whether the compute renderer draws every group of the effect (it draws no ribbons
    /// joining particles): `PlumeDraw::Auto` picks it only then.
    pub(crate) fn compute_draws(&self) -> bool {
        let groups: Vec<&plume_compiler::EffectIr> = (0..self.effect.group_names().len())
            .filter_map(|g| self.effect.group_compiled(g).ok())
            .map(|c| &c.ir)
            .collect();
        plume_runtime::outputs::ComputeOffscreen::why_not(&groups).is_none()
    }

    /// The draw for the camera `view` into `target`, made (or remade, when the camera's
    /// format, samples or size changed) as needed: by the compute renderer into a target of
    /// `compute_size` when that is given and the effect takes it (else the raster one, the
    /// reason logged once); None, with the reason logged once, when the effect cannot be
    /// drawn there.
    pub(crate) fn view_draw(
        &mut self,
        view: Entity,
        target: DrawTarget,
        compute_size: Option<(u32, u32)>,
        frame: u64,
    ) -> Option<()> {
        let size = compute_size.filter(|_| !self.compute_refused);
        if let Some(draw) = self.views.get_mut(&view) {
            if draw.target == target && draw.size == size {
                draw.frame = frame;
                return Some(());
            }
        }
        let name = self.effect.compiled().ir.name.clone();
        if size.is_none() && self.undrawable.contains(&target) {
            return None;
        }
        let (size, renderer) =
            renderer_or_raster(&self.effect, &target, size, &mut self.compute_refused);
        match renderer {
            Ok(renderer) => {
                self.views.insert(
                    view,
                    ViewDraw {
                        target,
                        size,
                        renderer,
                        frame,
                        timing: None,
                    },
                );
                Some(())
            }
            Err(err) => {
                // Said once per kind of target, not every frame.
                if !self.undrawable.contains(&target) {
                    error!("{name}: cannot be drawn: {err}");
                    self.undrawable.push(target);
                }
                None
            }
        }
    }
}
