//! The simulation passes: what advances an effect by steps. A stateful effect records, per step,
//! the spawn kernels (when something spawns), a field bake (when it bakes every step), the
//! flocking pass and the fused update, with each step's parameters selected by a dynamic
//! uniform offset, so nothing is read back between steps. A stateless effect only advances
//! its bookkeeping (the live spawn segments); its particles are computed when they are read
//! or drawn, from the segment table this module writes.

use std::sync::atomic::{AtomicU64, Ordering};

use plume_compiler::passes::stateless::{FRAME_HEADER_BYTES, SEGMENT_BYTES};
use plume_compiler::placement::Placement;
use plume_compiler::schedule::{LiveSegments, Schedule, Segment, StepPlan};
use plume_compiler::wgsl::WORKGROUP;
use plume_compiler::CompiledEffect;
use plume_compiler::Layout;

use crate::device::gpu::Gpu;
use crate::device::resources::{Chunk, Resources};
use crate::error::RuntimeError;
use crate::sim::flock::FlockPass;

/// The kernels that advance an effect.
pub(crate) enum Steps {
    /// Spawn and update kernels over the particle state.
    Stateful(StatefulSteps),
    /// Bookkeeping, and the `evaluate` kernel that writes the view when it is read back.
    Stateless(StatelessSteps),
}

/// A stateful effect's kernels.
pub(crate) struct StatefulSteps {
    pub(crate) init: wgpu::ComputePipeline,
    pub(crate) prepare: wgpu::ComputePipeline,
    pub(crate) spawn: wgpu::ComputePipeline,
    pub(crate) update: wgpu::ComputePipeline,
    flock: Option<FlockPass>,
    /// The baked field's `bake` kernel, its node count, and whether it runs every step.
    bake: Option<(wgpu::ComputePipeline, u64, bool)>,
    /// Per event the group is fed by: its `event_spawn` kernel (the stream's ordering prepares
    /// it).
    events: Vec<wgpu::ComputePipeline>,
}

/// A stateless group's events: its `fire` kernel (a step's firings from the closed form, over
/// the submission's segment table, for the step its `fire_state` binding holds), and how many
/// threads the current submission's table has, and the one's before it.
pub(crate) struct Firing {
    fire: wgpu::ComputePipeline,
    threads: u64,
    previous_threads: u64,
}

/// A stateless effect's `evaluate` kernel and its bookkeeping: steps only advance the live
/// segments; the view is computed when it is read. A group that fires events also runs its
/// `fire` kernel every step ([`Firing`]).
pub(crate) struct StatelessSteps {
    evaluate: wgpu::ComputePipeline,
    /// The `fire` kernels of a group that fires events.
    pub firing: Option<Firing>,
    /// The live spawn segments of the steps done.
    pub segments: LiveSegments,
    /// Steps done when the view was last evaluated (u64::MAX: never).
    evaluated_at: AtomicU64,
}

fn groups(gpu: &Gpu, threads: u64) -> Result<(u32, u32), RuntimeError> {
    gpu.grid(threads, u64::from(WORKGROUP))
}

impl Steps {
    /// The kernels of `effect`, whose buffers `res` holds.
    pub(crate) fn new(
        gpu: &Gpu,
        res: &Resources,
        effect: &CompiledEffect,
    ) -> Result<Self, RuntimeError> {
        if let Some(plan) = &effect.ir.stateless {
            return Ok(Steps::Stateless(StatelessSteps {
                evaluate: res.pipeline("evaluate"),
                firing: (!effect.ir.events.is_empty()).then(|| Firing {
                    fire: res.pipeline("fire"),
                    threads: 0,
                    previous_threads: 0,
                }),
                segments: LiveSegments::new(plan.lives.clone()),
                evaluated_at: AtomicU64::new(u64::MAX),
            }));
        }
        let flock = match &effect.ir.flock {
            Some(f) => Some(FlockPass::new(gpu, res, effect, f)?),
            None => None,
        };
        Ok(Steps::Stateful(StatefulSteps {
            init: res.pipeline("init"),
            prepare: res.pipeline("spawn_prepare"),
            spawn: res.pipeline("spawn"),
            update: res.pipeline("update"),
            flock,
            bake: effect.ir.field.as_ref().map(|f| {
                (
                    res.pipeline("bake"),
                    f.nodes(),
                    f.refresh == plume_compiler::field::Refresh::EveryStep,
                )
            }),
            events: (0..effect.ir.event_inputs.len())
                .map(|j| res.pipeline(&format!("event_spawn_{j}")))
                .collect(),
        }))
    }
}

