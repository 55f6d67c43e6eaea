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
//! the others, its particles' ages unchanged. `steps.rs` records the steps, `read.rs` reads
//! instances back.

mod read;
mod steps;

use plume_compiler::batch::compile_batched;
use plume_compiler::bursts::Burst;
use plume_compiler::passes::layout::{Role, COUNTERS_BYTES};
use plume_compiler::placement::Placement;
use plume_compiler::schedule::{Schedule, StepPlan};
use plume_compiler::wgsl::WORKGROUP;
use plume_compiler::CompiledEffect;

use crate::device::gpu::Gpu;
use crate::device::resources::Resources;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use crate::sim::group::Group;
use crate::sim::steps::Steps;

/// The identity transform, column-major.
const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// An instance's place in an [`EffectBatch`] (from [`EffectBatch::add`]); the place is given
/// to a new instance once this one is removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BatchInstance(pub u32);

/// Many instances of one effect in one set of buffers: one dispatch chain steps them all
/// ([`Self::advance`]) and one draw draws them all (the draw of [`Self::effect`], through
/// [`Effect::renderer`] or [`Effect::compute_renderer`], and [`Effect::prepare_draw`], as for
/// any effect; each instance through its own transform).
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
    /// Each place's transform from its instance's space to the world (column-major), as the
    /// draw reads them, and whether they changed since the last upload.
    models: Vec<[f32; 16]>,
    models_changed: bool,
    /// Instances whose slots are freed before the next step: new, restarted or removed.
    to_init: Vec<u32>,
    kernels: BatchKernels,
    /// Bytes of one instance's row, and of one step's rows (aligned for a dynamic offset).
    row_bytes: u64,
    step_stride: u64,
    /// The plan each instance's next step is written into while its row is recorded.
    plan: StepPlan,
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
            match binding.role {
                Role::Counters => binding.bytes = COUNTERS_BYTES * u64::from(instances),
                Role::Params => binding.bytes = row_bytes * u64::from(instances),
                Role::InstanceModels => binding.bytes = 64 * u64::from(instances),
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
                totals: std::sync::OnceLock::new(),
            },
            batched,
            instances: (0..instances).map(|_| None).collect(),
            models: vec![IDENTITY; instances as usize],
            models_changed: true,
            to_init: Vec::new(),
            kernels,
            row_bytes,
            step_stride,
            plan: StepPlan::default(),
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

    /// Adds an instance: at its start, at the identity placement and transform, with the
    /// file's params. None when the batch is full. Its slots are freed before the next step.
    pub fn add(&mut self) -> Option<BatchInstance> {
        let at = self.instances.iter().position(Option::is_none)?;
        self.instances[at] = Some(self.fresh_state());
        self.models[at] = IDENTITY;
        self.models_changed = true;
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

    /// The transform (column-major) from `instance`'s own space to the world, which its
    /// particles are drawn through once the next [`Self::advance`] (of any steps, 0 too) has
    /// uploaded it: an instance in its own space (an
    /// effect compiled without `placed`) moves its particles with it so, as a host moves an
    /// effect in local space by the view it draws it with. Identity until set. Refused when
    /// not finite.
    pub fn set_transform(
        &mut self,
        instance: BatchInstance,
        cols: [f32; 16],
    ) -> Result<(), RuntimeError> {
        self.state(instance)?;
        if !cols.iter().all(|c| c.is_finite()) {
            return Err(RuntimeError::Control(format!(
                "instance {}: a transform must be finite",
                instance.0
            )));
        }
        if self.models[instance.0 as usize] != cols {
            self.models[instance.0 as usize] = cols;
            self.models_changed = true;
        }
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
        let state = self.state_mut(instance)?;
        state.live_params[index] = value;
        state.schedule.set_param(index, value);
        Ok(())
    }

    /// Keeps `scale` of `instance`'s spawns from its next step on, as
    /// [`Effect::set_spawn_scale`] does for an effect.
    pub fn set_spawn_scale(
        &mut self,
        instance: BatchInstance,
        scale: f32,
    ) -> Result<(), RuntimeError> {
        self.state_mut(instance)?.schedule.set_spawn_scale(scale);
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
}
