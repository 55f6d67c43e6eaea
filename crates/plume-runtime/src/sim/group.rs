//! An effect instance: a compiled effect running on a device, Plume's own or a host
//! application's. It owns the effect's resources and ties the pipeline's stages together:
//! [`crate::sim::steps`] advances it, [`crate::sort::depth`] orders it, [`crate::draw::raster`] draws it into a
//! render pass, and [`crate::device::readback`] reads it back. Steps and draws are recorded into the
//! caller's command encoder and render pass; per-call parameters travel as copies inside that
//! encoder, so several steps, prepares and draws can share one submission.

use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::schedule::{Schedule, StepPlan};
use plume_compiler::CompiledEffect;

use crate::draw::camera::Camera;
use crate::sort::depth::{sort_buffers, DepthSort};
use crate::draw::raster::{DrawOptions, EffectRenderer};
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::device::gpu::Gpu;
use crate::device::readback::{decode_slots, decode_totals, read_buffer, read_words};
use crate::device::resources::{staging, Chunk, Resources, STEPS_PER_SUBMIT};
use crate::sort::radix::SortAlgorithm;
use crate::sim::steps::{params_bytes, StatelessSteps, Steps};
use crate::bench::timer::{median_after_warmup, PassTimer};

/// What a frame's preparation recorded: the steps done, and for a stateless effect the slots
/// its segment table covers.
pub(crate) struct PreparedFrame {
    /// Steps done.
    pub steps: u64,
    /// A stateless effect's frame threads (0 for a stateful one).
    pub threads: u32,
}

/// A compiled effect running on a GPU: its buffers, its kernels and its spawn schedule.
///
/// ```no_run
/// # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, view: &wgpu::TextureView,
/// #          camera: plume_runtime::Camera) -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::{DrawTarget, EffectInstance, Gpu};
/// let source = std::fs::read_to_string("effects/fountain.ron")?;
/// let effect = plume_compiler::compile_str(&source, &Default::default())?;
/// // On the host's own device and queue:
/// let mut fountain = EffectInstance::new(&Gpu::from_device(device, queue), effect)?;
/// let renderer = fountain.renderer(&DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm))?;
/// // Each frame: steps and the draw's preparation go into the host's encoder ...
/// let mut encoder = device.create_command_encoder(&Default::default());
/// fountain.advance(&mut encoder, 1)?;
/// fountain.prepare_draw(&mut encoder, &renderer, &camera)?;
/// {
///     // ... and the draw into the host's render pass, beside its own geometry.
///     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
///         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
///             view,
///             depth_slice: None,
///             resolve_target: None,
///             ops: wgpu::Operations::default(),
///         })],
///         ..Default::default()
///     });
///     renderer.draw(&mut pass);
/// }
/// queue.submit([encoder.finish()]);
/// # Ok(()) }
/// ```
pub struct EffectInstance {
    gpu: Gpu,
    effect: CompiledEffect,
    schedule: Schedule,
    res: Resources,
    steps: Steps,
    depth: Option<DepthSort>,
}

impl EffectInstance {
    /// Allocates `effect`'s buffers and builds its kernels on `gpu` (Plume's own device, or a
    /// host's through [`Gpu::from_device`]). Runs the initial state's kernel (every slot free)
    /// in its own submission.
    pub fn new(gpu: &Gpu, effect: CompiledEffect) -> Result<Self, RuntimeError> {
        Self::with_chunk_slots(gpu, effect, None)
    }

    /// Like [`EffectInstance::new`] with at most `max_chunk_slots` particles per buffer (tests
    /// use it to exercise the split on small effects).
    pub fn with_chunk_slots(
        gpu: &Gpu,
        effect: CompiledEffect,
        max_chunk_slots: Option<u64>,
    ) -> Result<Self, RuntimeError> {
        Self::with_shared(gpu, effect, max_chunk_slots, &[])
    }