impl StatefulSteps {
    /// Records the initial state: every slot free and the free list full (on the GPU: no host
    /// copy of the state), and a field baked once at time 0 (the params buffer starts zeroed).
    pub(crate) fn record_init(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunks: &[Chunk],
    ) -> Result<(), RuntimeError> {
        pass.set_pipeline(&self.init);
        for chunk in chunks {
            let (x, y) = groups(gpu, chunk.len)?;
            pass.set_bind_group(0, &chunk.bind_group, &[0]);
            pass.dispatch_workgroups(x, y, 1);
        }
        if let Some((bake, nodes, false)) = &self.bake {
            let (x, y) = groups(gpu, *nodes)?;
            pass.set_bind_group(0, &chunks[0].bind_group, &[0]);
            pass.set_pipeline(bake);
            pass.dispatch_workgroups(x, y, 1);
        }
        Ok(())
    }

    /// Records the steps' dispatches into `pass`, step j's parameters at offset j · `stride`:
    /// per step, a field bake when it bakes every step, the spawn kernels when something spawns
    /// (a step that requests nothing changes no counter), the flocking pass, then the update
    /// per chunk.
    pub(crate) fn record(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunks: &[Chunk],
        plans: &[StepPlan],
        stride: u64,
    ) -> Result<(), RuntimeError> {
        for (j, plan) in plans.iter().enumerate() {
            self.record_step(gpu, pass, chunks, plan, (j as u64 * stride) as u32)?;
        }
        Ok(())
    }

    /// Records one step (see [`Self::record`]) whose parameters are at `offset`.
    pub(crate) fn record_step(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunks: &[Chunk],
        plan: &StepPlan,
        offset: u32,
    ) -> Result<(), RuntimeError> {
        crate::device::dispatch_marks::boundary(pass);
        // A field baked every step is baked first: the spawn (Verlet's start) samples it too.
        if let Some((bake, nodes, true)) = &self.bake {
            let (x, y) = groups(gpu, *nodes)?;
            pass.set_bind_group(0, &chunks[0].bind_group, &[offset]);
            pass.set_pipeline(bake);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "bake");
        }
        if plan.requested() > 0 {
            pass.set_bind_group(0, &chunks[0].bind_group, &[offset]);
            pass.set_pipeline(&self.prepare);
            pass.dispatch_workgroups(1, 1, 1);
            crate::device::dispatch_marks::mark(pass, "spawn_prepare");
            // Every chunk sees every spawn; each writes only the slots it holds.
            let (x, y) = groups(gpu, u64::from(plan.requested()))?;
            pass.set_pipeline(&self.spawn);
            for chunk in chunks {
                pass.set_bind_group(0, &chunk.bind_group, &[offset]);
                pass.dispatch_workgroups(x, y, 1);
            }
            crate::device::dispatch_marks::mark(pass, "spawn");
        }
        if let Some(flock) = &self.flock {
            flock.record(gpu, pass, &chunks[0], offset)?;
        }
        pass.set_pipeline(&self.update);
        for chunk in chunks {
            let (x, y) = groups(gpu, chunk.len)?;
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
            pass.dispatch_workgroups(x, y, 1);
        }
        crate::device::dispatch_marks::mark(pass, "update");
        Ok(())
    }

    /// Records the spawn of the `input`-th event this group is fed by, from the parent's
    /// firings in id order (as the stream's ordering left them, having popped the children's
    /// slots), with the step's parameters at `offset`: `event_spawn` runs per chunk over
    /// `grid`'s workgroups, whose threads stride over the children.
    pub(crate) fn record_event_spawn(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        chunks: &[Chunk],
        input: usize,
        grid: (u32, u32),
        offset: u32,
    ) {
        pass.set_pipeline(&self.events[input]);
        for chunk in chunks {
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        }
        crate::device::dispatch_marks::mark(pass, "event_spawn");
    }
}

