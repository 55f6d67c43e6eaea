//! [`EffectBatch`]: many instances of one effect, stepped by one chain of dispatches and drawn
//! by one draw. A game runs hundreds of copies of one small effect (impacts, torches,
//! footsteps); as separate [`Effect`]s each costs the CPU its own uploads, dispatches and
//! draw every frame, which soon costs more than the GPU work. A batch holds them all in one
//! effect's buffers (`plume_compiler::batch` lays them out), so the CPU cost of a frame is
//! one upload, three dispatches a step and one draw, whatever the number of instances.
//!
//! Each instance keeps what makes it itself: its spawn schedule (ids, emitter counters,
//! bursts, time), its placement and its live params. Instances share the batch's step index;
//! one that takes fewer steps in a frame than the batch (paused, or slower) is held through
//! the others, its particles' ages unchanged.

use plume_compiler::batch::compile_batched;
use plume_compiler::bursts::Burst;
use plume_compiler::passes::layout::COUNTERS_BYTES;
use plume_compiler::placement::Placement;
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::schedule::Schedule;
use plume_compiler::wgsl::WORKGROUP;
use plume_compiler::CompiledEffect;

use crate::device::buffers::staging;
use crate::device::gpu::Gpu;
use crate::device::readback::{decode_slots, decode_totals, read_buffer};
use crate::device::resources::{Resources, BATCH_STEPS};
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use crate::sim::group::Group;
use crate::sim::steps::{write_params_row, Steps};

/// An instance's place in an [`EffectBatch`] (from [`EffectBatch::add`]); the place is given
/// to a new instance once this one is removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BatchInstance(pub u32);

/// Many instances of one effect in one set of buffers: one dispatch chain steps them all
/// ([`Self::advance`]) and one draw draws them all (the draw of [`Self::effect`], through
/// [`Effect::renderer`] and [`Effect::prepare_draw`] as for any effect).
///
/// Batches take effects of one group without events, trails, depth sort, flocking, a baked
/// field, motion in halves or a scene-depth collider (`plume_compiler::batch::unbatchable`
/// says which stops one). Effects placed in a world ([`Self::set_placement`]) draw from one
/// world space: a batch draws every instance through one camera.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_compiler::{placement::Placement, CompileOptions};
/// use plume_runtime::{EffectBatch, Gpu};
/// let source = r#"Effect(name: "puff", capacity: 64,
///     emitters: [Emitter(rate: 600.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))])"#;
/// let options = CompileOptions { placed: true, ..Default::default() };
/// let compiled = plume_compiler::compile_str(source, &options)?;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut puffs = EffectBatch::new(&gpu, &compiled, 100)?;
/// let a = puffs.add().expect("room for 100");
/// let b = puffs.add().expect("room for 100");
/// puffs.set_placement(b, Placement::from_cols([1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
///     0.0, 0.0, 1.0, 0.0, 5.0, 0.0, 0.0, 1.0]).unwrap())?;
/// let mut encoder = gpu.device.create_command_encoder(&Default::default());
/// puffs.advance(&mut encoder, |_| 6)?; // every instance 6 steps: 60 particles each
/// gpu.queue.submit([encoder.finish()]);
/// assert_eq!(puffs.totals(a)?.alive, 60);
/// assert!(puffs.records(b)?.iter().all(|r| r.position.x > 5.0));
/// # Ok(())
/// # }
/// ```
pub struct EffectBatch {
    /// The batch's one group: its buffers (every instance's) and its draw.
    effect: Effect,
    /// The batched compile, `CAPACITY` an instance's (how one instance's slots decode).
    batched: CompiledEffect,
    instances: Vec<Option<InstanceState>>,
    /// Instances whose slots are freed before the next step: new, restarted or removed.
    to_init: Vec<u32>,
    kernels: BatchKernels,
    /// Bytes of one instance's row, and of one step's rows (aligned for a dynamic offset).
    row_bytes: u64,
    step_stride: u64,
}

