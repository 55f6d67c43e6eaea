//! One group of an effect: a compiled particle system running on a device, Plume's own or a
//! host application's. It owns the group's resources and ties its stages together:
//! [`crate::sim::steps`] advances it, [`crate::sort::depth`] orders it, and
//! [`crate::device::readback`] reads it back. An effect of one system is one group; an effect
//! graph is several, stepped together by [`crate::sim::graph`]. Steps are recorded into the
//! caller's command encoder; per-call parameters travel as copies inside that encoder, so
//! several steps, prepares and draws can share one submission. The draw of a group, and its
//! frame's preparation, are [`crate::draw`]'s; its timings, [`crate::bench`]'s.

use plume_compiler::passes::layout::Role;
use plume_compiler::placement::Placement;
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::schedule::{Schedule, StepPlan};
use plume_compiler::CompiledEffect;

use crate::device::buffers::staging;
use crate::device::gpu::Gpu;
use crate::device::readback::{decode_slots, decode_totals, read_buffer};
use crate::device::resources::{binding_bytes, Chunk, Resources, STEPS_PER_SUBMIT};
use crate::error::RuntimeError;
use crate::sim::steps::{params_bytes, StatelessSteps, Steps};
use crate::sort::depth::DepthSort;

/// A compiled particle system running on a GPU: its buffers, its kernels, its depth sort and
/// its spawn schedule.
pub(crate) struct Group {
    pub(crate) gpu: Gpu,
    pub(crate) effect: CompiledEffect,
    pub(crate) schedule: Schedule,
    pub(crate) res: Resources,
    pub(crate) steps: Steps,
    pub(crate) depth: Option<DepthSort>,
    /// Where a placed effect's emitters spawn (`features::placement`; identity until set).
    pub(crate) placement: Placement,
    /// The live params' values now, in name order (`CompileOptions::live_params`; empty
    /// otherwise).
    pub(crate) live_params: Vec<f32>,
}