impl StatefulSteps {
    /// The flocking pass, when the effect flocks.
    #[cfg(feature = "tools")]
    pub(crate) fn flock(&self) -> Option<&FlockPass> {
        self.flock.as_ref()
    }
}

/// The steps' parameters as the uniform buffer holds them, step j at j · `stride`: first id,
/// requested, kernel time (wrapped when `wrap_time`, see `EffectIr::wraps_kernel_time`), step
/// index, then for a placed effect the `placement`'s rows (`features::placement`), then
/// (count, counter before, 0, 0) per emitter slot, then for an effect that takes bursts their
/// slots (`features::bursts`), then the `live_params` (`CompileOptions::live_params`).
pub(crate) fn params_bytes(
    plans: &[StepPlan],
    layout: &Layout,
    stride: u64,
    wrap_time: bool,
    placement: &Placement,
    live_params: &[f32],
) -> Vec<u8> {
    let mut bytes = vec![0u8; stride as usize * plans.len()];
    for (plan, row) in plans.iter().zip(bytes.chunks_exact_mut(stride as usize)) {
        write_params_row(row, plan, layout, wrap_time, placement, live_params);
    }
    bytes
}

/// One step's parameters (see [`params_bytes`]) into `row`, whose bytes past them are left as
/// they are. Allocates nothing unless the step fires bursts: a submission writes a row per
/// instance per step.
pub(crate) fn write_params_row(
    row: &mut [u8],
    plan: &StepPlan,
    layout: &Layout,
    wrap_time: bool,
    placement: &Placement,
    live_params: &[f32],
) {
    let mut at = 0;
    let mut put = |w: u32| {
        row[at..at + 4].copy_from_slice(&w.to_le_bytes());
        at += 4;
    };
    for w in [
        plan.first_id,
        plan.requested(),
        plan.kernel_time(wrap_time).to_bits(),
        plan.step as u32,
    ] {
        put(w);
    }
    if layout.placed {
        placement.words().into_iter().for_each(&mut put);
    }
    for e in 0..layout.emitter_slots as usize {
        let (count, k0) = plan.emitters.get(e).copied().unwrap_or((0, 0));
        [count, k0, 0, 0].into_iter().for_each(&mut put);
    }
    if layout.bursts {
        match plan.bursts.is_empty() {
            // No bursts: every slot zero.
            true => (0..plume_compiler::bursts::SLOTS * 12).for_each(|_| put(0)),
            false => plume_compiler::bursts::words(&plan.bursts)
                .into_iter()
                .for_each(&mut put),
        }
    }
    let user = layout.user_vec4s() as usize * 4;
    for k in 0..user {
        put(live_params.get(k).map_or(0, |p| p.to_bits()));
    }
}