/// What one instance keeps.
struct InstanceState {
    schedule: Schedule,
    placement: Placement,
    live_params: Vec<f32>,
    /// Steps the batch took that this instance sat out: the batch's step index less its own.
    held: u64,
}

/// The batched module's kernels.
struct BatchKernels {
    init: wgpu::ComputePipeline,
    init_last: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    spawn: wgpu::ComputePipeline,
    update: wgpu::ComputePipeline,
}

impl EffectBatch {
    /// A batch of room for `instances` instances of `compiled` (an effect of one group,
    /// compiled with `placed` for instances at places of their own, `bursts` and
    /// `live_params` as each instance needs), its buffers allocated and every slot free. An
    /// effect batching does not cover is refused with the reason.
    pub fn new(gpu: &Gpu, compiled: &CompiledEffect, instances: u32) -> Result<Self, RuntimeError> {
        let batched = match compiled.layout.batched {
            true => compiled.clone(),
            false => compile_batched(compiled).map_err(|e| RuntimeError::Control(e.to_string()))?,
        };
        let instances = instances.max(1);
        let capacity = batched.ir.capacity;
        let total = capacity.checked_mul(instances).ok_or_else(|| {
            RuntimeError::Control(format!(
                "{instances} instances of {capacity} slots are more slots than a batch holds"
            ))
        })?;
        let row_bytes = batched.layout.params_bytes();
        // The effect the runtime allocates and draws: every instance's slots, counters and rows.
        let mut whole = batched.clone();
        whole.ir.capacity = total;
        for binding in &mut whole.layout.bindings {
            match binding.name {
                "counters" => binding.bytes = COUNTERS_BYTES * u64::from(instances),
                "params" => binding.bytes = row_bytes * u64::from(instances),
                _ => {}
            }
        }
        let res = Resources::new(gpu, &whole, None, &[])?;
        if res.chunk_count() > 1 {
            return Err(RuntimeError::Control(format!(
                "{instances} instances of {capacity} slots are more than one particle buffer holds on this adapter: batch fewer"
            )));
        }
        let steps = Steps::new(gpu, &res, &whole)?;
        let Steps::Stateful(stateful) = &steps else {
            return Err(RuntimeError::Control("a batched effect is stateful".into()));
        };
        // The group's kernels, and the one that frees a single instance's slots.
        let kernels = BatchKernels {
            init: stateful.init.clone(),
            init_last: res.pipeline("init_last"),
            prepare: stateful.prepare.clone(),
            spawn: stateful.spawn.clone(),
            update: stateful.update.clone(),
        };
        let step_stride = res.params_stride;
        // The group's schedule only counts the batch's steps (the draw reads them): it spawns
        // nothing itself, the instances' schedules do.
        let mut counting = whole.ir.clone();
        counting.emitters.clear();
        let group = Group {
            gpu: gpu.clone(),
            schedule: Schedule::new(&counting),
            live_params: whole.ir.live_params.iter().map(|p| p.1 as f32).collect(),
            effect: whole,
            res,
            steps,
            depth: None,
            placement: Placement::IDENTITY,
        };
        let batch = Self {
            effect: Effect {
                gpu: gpu.clone(),
                names: vec![batched.ir.name.clone()],
                groups: vec![group],
                events: None,
                warnings: batched.warnings.clone(),
                depth_copy: Default::default(),
                bounds: std::sync::OnceLock::new(),
            },
            batched,
            instances: (0..instances).map(|_| None).collect(),
            to_init: Vec::new(),
            kernels,
            row_bytes,
            step_stride,
        };
        // Every instance's slots free and its counters zeroed, in one dispatch.
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            let (x, y) = gpu.grid(u64::from(capacity), u64::from(WORKGROUP))?;
            pass.set_pipeline(&batch.kernels.init);
            pass.set_bind_group(0, &batch.group().chunks()?[0].bind_group, &[0]);
            pass.dispatch_workgroups(x, y, instances);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error()?;
        Ok(batch)
    }