    /// Like [`Self::with_chunk_slots`], binding the given buffers (by binding index) instead
    /// of allocating them: how an effect graph's groups share their event buffers.
    pub(crate) fn with_shared(
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
        let instance = Self {
            gpu: gpu.clone(),
            schedule: Schedule::new(&effect.ir),
            effect,
            res,
            steps,
            depth,
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

    fn chunks(&self) -> Result<&[Chunk], RuntimeError> {
        self.res.chunks(&self.effect)
    }

    /// Records `steps` steps into the caller's `encoder` (a compute pass per
    /// [`STEPS_PER_SUBMIT`] steps, each preceded by the copy of its steps' parameters). The
    /// schedule advances now: submit the encoder before reading the instance back. A stateless
    /// effect only advances its bookkeeping and records nothing.
    pub fn advance(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<(), RuntimeError> {
        self.advance_timed(encoder, steps, None).map(|_| ())
    }

    /// Like [`Self::advance`], with GPU timestamps: `query_set` gets one at index `first` when
    /// the steps' first compute pass begins and one at `first + 1` when the last one ends.
    /// Returns whether any pass was recorded (a stateless effect, or 0 steps, records none).
    pub fn advance_timed(
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

    /// Records the parameters' copy and one compute pass of `plans` (at most 256 steps).
    fn record_plans(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        plans: &[StepPlan],
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<(), RuntimeError> {
        let Steps::Stateful(stateful) = &self.steps else {
            return Ok(());
        };
        self.copy_params(encoder, plans)?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("steps"),
            timestamp_writes,
        });
        stateful.record(
            &self.gpu,
            &mut pass,
            self.chunks()?,
            plans,
            self.res.params_stride,
        )
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
            self.effect.layout.emitter_slots,
            self.res.params_stride,
            self.effect.ir.wraps_kernel_time(),
        );
        let src = staging(&self.gpu, "step params", &bytes)?;
        encoder.copy_buffer_to_buffer(&src, 0, params, 0, bytes.len() as u64);
        Ok(())
    }

    /// An effect graph's step batch (at most [`STEPS_PER_SUBMIT`] steps): plans the next `n`
    /// steps and records their parameters' copy into `encoder`. A stateless group only
    /// advances its bookkeeping and returns no plans.
    pub(crate) fn plan_graph_batch(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        n: u64,
    ) -> Result<Vec<StepPlan>, RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            let first_step = stateless.segments.steps_done();
            if stateless.firing.is_none() {
                stateless.advance(&mut self.schedule, n, |_| {});
            } else {
                // The batch's table and its first step, for `fire` (see wgsl/stateless.rs).
                if n > plume_compiler::passes::stateless::FIRE_BATCH_STEPS {
                    return Err(RuntimeError::Gpu(format!(
                        "a batch of {n} steps is longer than a firing stateless group's table covers"
                    )));
                }
                // Every segment live at some step of the batch: those live at its start, and
                // every one its steps spawn (one spawned and gone within it included).
                let mut seen: Vec<plume_compiler::schedule::Segment> =
                    stateless.segments.iter().copied().collect();
                stateless
                    .segments
                    .advance_noting(&mut self.schedule, n, &mut seen);
                let (table, threads) = StatelessSteps::fire_table(&self.effect, &seen)?;
                stateless.set_fire_threads(threads);
                let mut state = [0u8; 16];
                state[..4].copy_from_slice(&(first_step as u32).to_le_bytes());
                for (name, bytes) in [("fire_frame", table.as_slice()), ("fire_state", &state)] {
                    let dst = self.res.extra_named(&self.effect, name).ok_or_else(|| {
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
        let plans: Vec<StepPlan> = (0..n).map(|_| self.schedule.next_plan()).collect();
        self.copy_params(encoder, &plans)?;
        Ok(plans)
    }

    /// Records step `j` of a batch planned by [`Self::plan_graph_batch`] (for a stateless
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
                Some(_) => stateless.record_fire(&self.gpu, pass, &self.chunks()?[0]),
                None => Ok(()),
            };
        }
        let (Steps::Stateful(stateful), Some(plan)) = (&self.steps, plans.get(j)) else {
            return Ok(());
        };
        let offset = (j as u64 * self.res.params_stride) as u32;
        stateful.record_step(&self.gpu, pass, self.chunks()?, plan, offset)
    }

    /// Records the spawn of the `input`-th event this group is fed by at step `j` of the batch.
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
        let dispatch = self
            .res
            .extra_named(&self.effect, "event_dispatch")
            .ok_or_else(|| {
                RuntimeError::Gpu("a group fed by events has no dispatch buffer".into())
            })?;
        let offset = (j as u64 * self.res.params_stride) as u32;
        stateful.record_event_spawn(pass, self.chunks()?, input, dispatch, offset);
        Ok(())
    }

    /// Runs `steps` steps in submissions of [`STEPS_PER_SUBMIT`], calling `progress(done)`
    /// after each is submitted. Returns when the GPU has finished.
    pub fn run(&mut self, steps: u64, mut progress: impl FnMut(u64)) -> Result<(), RuntimeError> {
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, steps, progress);
            return Ok(());
        }
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            self.advance(&mut encoder, n)?;
            self.gpu.queue.submit([encoder.finish()]);
            self.gpu.take_error()?;
            done += n;
            progress(done);
        }
        self.gpu.wait()
    }

    /// A draw of this effect into render targets like `target`: the effect's draw module on a
    /// render pipeline for that target. Create one per kind of target; reuse it every frame.
    pub fn renderer(&self, target: &DrawTarget) -> Result<EffectRenderer, RuntimeError> {
        self.renderer_with(target, &DrawOptions::default())
    }

    /// Like [`Self::renderer`] with other choices ([`DrawOptions`]).
    pub fn renderer_with(
        &self,
        target: &DrawTarget,
        options: &DrawOptions,
    ) -> Result<EffectRenderer, RuntimeError> {
        EffectRenderer::new(&self.gpu, &self.effect, &self.res, target, options)
    }

    /// Records what a draw from `camera` needs this frame into the caller's `encoder`, outside
    /// any render pass: the camera and the steps done; for a stateless effect its segment
    /// table; for `sort: true` the depth keys and their sort along the camera's axis, and the
    /// live count of the indirect draw. Then call [`EffectRenderer::draw`] in a render pass.
    /// An unsorted stateless effect records no compute pass at all.
    pub fn prepare_draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        renderer: &EffectRenderer,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        let frame = self.prepare_frame(encoder, camera)?;
        renderer.write_view(encoder, camera, frame.steps)?;
        renderer.set_frame_instances(frame.threads);
        if renderer.counts_on_gpu() {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("draw count"),
                timestamp_writes: None,
            });
            renderer.record_instance_count(&mut pass)?;
        }
        Ok(())
    }

    /// Records what any view of this frame needs, whatever draws it: a stateless effect's
    /// segment table, and for `sort: true` the depth keys and their sort along `camera`'s axis.
    pub(crate) fn prepare_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> Result<PreparedFrame, RuntimeError> {
        let mut frame = PreparedFrame {
            steps: self.schedule.steps_done(),
            threads: 0,
        };
        if let Steps::Stateless(stateless) = &self.steps {
            frame.threads = self.copy_frame(encoder, stateless)?;
        }
        if let Some(depth) = &self.depth {
            self.copy_depth_axis(encoder, camera)?;
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("depth sort"),
                timestamp_writes: None,
            });
            depth.record(
                &self.gpu,
                &mut pass,
                &self.res,
                self.sort_chunks()?,
                SortAlgorithm::Radix,
            )?;
        }
        Ok(frame)
    }

    /// The buffers and layout a draw of this effect binds (for [`crate::draw::splat`]).
    pub(crate) fn resources(&self) -> &Resources {
        &self.res
    }

    /// The particle buffers the depth keys read (none for a stateless effect: it evaluates in
    /// place, so sorting allocates no view).
    fn sort_chunks(&self) -> Result<&[Chunk], RuntimeError> {
        match self.steps {
            Steps::Stateless(_) => Ok(&[]),
            Steps::Stateful(_) => self.chunks(),
        }
    }

    /// Copies a stateless effect's segment table for the steps done into the frame buffer;
    /// returns its threads.
    fn copy_frame(
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

    fn copy_depth_axis(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        let src = staging(&self.gpu, "depth axis", &camera.depth_axis_bytes())?;
        encoder.copy_buffer_to_buffer(&src, 0, &sort_buffers(&self.res)?.depth_axis, 0, 16);
        Ok(())
    }

    /// Writes a stateless effect's segment table now, with the queue (for timed passes, which
    /// record into an encoder of their own; a frame's draw copies it in its encoder instead).
    fn write_frame_now(&self, stateless: &StatelessSteps) -> Result<(), RuntimeError> {
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
    fn depth(&self) -> Result<&DepthSort, RuntimeError> {
        self.depth.as_ref().ok_or_else(|| {
            RuntimeError::Output("this effect has no sort stage (sort: false)".into())
        })
    }

    /// The effect's own camera (its view matrix is all the sort uses).
    fn effect_camera(&self) -> Camera {
        Camera::from_effect(&self.effect.ir.camera, 1.0)
    }

    /// A stateless effect: computes the view at the steps done, unless it already holds them.
    /// A stateful effect: nothing to do.
    fn evaluate_view(&self) -> Result<(), RuntimeError> {
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

    /// Sorts every slot by depth along `camera`'s axis on the GPU (farthest first, free slots
    /// last) and returns the live slots in draw order, each with its 16-bit key
    /// ([`crate::sort::quantise`]).
    pub fn draw_order_from(
        &self,
        camera: &Camera,
        algorithm: SortAlgorithm,
    ) -> Result<Vec<(u32, u32)>, RuntimeError> {
        let depth = self.depth()?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        if let Steps::Stateless(stateless) = &self.steps {
            self.copy_frame(&mut encoder, stateless)?;
        }
        self.copy_depth_axis(&mut encoder, camera)?;
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            depth.record(
                &self.gpu,
                &mut pass,
                &self.res,
                self.sort_chunks()?,
                algorithm,
            )?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        let alive = self.totals()?.alive as usize;
        let buffers = sort_buffers(&self.res)?;
        let keys = read_words(&self.gpu, &buffers.keys, alive)?;
        let slots = read_words(&self.gpu, &buffers.vals, alive)?;
        Ok(slots.into_iter().zip(keys).collect())
    }

    /// [`Self::draw_order_from`] the effect's own camera.
    pub fn draw_order(&self, algorithm: SortAlgorithm) -> Result<Vec<(u32, u32)>, RuntimeError> {
        self.draw_order_from(&self.effect_camera(), algorithm)
    }

    /// Times the depth keys and the sort of every slot in one pass (seconds), from the
    /// effect's camera.
    pub fn time_sort(
        &self,
        timer: &PassTimer<'_>,
        algorithm: SortAlgorithm,
    ) -> Result<f64, RuntimeError> {
        let depth = self.depth()?;
        if let Steps::Stateless(stateless) = &self.steps {
            self.write_frame_now(stateless)?;
        }
        self.gpu.queue.write_buffer(
            &sort_buffers(&self.res)?.depth_axis,
            0,
            &self.effect_camera().depth_axis_bytes(),
        );
        let chunks = self.sort_chunks()?;
        let seconds =
            timer.time(|pass| depth.record(&self.gpu, pass, &self.res, chunks, algorithm))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// The live particles in draw order: sorted by their 16-bit depth keys on the GPU,
    /// farthest first; equal keys by id, so the order is the same run after run.
    pub fn records_in_draw_order(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let order = self.draw_order(SortAlgorithm::Radix)?;
        let by_slot = self.records_by_slot()?;
        let mut out: Vec<(u32, ParticleRecord)> = Vec::with_capacity(order.len());
        for (slot, key) in order {
            let record = by_slot
                .get(slot as usize)
                .copied()
                .flatten()
                .ok_or_else(|| {
                    RuntimeError::Readback(format!("sorted slot {slot} holds no live particle"))
                })?;
            out.push((key, record));
        }
        // Stable: equal keys (depths within one key step) by id.
        out.sort_by_key(|(key, r)| (*key, r.id));
        Ok(out.into_iter().map(|(_, r)| r).collect())
    }

    /// Runs `steps` (at most [`STEPS_PER_SUBMIT`]) in one timed compute pass; returns seconds.
    /// A stateless effect advances its bookkeeping by `steps` and times as many evaluations of
    /// the view (each one what a frame read back costs), so the two compare per step.
    pub fn time_steps(&mut self, timer: &PassTimer<'_>, steps: u32) -> Result<f64, RuntimeError> {
        let steps = steps.min(STEPS_PER_SUBMIT);
        if let Steps::Stateless(stateless) = &mut self.steps {
            stateless.advance(&mut self.schedule, u64::from(steps), |_| {});
            let Steps::Stateless(stateless) = &self.steps else {
                unreachable!("matched above");
            };
            self.write_frame_now(stateless)?;
            let chunks = self.chunks()?;
            let seconds = timer.time(|pass| {
                for _ in 0..steps {
                    stateless.record_evaluate(&self.gpu, pass, chunks)?;
                }
                Ok(())
            })?;
            self.gpu.take_error()?;
            stateless.mark_view_current();
            return Ok(seconds);
        }
        let Steps::Stateful(stateful) = &self.steps else {
            unreachable!("stateless returned above");
        };
        let plans: Vec<StepPlan> = (0..steps).map(|_| self.schedule.next_plan()).collect();
        let bytes = params_bytes(
            &plans,
            self.effect.layout.emitter_slots,
            self.res.params_stride,
            self.effect.ir.wraps_kernel_time(),
        );
        let params = self
            .res
            .params
            .as_ref()
            .expect("a stateful effect has params");
        self.gpu.queue.write_buffer(params, 0, &bytes);
        let chunks = self.chunks()?;
        let stride = self.res.params_stride;
        let seconds =
            timer.time(|pass| stateful.record(&self.gpu, pass, chunks, &plans, stride))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// Steps done and the GPU's counters: alive, spawned, died, dropped. A stateless effect
    /// drops nothing and counts from its bookkeeping (the kernels' own lifetime draw).
    pub fn totals(&self) -> Result<Totals, RuntimeError> {
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
        Ok(decode_totals(
            &bytes,
            self.effect.ir.capacity,
            self.schedule.steps_done(),
        ))
    }

    /// The live particles in id order, velocity as the integrator knows it (Verlet's derived).
    pub fn records(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let mut out: Vec<ParticleRecord> = self.records_by_slot()?.into_iter().flatten().collect();
        out.sort_by_key(|r| r.id);
        Ok(out)
    }

    /// Every slot's particle, in slot order (None for a free slot): the order an unsorted draw
    /// follows.
    pub fn records_by_slot(&self) -> Result<Vec<Option<ParticleRecord>>, RuntimeError> {
        self.evaluate_view()?;
        let mut bytes = Vec::new();
        for chunk in self.chunks()? {
            bytes.push(read_buffer(&self.gpu, &chunk.buffer)?);
        }
        decode_slots(&self.effect, &self.schedule, &bytes)
    }

    /// Reads a flocking buffer back by its layout name (`boids`, `flock_out`, ...), for tests.
    pub fn read_flock_buffer(&self, name: &str) -> Result<Vec<u8>, RuntimeError> {
        let buffer = self
            .effect
            .ir
            .flock
            .as_ref()
            .and_then(|_| self.res.extra_named(&self.effect, name))
            .ok_or_else(|| RuntimeError::Output(format!("this effect has no buffer {name}")))?;
        read_buffer(&self.gpu, buffer)
    }

    /// Times each stage of the flocking pass on the current state (seconds, by stage name),
    /// the median of `repeats` runs of each stage prefix, by difference. Empty when the effect
    /// does not flock. The state does not change: the pass writes only its own buffers.
    pub fn time_flock_stages(
        &self,
        timer: &PassTimer<'_>,
        repeats: u32,
    ) -> Result<Vec<(&'static str, f64)>, RuntimeError> {
        let Steps::Stateful(stateful) = &self.steps else {
            return Ok(Vec::new());
        };
        let Some(flock) = stateful.flock() else {
            return Ok(Vec::new());
        };
        let chunk = &self.chunks()?[0];
        let mut prefix = vec![0.0];
        for stages in 1..=flock.stage_names().len() {
            prefix.push(median_after_warmup(repeats, || {
                timer.time(|pass| flock.record_stages(&self.gpu, pass, chunk, 0, stages))
            })?);
        }
        self.gpu.take_error()?;
        Ok(flock
            .stage_names()
            .iter()
            .zip(prefix.windows(2))
            .map(|(name, w)| (*name, w[1] - w[0]))
            .collect())
    }

    /// Whether its steps record GPU work: a stateful effect's, or a stateless group's that fires
    /// events.
    pub(crate) fn steps_on_gpu(&self) -> bool {
        match &self.steps {
            Steps::Stateful(_) => true,
            Steps::Stateless(s) => s.firing.is_some(),
        }
    }

    /// Whether the effect runs stateless (no state kept; computed when read or drawn).
    pub fn is_stateless(&self) -> bool {
        matches!(self.steps, Steps::Stateless(_))
    }

    /// Number of particle buffers the state is split into.
    pub fn chunk_count(&self) -> usize {
        self.res.chunk_count()
    }

    /// Bytes of particle buffers allocated now: the state (stateful), or the view a readback
    /// made (stateless; 0 for an effect that has only been drawn).
    pub fn particle_buffer_bytes(&self) -> u64 {
        if !self.res.has_chunks() {
            return 0;
        }
        self.chunks()
            .map(|c| c.iter().map(|c| c.buffer.size()).sum())
            .unwrap_or(0)
    }

    /// The compiled effect being run.
    pub fn effect(&self) -> &CompiledEffect {
        &self.effect
    }

    /// The spawn schedule (steps done, ids requested, ages).
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Steps done so far.
    pub fn steps_done(&self) -> u64 {
        self.schedule.steps_done()
    }

    /// Simulation time of the steps done, k · dt (s, f64).
    pub fn time(&self) -> f64 {
        self.schedule.steps_done() as f64 * self.effect.ir.dt
    }

    /// A stateful effect's counters (six u32: free count, spawn base, spawn count, spawned,
    /// dropped, died), for a host that reads totals without waiting: copy them in its
    /// encoder, map the copy, and decode it with [`crate::device::readback::decode_totals`]. None for
    /// a stateless effect, whose [`Self::totals`] needs no GPU.
    pub fn counters(&self) -> Option<&wgpu::Buffer> {
        self.res.counters.as_ref()
    }

    /// The device this instance runs on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }
}