impl StatelessSteps {
    /// Advances the bookkeeping by `steps`, calling `progress(done)` every 2^16 steps.
    pub(crate) fn advance(
        &mut self,
        schedule: &mut Schedule,
        steps: u64,
        mut progress: impl FnMut(u64),
    ) {
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(1 << 16);
            self.segments.advance(schedule, n);
            done += n;
            progress(done);
        }
    }

    /// The segment table of the steps done, as the `frame` binding holds it, and the number of
    /// slots it covers (the threads, which is also how many instances a draw needs).
    pub(crate) fn frame_bytes(
        &self,
        effect: &CompiledEffect,
        table_bytes: u64,
    ) -> Result<(Vec<u8>, u32), RuntimeError> {
        let done = self.segments.steps_done();
        let count = self.segments.len() as u64;
        if FRAME_HEADER_BYTES + count * SEGMENT_BYTES > table_bytes {
            return Err(RuntimeError::Gpu(format!(
                "{count} live spawn segments overflow the stateless table (a bug in the compiler's bound)"
            )));
        }
        let mut words: Vec<u32> = vec![0, count as u32, done as u32, 0];
        let mut threads = 0u64;
        let dt = effect.ir.dt;
        for seg in self.segments.iter() {
            let age = done - seg.step;
            // The age in f64 steps, rounded to f32 seconds once: no drift at any t.
            let tau = (age as f64 * dt) as f32;
            words.extend([
                threads as u32,
                seg.first_id,
                seg.k_base,
                seg.emitter as u32,
                age.min(u64::from(u32::MAX)) as u32,
                seg.step as u32,
                tau.to_bits(),
                0,
            ]);
            threads += u64::from(seg.count);
        }
        if threads > u64::from(effect.ir.capacity) {
            return Err(RuntimeError::Gpu(format!(
                "{threads} stateless particles exceed the capacity {} (a bug in the compiler's bound)",
                effect.ir.capacity
            )));
        }
        words[0] = threads as u32;
        Ok((
            words.iter().flat_map(|w| w.to_le_bytes()).collect(),
            threads as u32,
        ))
    }

    /// The `fire_frame` table of `segments` (every segment live at some step of a submission), with
    /// each one's first thread, and the threads in all. Only the spawn steps and ids matter to
    /// `fire`, which computes each particle's age at its step.
    pub(crate) fn fire_table(
        effect: &CompiledEffect,
        segments: &[Segment],
    ) -> Result<(Vec<u8>, u64), RuntimeError> {
        let mut words: Vec<u32> = vec![0, segments.len() as u32, 0, 0];
        let mut threads = 0u64;
        for seg in segments {
            words.extend([
                threads as u32,
                seg.first_id,
                seg.k_base,
                seg.emitter as u32,
                0,
                seg.step as u32,
                0,
                0,
            ]);
            threads += u64::from(seg.count);
        }
        words[0] = threads as u32;
        let room = effect
            .ir
            .stateless
            .as_ref()
            .map_or(0, |p| p.fire_table_bytes());
        if words.len() as u64 * 4 > room {
            return Err(RuntimeError::Gpu(format!(
                "{} spawn segments overflow the firing table of {room} bytes (a bug in the compiler's bound)",
                segments.len()
            )));
        }
        Ok((
            words.iter().flat_map(|w| w.to_le_bytes()).collect(),
            threads,
        ))
    }

    /// Sets the current submission's table size ([`Self::fire_table`]'s threads).
    pub(crate) fn set_fire_threads(&mut self, threads: u64) {
        if let Some(f) = &mut self.firing {
            f.previous_threads = f.threads;
            f.threads = threads;
        }
    }

    /// The most firings of one event that step `j` of the current submission orders: those of the
    /// step before, which fired over the current submission's table or, for its first step, over
    /// the submission's before it (each particle of the table fires an event at most once a step).
    pub(crate) fn firings_bound(&self, j: usize) -> Option<u64> {
        self.firing.as_ref().map(|f| {
            if j == 0 {
                f.previous_threads
            } else {
                f.threads
            }
        })
    }

    /// Records the firings of step `j` of the submission (its step, in `fire_state` at the offset
    /// `Group::plan_graph_submission` wrote it, bound at that dynamic offset).
    pub(crate) fn record_fire(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunk: &Chunk,
        j: usize,
    ) -> Result<(), RuntimeError> {
        let Some(f) = &self.firing else {
            return Ok(());
        };
        if f.threads > 0 {
            let offset = j as u64 * crate::device::resources::fire_state_stride(gpu);
            let (x, y) = groups(gpu, f.threads)?;
            pass.set_bind_group(0, &chunk.bind_group, &[offset as u32]);
            pass.set_pipeline(&f.fire);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "fire");
        }
        Ok(())
    }

    /// Records one evaluation of the whole view into `pass`.
    pub(crate) fn record_evaluate(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunks: &[Chunk],
    ) -> Result<(), RuntimeError> {
        pass.set_pipeline(&self.evaluate);
        // A firing group's layout has the step's dynamic offset, which `evaluate` ignores.
        let offsets: &[u32] = if self.firing.is_some() { &[0] } else { &[] };
        for chunk in chunks {
            let (x, y) = groups(gpu, chunk.len)?;
            pass.set_bind_group(0, &chunk.bind_group, offsets);
            pass.dispatch_workgroups(x, y, 1);
        }
        Ok(())
    }

    /// Whether the view already holds the steps done.
    pub(crate) fn view_is_current(&self) -> bool {
        self.evaluated_at.load(Ordering::Relaxed) == self.segments.steps_done()
    }

    /// Records that the view now holds the steps done.
    pub(crate) fn mark_view_current(&self) {
        self.evaluated_at
            .store(self.segments.steps_done(), Ordering::Relaxed);
    }
}