    /// The batch as one effect: what draws every instance ([`Effect::renderer`] and
    /// [`Effect::compute_renderer`], then [`Effect::prepare_draw`]), and its totals and live
    /// box over every instance. Read an instance's particles back with [`Self::records`]: the
    /// effect's own records count ages in the batch's steps.
    pub fn effect(&self) -> &Effect {
        &self.effect
    }

    fn group(&self) -> &Group {
        &self.effect.groups[0]
    }

    /// The batched compile (its `ir.capacity` is one instance's).
    pub fn compiled(&self) -> &CompiledEffect {
        &self.batched
    }

    /// Instances the batch has room for.
    pub fn room(&self) -> u32 {
        self.instances.len() as u32
    }

    /// Instances in the batch now.
    pub fn len(&self) -> usize {
        self.instances.iter().flatten().count()
    }

    /// Whether the batch holds no instance.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Adds an instance: at its start, at the identity placement, with the file's params.
    /// None when the batch is full. Its slots are freed before the next step.
    pub fn add(&mut self) -> Option<BatchInstance> {
        let at = self.instances.iter().position(Option::is_none)?;
        self.instances[at] = Some(self.fresh_state());
        self.to_init.push(at as u32);
        Some(BatchInstance(at as u32))
    }

    fn fresh_state(&self) -> InstanceState {
        InstanceState {
            schedule: Schedule::new(&self.batched.ir),
            placement: Placement::IDENTITY,
            live_params: self
                .batched
                .ir
                .live_params
                .iter()
                .map(|p| p.1 as f32)
                .collect(),
            held: self.group().schedule.steps_done(),
        }
    }

    /// Removes `instance`: its particles are freed before the next step (and drawn no more
    /// from then), and its place is free for another.
    pub fn remove(&mut self, instance: BatchInstance) -> Result<(), RuntimeError> {
        self.state_mut(instance)?;
        self.instances[instance.0 as usize] = None;
        self.to_init.push(instance.0);
        Ok(())
    }

    /// Starts `instance` again: its particles freed, its schedule at its start; its placement
    /// and params kept.
    pub fn restart(&mut self, instance: BatchInstance) -> Result<(), RuntimeError> {
        let fresh = self.fresh_state();
        let state = self.state_mut(instance)?;
        state.schedule = fresh.schedule;
        state.held = fresh.held;
        self.to_init.push(instance.0);
        Ok(())
    }

    fn state(&self, instance: BatchInstance) -> Result<&InstanceState, RuntimeError> {
        self.instances
            .get(instance.0 as usize)
            .and_then(Option::as_ref)
            .ok_or_else(|| {
                RuntimeError::Control(format!("no instance {} in this batch", instance.0))
            })
    }

    fn state_mut(&mut self, instance: BatchInstance) -> Result<&mut InstanceState, RuntimeError> {
        self.instances
            .get_mut(instance.0 as usize)
            .and_then(Option::as_mut)
            .ok_or_else(|| {
                RuntimeError::Control(format!("no instance {} in this batch", instance.0))
            })
    }

    /// Where `instance`'s emitters spawn from its next step on (an effect compiled `placed`).
    pub fn set_placement(
        &mut self,
        instance: BatchInstance,
        placement: Placement,
    ) -> Result<(), RuntimeError> {
        self.state_mut(instance)?.placement = placement;
        Ok(())
    }