impl Group {
    /// Allocates `effect`'s buffers and builds its kernels on `gpu`, with at most
    /// `max_chunk_slots` particles per buffer (tests use it to exercise the split on small
    /// effects), binding the `shared` buffers (by binding index) instead of allocating them:
    /// how an effect graph's groups share their event buffers. Runs the initial state's
    /// kernel (every slot free) in its own submission.
    pub(crate) fn new(
        gpu: &Gpu,
        effect: CompiledEffect,
        max_chunk_slots: Option<u64>,
        shared: &[(u32, wgpu::Buffer)],
    ) -> Result<Self, RuntimeError> {
        let res = Resources::new(gpu, &effect, max_chunk_slots, shared)?;
        let steps = Steps::new(gpu, &res, &effect)?;
        let depth = match effect.layout.sorts() {
            true => Some(DepthSort::new(gpu, &res, &effect)?),
            false => None,
        };
        let live_params = effect.ir.live_params.iter().map(|p| p.1 as f32).collect();
        let instance = Self {
            gpu: gpu.clone(),
            schedule: Schedule::new(&effect.ir),
            effect,
            res,
            steps,
            depth,
            placement: Placement::IDENTITY,
            live_params,
        };
        if let Steps::Stateful(stateful) = &instance.steps {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                stateful.record_init(gpu, &mut pass, instance.chunks()?)?;
            }
            gpu.queue.submit([encoder.finish()]);
        }
        gpu.take_error()?;
        Ok(instance)
    }

    /// The particle buffers (a stateless group's view is allocated on first use).
    pub(crate) fn chunks(&self) -> Result<&[Chunk], RuntimeError> {
        self.res.chunks(&self.effect)
    }

    /// Records `steps` steps into the caller's `encoder` (a compute pass per
    /// [`STEPS_PER_SUBMIT`] steps, each preceded by the copy of its steps' parameters), with
    /// GPU timestamps when given: `query_set` gets one at index `first` when the steps' first
    /// compute pass begins and one at `first + 1` when the last one ends. The schedule
    /// advances now: submit the encoder before reading the group back. Returns whether any
    /// pass was recorded (a stateless group only advances its bookkeeping and records none).
    pub(crate) fn advance_timed(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) -> Result<bool, RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, steps, |_| {});
            return Ok(false);
        }
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let plans: Vec<StepPlan> = (0..n).map(|_| self.schedule.next_plan()).collect();
            let writes = timestamps.map(|(set, first)| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: (done == 0).then_some(first),
                end_of_pass_write_index: (done + n == steps).then_some(first + 1),
            });
            self.record_plans(encoder, &plans, writes)?;
            done += n;
        }
        Ok(steps > 0)
    }

    /// Plans `steps` steps (at most [`STEPS_PER_SUBMIT`]) and records their parameters' copy
    /// into `encoder`, for [`Self::record_planned`] in a compute pass of the caller's; a
    /// stateless group only advances its bookkeeping and plans nothing.
    pub(crate) fn plan_steps(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<Vec<StepPlan>, RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, steps, |_| {});
            return Ok(Vec::new());
        }
        let plans: Vec<StepPlan> = (0..steps).map(|_| self.schedule.next_plan()).collect();
        self.copy_params(encoder, &plans)?;
        Ok(plans)
    }

    /// Records `plans` (from [`Self::plan_steps`]) into the caller's compute pass.
    pub(crate) fn record_planned(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        plans: &[StepPlan],
    ) -> Result<(), RuntimeError> {
        match &self.steps {
            Steps::Stateful(stateful) if !plans.is_empty() => stateful.record(
                &self.gpu,
                pass,
                self.chunks()?,
                plans,
                self.res.params_stride,
            ),
            _ => Ok(()),
        }
    }

    /// Records the parameters' copy and one compute pass of `plans` (at most 256 steps).
    fn record_plans(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        plans: &[StepPlan],
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<(), RuntimeError> {
        let Steps::Stateful(_) = &self.steps else {
            return Ok(());
        };
        self.copy_params(encoder, plans)?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("steps"),
            timestamp_writes,
        });
        self.record_planned(&mut pass, plans)
    }

    /// Records the copy of `plans`' parameters (at most 256 steps) into the params buffer.
    fn copy_params(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        plans: &[StepPlan],
    ) -> Result<(), RuntimeError> {
        let Some(params) = self.res.params.as_ref() else {
            return Ok(());
        };
        let bytes = params_bytes(
            plans,
            &self.effect.layout,
            self.res.params_stride,
            self.effect.ir.wraps_kernel_time(),
            &self.placement,
            &self.live_params,
        );
        let src = staging(&self.gpu, "step params", &bytes)?;
        encoder.copy_buffer_to_buffer(&src, 0, params, 0, bytes.len() as u64);
        Ok(())
    }

    /// An effect graph's steps of one submission (at most [`STEPS_PER_SUBMIT`] steps): plans the next `n`
    /// steps and records their parameters' copy into `encoder`. A stateless group only
    /// advances its bookkeeping and returns no plans.
    pub(crate) fn plan_graph_submission(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        n: u64,
    ) -> Result<Vec<StepPlan>, RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            let first_step = stateless.segments.steps_done();
            if stateless.firing.is_none() {
                stateless.advance(&mut self.schedule, n, |_| {});
            } else {
                // The submission's table and its first step, for `fire` (see wgsl/stateless.rs).
                if n > plume_compiler::passes::stateless::FIRE_BATCH_STEPS {
                    return Err(RuntimeError::Gpu(format!(
                        "a submission of {n} steps is longer than a firing stateless group's table covers"
                    )));
                }
                // Every segment live at some step of the submission: those live at its start, and
                // every one its steps spawn (one spawned and gone within it included).
                let mut seen: Vec<plume_compiler::schedule::Segment> =
                    stateless.segments.iter().copied().collect();
                stateless
                    .segments
                    .advance_noting(&mut self.schedule, n, &mut seen);
                let (table, threads) = StatelessSteps::fire_table(&self.effect, &seen)?;
                stateless.set_fire_threads(threads);
                // Each step of the submission at its own offset, which its `fire` binds.
                let stride = crate::device::resources::fire_state_stride(&self.gpu) as usize;
                let mut state = vec![0u8; n as usize * stride];
                for (j, word) in state.chunks_exact_mut(stride).enumerate() {
                    word[..4].copy_from_slice(&((first_step + j as u64) as u32).to_le_bytes());
                }
                for (role, bytes) in [
                    (Role::FireFrame, table.as_slice()),
                    (Role::FireState, &state),
                ] {
                    let name = role.name();
                    let dst = self.res.extra_of(&self.effect, role).ok_or_else(|| {
                        RuntimeError::Gpu(format!("a firing stateless group has no {name}"))
                    })?;
                    let src = staging(&self.gpu, name, bytes)?;
                    encoder.copy_buffer_to_buffer(&src, 0, dst, 0, bytes.len() as u64);
                }
                // Its kernels bind the view's buffers: allocate them now.
                self.chunks()?;
            }
            return Ok(Vec::new());
        }
        self.plan_steps(encoder, n)
    }

    /// Records step `j` of a submission planned by [`Self::plan_graph_submission`] (for a stateless
    /// group, its firings if it fires events, else nothing).
    pub(crate) fn record_graph_step(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        plans: &[StepPlan],
        j: usize,
    ) -> Result<(), RuntimeError> {
        if let Steps::Stateless(stateless) = &self.steps {
            // A group that does not fire has no step work (and its view may not exist yet).
            return match stateless.firing {
                Some(_) => stateless.record_fire(&self.gpu, pass, &self.chunks()?[0], j),
                None => Ok(()),
            };
        }
        let (Steps::Stateful(stateful), Some(plan)) = (&self.steps, plans.get(j)) else {
            return Ok(());
        };
        let offset = (j as u64 * self.res.params_stride) as u32;
        stateful.record_step(&self.gpu, pass, self.chunks()?, plan, offset)
    }

    /// The counters of a group fed by events, where the streams' orderings prepare its
    /// spawns.
    pub(crate) fn event_counters(&self) -> Result<&wgpu::Buffer, RuntimeError> {
        self.res.counters.as_ref().ok_or_else(|| {
            RuntimeError::Gpu("a group fed by events has no counters buffer (a bug)".into())
        })
    }

    /// Records the spawn of the `input`-th event this group is fed by at step `j` of the submission.
    pub(crate) fn record_event_spawn(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        input: usize,
        j: usize,
    ) -> Result<(), RuntimeError> {
        let Steps::Stateful(stateful) = &self.steps else {
            return Err(RuntimeError::Gpu(
                "a group fed by events is stateful (a bug in the compiler)".into(),
            ));
        };
        // A fixed grid over the group's slots, at most SPAWN_WORKGROUPS workgroups, whose
        // threads stride over the children (plume_compiler::events::emit_kernels).
        let slots = u64::from(self.effect.ir.capacity).min(
            u64::from(plume_compiler::events::SPAWN_WORKGROUPS)
                * u64::from(plume_compiler::wgsl::WORKGROUP),
        );
        let grid = self
            .gpu
            .grid(slots, u64::from(plume_compiler::wgsl::WORKGROUP))?;
        let offset = (j as u64 * self.res.params_stride) as u32;
        stateful.record_event_spawn(pass, self.chunks()?, input, grid, offset);
        Ok(())
    }

    /// Runs `steps` steps in submissions of [`STEPS_PER_SUBMIT`], calling `progress(done)`
    /// after each is submitted. Returns when the GPU has finished.
    pub(crate) fn run(
        &mut self,
        steps: u64,
        mut progress: impl FnMut(u64),
    ) -> Result<(), RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, steps, progress);
            return Ok(());
        }
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            self.advance_timed(&mut encoder, n, None)?;
            self.gpu.queue.submit([encoder.finish()]);
            self.gpu.take_error()?;
            done += n;
            progress(done);
        }
        self.gpu.wait()
    }

    /// The particle buffers the depth keys read (none for a stateless effect: it evaluates in
    /// place, so sorting allocates no view).
    pub(crate) fn sort_chunks(&self) -> Result<&[Chunk], RuntimeError> {
        match self.steps {
            Steps::Stateless(_) => Ok(&[]),
            Steps::Stateful(_) => self.chunks(),
        }
    }

    /// Copies a stateless effect's segment table for the steps done into the frame buffer;
    /// returns its threads.
    pub(crate) fn copy_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        stateless: &StatelessSteps,
    ) -> Result<u32, RuntimeError> {
        let frame = self
            .res
            .frame
            .as_ref()
            .expect("a stateless effect has a frame");
        let (bytes, threads) = stateless.frame_bytes(&self.effect, frame.size())?;
        let src = staging(&self.gpu, "frame", &bytes)?;
        encoder.copy_buffer_to_buffer(&src, 0, frame, 0, bytes.len() as u64);
        Ok(threads)
    }

    /// Writes a stateless effect's segment table now, with the queue (for timed passes, which
    /// record into an encoder of their own; a frame's draw copies it in its encoder instead).
    #[cfg(feature = "tools")]
    pub(crate) fn write_frame_now(&self, stateless: &StatelessSteps) -> Result<(), RuntimeError> {
        let frame = self
            .res
            .frame
            .as_ref()
            .expect("a stateless effect has a frame");
        let (bytes, _) = stateless.frame_bytes(&self.effect, frame.size())?;
        self.gpu.queue.write_buffer(frame, 0, &bytes);
        Ok(())
    }

    /// The sort stage, or the error of asking a `sort: false` effect for an order.
    pub(crate) fn depth(&self) -> Result<&DepthSort, RuntimeError> {
        self.depth.as_ref().ok_or_else(|| {
            RuntimeError::Output("this effect has no sort stage (sort: false)".into())
        })
    }

    /// A stateless effect: computes the view at the steps done, unless it already holds them.
    /// A stateful effect: nothing to do.
    pub(crate) fn evaluate_view(&self) -> Result<(), RuntimeError> {
        let Steps::Stateless(stateless) = &self.steps else {
            return Ok(());
        };
        if stateless.view_is_current() && self.res.has_chunks() {
            return Ok(());
        }
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.copy_frame(&mut encoder, stateless)?;
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            stateless.record_evaluate(&self.gpu, &mut pass, self.chunks()?)?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        stateless.mark_view_current();
        Ok(())
    }

    /// Steps done and the GPU's counters: alive, spawned, died, dropped. A stateless effect
    /// drops nothing and counts from its bookkeeping (the kernels' own lifetime draw).
    pub(crate) fn totals(&self) -> Result<Totals, RuntimeError> {
        if let Steps::Stateless(stateless) = &self.steps {
            let spawned = u64::from(self.schedule.ids_requested());
            let alive = stateless.segments.alive(&self.effect.ir);
            return Ok(Totals {
                steps: self.schedule.steps_done(),
                alive,
                spawned,
                died: spawned - alive,
                dropped: 0,
            });
        }
        let counters = self
            .res
            .counters
            .as_ref()
            .expect("a stateful effect has counters");
        let bytes = read_buffer(&self.gpu, counters)?;
        Ok(self.decode_counters(&bytes, self.schedule.steps_done()))
    }

    /// The totals in a copy of a stateful group's counters made when `steps` steps were done.
    pub(crate) fn decode_counters(&self, bytes: &[u8], steps: u64) -> Totals {
        if !self.effect.layout.batched {
            return decode_totals(bytes, self.effect.ir.capacity, steps);
        }
        // A batch (`sim::batch`): every instance's counters, added up.
        let size = plume_compiler::passes::layout::COUNTERS_BYTES as usize;
        let instances = (binding_bytes(&self.effect, Role::Counters) as usize / size).max(1);
        let capacity = self.effect.ir.capacity / instances as u32;
        let mut sum = Totals {
            steps,
            alive: 0,
            spawned: 0,
            died: 0,
            dropped: 0,
        };
        for one in bytes.chunks_exact(size).take(instances) {
            let t = decode_totals(one, capacity, steps);
            sum.alive += t.alive;
            sum.spawned += t.spawned;
            sum.died += t.died;
            sum.dropped += t.dropped;
        }
        sum
    }

    /// The live particles in id order, velocity as the integrator knows it (Verlet's derived).
    pub(crate) fn records(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let mut out: Vec<ParticleRecord> = self.records_by_slot()?.into_iter().flatten().collect();
        out.sort_by_key(|r| r.id);
        Ok(out)
    }

    /// Every slot's particle, in slot order (None for a free slot): the order an unsorted draw
    /// follows.
    pub(crate) fn records_by_slot(&self) -> Result<Vec<Option<ParticleRecord>>, RuntimeError> {
        self.evaluate_view()?;
        let mut bytes = Vec::new();
        for chunk in self.chunks()? {
            bytes.push(read_buffer(&self.gpu, &chunk.buffer)?);
        }
        decode_slots(&self.effect, &self.schedule, &bytes)
    }

    /// Reads a buffer of the layout beside the particles back by its role (`Role::Boids`,
    /// `Role::RibbonTable`, ...), for tests and benchmarks.
    #[cfg(feature = "tools")]
    pub(crate) fn read_extra_buffer(&self, role: Role) -> Result<Vec<u8>, RuntimeError> {
        let buffer = self.res.extra_of(&self.effect, role).ok_or_else(|| {
            RuntimeError::Output(format!("this effect has no buffer {}", role.name()))
        })?;
        read_buffer(&self.gpu, buffer)
    }

    /// Whether its steps record GPU work: a stateful effect's, or a stateless group's that fires
    /// events.
    pub(crate) fn steps_on_gpu(&self) -> bool {
        match &self.steps {
            Steps::Stateful(_) => true,
            Steps::Stateless(s) => s.firing.is_some(),
        }
    }

    /// For a stateless group that fires events, the most firings of one event that step `j` of
    /// the planned submission orders ([`StatelessSteps::firings_bound`]); None for a stateful group,
    /// whose firings the host cannot bound below its capacity.
    pub(crate) fn firings_bound(&self, j: usize) -> Option<u64> {
        match &self.steps {
            Steps::Stateless(s) => s.firings_bound(j),
            Steps::Stateful(_) => None,
        }
    }

    /// Whether the effect runs stateless (no state kept; computed when read or drawn).
    pub(crate) fn is_stateless(&self) -> bool {
        matches!(self.steps, Steps::Stateless(_))
    }

    /// Number of particle buffers the state is split into.
    #[cfg(feature = "tools")]
    pub(crate) fn chunk_count(&self) -> usize {
        self.res.chunk_count()
    }

    /// Bytes of particle buffers allocated now: the state (stateful), or the view a readback
    /// made (stateless; 0 for an effect that has only been drawn).
    #[cfg(feature = "tools")]
    pub(crate) fn particle_buffer_bytes(&self) -> u64 {
        if !self.res.has_chunks() {
            return 0;
        }
        self.chunks()
            .map(|c| c.iter().map(|c| c.buffer.size()).sum())
            .unwrap_or(0)
    }

    /// Steps done so far.
    pub(crate) fn steps_done(&self) -> u64 {
        self.schedule.steps_done()
    }

    /// A stateful effect's counters (six u32: free count, spawn base, spawn count, spawned,
    /// dropped, died), for a host that reads totals without waiting: copy them in its
    /// encoder, map the copy, and decode it with [`crate::device::readback::decode_totals`]. None for
    /// a stateless effect, whose [`Self::totals`] needs no GPU.
    pub(crate) fn counters(&self) -> Option<&wgpu::Buffer> {
        self.res.counters.as_ref()
    }
}