    /// Sets `instance`'s param `name` (an effect compiled with `live_params`), as
    /// [`Effect::set_param`] does for an effect.
    pub fn set_param(
        &mut self,
        instance: BatchInstance,
        name: &str,
        value: f32,
    ) -> Result<(), RuntimeError> {
        if !(value.is_finite() && f64::from(value.abs()) <= plume_compiler::expr::VALUE_BOUND) {
            return Err(RuntimeError::Control(format!(
                "param `{name}` = {value}: a param must be finite and within ±1e18"
            )));
        }
        let names: Vec<&str> = self
            .batched
            .ir
            .live_params
            .iter()
            .map(|p| p.0.as_str())
            .collect();
        let index = names.iter().position(|n| *n == name).ok_or_else(|| {
            RuntimeError::Control(format!(
                "unknown param `{name}`: the batch's live params are [{}]",
                names.join(", ")
            ))
        })?;
        self.state_mut(instance)?.live_params[index] = value;
        Ok(())
    }

    /// Queues a burst for `instance`'s next step (an effect compiled with `bursts`), as
    /// [`Effect::burst`] does for an effect.
    pub fn burst(&mut self, instance: BatchInstance, burst: Burst) -> Result<(), RuntimeError> {
        if !self.batched.ir.bursts {
            return Err(RuntimeError::Control(
                "this batch does not take bursts from code: compile it with CompileOptions { bursts: true, .. }".into(),
            ));
        }
        let state = self.state_mut(instance)?;
        state
            .schedule
            .queue_burst(burst)
            .map_err(RuntimeError::Control)
    }

    /// Steps `instance` has taken of its own.
    pub fn steps_done(&self, instance: BatchInstance) -> Result<u64, RuntimeError> {
        Ok(self.state(instance)?.schedule.steps_done())
    }

    /// Records this frame's steps into `encoder`: `steps(instance)` steps for each instance (0
    /// for one that is paused). The batch takes as many steps as the instance that takes
    /// most; the others sit out the rest, held. First the slots of instances added, restarted
    /// or removed since the last call are freed. Then, per [`BATCH_STEPS`] steps, one upload
    /// of every instance's rows and one compute pass. The schedules advance now.
    pub fn advance(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: impl Fn(BatchInstance) -> u64,
    ) -> Result<(), RuntimeError> {
        let parts: Vec<Vec<(u64, Option<Placement>)>> = (0..self.instances.len())
            .map(|k| match self.instances[k] {
                Some(_) => vec![(steps(BatchInstance(k as u32)), None)],
                None => Vec::new(),
            })
            .collect();
        self.advance_along(encoder, &parts)
    }

    /// [`Self::advance`] with each instance's steps in parts: `parts[k]`, for the instance in
    /// place k ([`BatchInstance`]`(k)`), is a list of (steps, the placement they spawn at, or
    /// None to keep the one set), in order; a place without an instance, or past the list, is
    /// ignored. A host whose emitter moved far in a frame of several steps spawns along the
    /// way so.
    pub fn advance_along(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[Vec<(u64, Option<Placement>)>],
    ) -> Result<(), RuntimeError> {
        let wants: Vec<u64> = (0..self.instances.len())
            .map(|k| match (&self.instances[k], parts.get(k)) {
                (Some(_), Some(p)) => p.iter().map(|q| q.0).sum(),
                _ => 0,
            })
            .collect();
        let most = wants.iter().copied().max().unwrap_or(0);
        // Dispatches cover the instances up to the last one there is.
        let layers = self
            .instances
            .iter()
            .rposition(Option::is_some)
            .map_or(0, |k| k + 1);
        self.record_inits(encoder)?;
        let mut done = 0;
        while done < most {
            let n = (most - done).min(u64::from(BATCH_STEPS));
            self.record_plan(encoder, parts, done, n, layers as u32)?;
            done += n;
        }
        Ok(())
    }

    /// Frees the slots of every instance added, restarted or removed since the last steps.
    fn record_inits(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<(), RuntimeError> {
        if self.to_init.is_empty() {
            return Ok(());
        }
        let gpu = &self.effect.gpu;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("batch init"),
            timestamp_writes: None,
        });
        let (x, y) = gpu.grid(u64::from(self.batched.ir.capacity), u64::from(WORKGROUP))?;
        pass.set_pipeline(&self.kernels.init_last);
        pass.set_bind_group(0, &self.group().chunks()?[0].bind_group, &[0]);
        self.to_init.sort_unstable();
        self.to_init.dedup();
        for &k in &self.to_init {
            // `init_last` inits the last layer of its dispatch: instance k.
            pass.dispatch_workgroups(x, y, k + 1);
        }
        drop(pass);
        self.to_init.clear();
        Ok(())
    }

    /// Records `n` batch steps from step `from` of this frame: each instance's rows (its
    /// plan while its parts still hold steps, placed as its part says, else a held row), one
    /// upload, one compute pass.
    fn record_plan(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[Vec<(u64, Option<Placement>)>],
        from: u64,
        n: u64,
        layers: u32,
    ) -> Result<(), RuntimeError> {
        let row = self.row_bytes as usize;
        let stride = self.step_stride as usize;
        let layout = &self.batched.layout;
        let wraps = self.batched.ir.wraps_kernel_time();
        let mut bytes = vec![0u8; stride * n as usize];
        let mut most_requested = vec![0u32; n as usize];
        for (j, most) in most_requested.iter_mut().enumerate() {
            let step = self.effect.groups[0].schedule.next_plan().step as u32;
            for (k, state) in self.instances.iter_mut().enumerate() {
                let at = j * stride + k * row;
                let out = &mut bytes[at..at + row];
                let Some(state) = state else {
                    continue;
                };
                if let Some(placement) = parts.get(k).and_then(|p| part_at(p, from + j as u64)) {
                    if let Some(placement) = placement {
                        state.placement = placement;
                    }
                    let plan = state.schedule.next_plan();
                    *most = (*most).max(plan.requested());
                    write_params_row(
                        out,
                        &plan,
                        layout,
                        wraps,
                        &state.placement,
                        &state.live_params,
                    );
                    // Active this step.
                    out[row - 16..row - 12].copy_from_slice(&1u32.to_le_bytes());
                } else {
                    state.held += 1;
                }
                // Every row carries the batch's step index: deaths and ages reckon from it.
                out[12..16].copy_from_slice(&step.to_le_bytes());
            }
        }
        let src = staging(&self.effect.gpu, "batch step params", &bytes)?;
        let params = self
            .group()
            .res
            .params
            .as_ref()
            .expect("a batch is stateful");
        encoder.copy_buffer_to_buffer(&src, 0, params, 0, bytes.len() as u64);
        let gpu = &self.effect.gpu;
        let group = &self.effect.groups[0];
        let bind_group = &group.chunks()?[0].bind_group;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("batch steps"),
            timestamp_writes: None,
        });
        let (ux, uy) = gpu.grid(u64::from(self.batched.ir.capacity), u64::from(WORKGROUP))?;
        for (j, requested) in most_requested.iter().enumerate() {
            pass.set_bind_group(0, bind_group, &[(j * stride) as u32]);
            if *requested > 0 {
                pass.set_pipeline(&self.kernels.prepare);
                pass.dispatch_workgroups(1, 1, layers);
                let (x, y) = gpu.grid(u64::from(*requested), u64::from(WORKGROUP))?;
                pass.set_pipeline(&self.kernels.spawn);
                pass.dispatch_workgroups(x, y, layers);
            }
            pass.set_pipeline(&self.kernels.update);
            pass.dispatch_workgroups(ux, uy, layers);
        }
        Ok(())
    }

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

    /// `instance`'s live particles, by id (waits for the GPU), as [`Effect::records`] gives
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

/// The placement of step `t` of an instance's frame in `parts` (Some(None): its own), or None
/// past its steps.
fn part_at(parts: &[(u64, Option<Placement>)], t: u64) -> Option<Option<Placement>> {
    let mut end = 0;
    for (steps, placement) in parts {
        end += steps;
        if t < end {
            return Some(*placement);
        }
    }
    None
}
