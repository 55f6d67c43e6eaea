//! An effect graph running on a device: one [`EffectInstance`] per group, and the event
//! streams between them (plume_compiler::events has the contract). Each stream owns buffers
//! that both groups bind: the firing group notes each firing's id and slot and writes its
//! record in the slot; at the start of the next step crate::sim::events puts the firing slots
//! in id order, and the child's `event_prepare` and `event_spawn` turn them, in that order,
//! into particles. Every step of every group and every stream is recorded into one compute
//! pass per batch of steps: nothing is read back between steps.

use plume_compiler::events::{
    in_binding, out_binding, Ordering, RECORDS_HEADER_BYTES, RECORD_BYTES,
};
use plume_compiler::graph::{CompiledGraph, Stream};
use plume_compiler::reference::{ParticleRecord, Totals};

use crate::error::RuntimeError;
use crate::sim::events::EventOrder;
use crate::device::gpu::Gpu;
use crate::sim::group::EffectInstance;
use crate::device::resources::{STEPS_PER_SUBMIT, STORAGE};
use crate::sort::radix::GpuSorter;
use crate::bench::timer::{median_after_warmup, PassTimer};

/// One event stream and the ordering of its firings.
struct StreamOrder {
    stream: Stream,
    order: EventOrder,
}

/// An effect of one or more groups running on a GPU.
///
/// ```
/// // Shells that burst when their fuse (0.2 s) runs out, 30 sparks each.
/// let source = r#"Effect(
///     name: "shells",
///     capacity: 8,
///     emitters: [Emitter(burst: 8, shape: Sphere(center: (0.0, 5.0, 0.0), radius: 1.0),
///                        velocity: Constant((0.0, 4.0, 0.0)), lifetime: Some((0.2, 0.2)))],
///     forces: [Gravity((0.0, -9.81, 0.0))],
///     events: [Event(on: Death, target: "sparks", count: 30, velocity: Radial(speed: (2.0, 3.0)),
///                    lifetime: Some((1.0, 1.0)), inherit_velocity: 0.5)],
///     groups: [Group(name: "sparks", capacity: 1000, forces: [Gravity((0.0, -9.81, 0.0))])],
/// )"#;
/// let graph = plume_compiler::graph::compile_graph_str(source, &Default::default()).unwrap();
/// let gpu = plume_runtime::Gpu::new(&Default::default()).unwrap();
/// let mut shells = plume_runtime::GraphInstance::new(&gpu, graph.clone()).unwrap();
/// shells.run(20, |_| {}).unwrap();
/// // The shells died at step 11 (12 steps of 1/60 s); their sparks spawned at step 12.
/// assert_eq!(shells.totals(0).unwrap().alive, 0);
/// assert_eq!(shells.totals(1).unwrap().spawned, 240);
/// // The f64 reference runs the same graph: the same particles in every group.
/// let mut reference = plume_compiler::reference::ReferenceGraph::new(&graph);
/// reference.run(20);
/// for g in 0..2 {
///     let ids = |records: Vec<plume_compiler::reference::ParticleRecord>| {
///         records.iter().map(|r| r.id).collect::<Vec<_>>()
///     };
///     assert_eq!(ids(shells.records(g).unwrap()), ids(reference.records(g)));
/// }
/// ```
pub struct GraphInstance {
    gpu: Gpu,
    names: Vec<String>,
    groups: Vec<EffectInstance>,
    orders: Vec<StreamOrder>,
}

impl GraphInstance {
    /// Allocates every group's buffers and the event streams' on `gpu`, and builds the kernels.
    pub fn new(gpu: &Gpu, graph: CompiledGraph) -> Result<Self, RuntimeError> {
        Self::with_chunk_slots(gpu, graph, None)
    }

    /// Like [`Self::new`] with at most `max_chunk_slots` particles per buffer in every group
    /// (tests use it to exercise the split on small effects).
    pub fn with_chunk_slots(
        gpu: &Gpu,
        graph: CompiledGraph,
        max_chunk_slots: Option<u64>,
    ) -> Result<Self, RuntimeError> {
        let mut shared: Vec<Vec<(u32, wgpu::Buffer)>> = vec![Vec::new(); graph.groups.len()];
        let sorter = GpuSorter::new(gpu);
        let mut orders = Vec::new();
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size);
        for s in &graph.streams {
            let parent = u64::from(graph.groups[s.parent].effect.ir.capacity);
            // A stream's records are one binding of 32 bytes a parent slot (not split into
            // chunks as particles are): that bounds a firing group's capacity.
            let bytes = RECORDS_HEADER_BYTES + parent * RECORD_BYTES;
            if bytes > limit {
                return Err(RuntimeError::Output(format!(
                    "group {:?} fires events: their records take {bytes} bytes, more than the adapter's {limit}-byte binding; a group that fires events holds at most {} particles here",
                    graph.groups[s.parent].name,
                    (limit - RECORDS_HEADER_BYTES) / RECORD_BYTES
                )));
            }
            let buffer = |label: &str, size: u64| {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: STORAGE,
                    mapped_at_creation: false,
                })
            };
            let keys = buffer("event keys", parent * 4);
            let vals = buffer("event slots", parent * 4);
            // Where the child reads the firing slots in id order: counted into a buffer of
            // their own, or first in the sorted values.
            let order = match s.ordering {
                Ordering::Counted => buffer("event order", parent * 4),
                Ordering::Sorted => vals.clone(),
            };
            let records = buffer(
                "event records",
                RECORDS_HEADER_BYTES + parent * RECORD_BYTES,
            );
            let at = out_binding(s.out_slot);
            shared[s.parent].extend([
                (at, keys.clone()),
                (at + 1, vals.clone()),
                (at + 2, records.clone()),
            ]);
            let at = in_binding(s.in_slot);
            shared[s.child].extend([(at, order.clone()), (at + 1, records.clone())]);
            orders.push(StreamOrder {
                stream: s.clone(),
                order: EventOrder::new(
                    gpu,
                    &sorter,
                    s.ordering,
                    parent,
                    (&keys, &vals, &records),
                    &order,
                )?,
            });
        }
        let mut names = Vec::new();
        let mut groups = Vec::new();
        for (g, group) in graph.groups.into_iter().enumerate() {
            names.push(group.name);
            groups.push(EffectInstance::with_shared(
                gpu,
                group.effect,
                max_chunk_slots,
                &shared[g],
            )?);
        }
        gpu.take_error()?;
        Ok(Self {
            gpu: gpu.clone(),
            names,
            groups,
            orders,
        })
    }

    /// Records `steps` steps of every group into `encoder` (a compute pass per
    /// [`STEPS_PER_SUBMIT`] steps). Per step: each stream's ordering and its child's event spawn,
    /// in stream order, then each group's own step (spawn, update), in group order.
    pub fn advance(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<(), RuntimeError> {
        self.advance_timed(encoder, steps, None).map(|_| ())
    }

    /// Like [`Self::advance`], with GPU timestamps: `query_set` gets one at index `first` when
    /// the steps' first compute pass begins and one at `first + 1` when the last one ends.
    /// Returns whether any pass was recorded (none when every group is stateless, or for 0
    /// steps), as [`EffectInstance::advance_timed`] does.
    pub fn advance_timed(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) -> Result<bool, RuntimeError> {
        let gpu_work = self.groups.iter().any(EffectInstance::steps_on_gpu);
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let plans = self
                .groups
                .iter_mut()
                .map(|g| g.plan_graph_batch(encoder, n))
                .collect::<Result<Vec<_>, _>>()?;
            if gpu_work {
                let writes = timestamps.map(|(set, first)| wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: (done == 0).then_some(first),
                    end_of_pass_write_index: (done + n == steps).then_some(first + 1),
                });
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("graph steps"),
                    timestamp_writes: writes,
                });
                self.record_batch(&mut pass, &plans, n)?;
            }
            done += n;
        }
        Ok(gpu_work && steps > 0)
    }

    /// Records a planned batch of `steps` steps (each group's plans, from `plan_graph_batch`):
    /// per step, each stream's ordering and its child's event spawn, in stream order, then each
    /// group's own step.
    fn record_batch(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        plans: &[Vec<plume_compiler::schedule::StepPlan>],
        steps: u64,
    ) -> Result<(), RuntimeError> {
        for j in 0..steps as usize {
            for s in &self.orders {
                s.order.record(pass);
                self.groups[s.stream.child].record_event_spawn(pass, s.stream.in_slot, j)?;
            }
            for (g, group) in self.groups.iter().enumerate() {
                group.record_graph_step(pass, &plans[g], j)?;
            }
        }
        Ok(())
    }

    /// Runs `steps` steps in submissions of [`STEPS_PER_SUBMIT`], calling `progress(done)`
    /// after each; returns when the GPU has finished.
    pub fn run(&mut self, steps: u64, mut progress: impl FnMut(u64)) -> Result<(), RuntimeError> {
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

    /// The groups' names, the top-level group first.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The groups' instances (to draw or read each one).
    pub fn groups(&self) -> &[EffectInstance] {
        &self.groups
    }

    /// Group `g`'s live particles in id order.
    pub fn records(&self, g: usize) -> Result<Vec<ParticleRecord>, RuntimeError> {
        self.group(g)?.records()
    }

    /// Group `g`'s totals (spawned and dropped count its event spawns).
    pub fn totals(&self, g: usize) -> Result<Totals, RuntimeError> {
        self.group(g)?.totals()
    }

    fn group(&self, g: usize) -> Result<&EffectInstance, RuntimeError> {
        self.groups.get(g).ok_or_else(|| {
            RuntimeError::Output(format!(
                "the effect has {} groups, not {}",
                self.groups.len(),
                g + 1
            ))
        })
    }

    /// Steps done so far.
    pub fn steps_done(&self) -> u64 {
        self.groups[0].steps_done()
    }

    /// Runs `steps` steps (at most [`STEPS_PER_SUBMIT`]) in one timed compute pass; returns
    /// seconds. The steps' parameters are copied in a submission of their own first.
    pub fn time_steps(&mut self, timer: &PassTimer<'_>, steps: u32) -> Result<f64, RuntimeError> {
        let n = u64::from(steps.min(STEPS_PER_SUBMIT));
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let plans = self
            .groups
            .iter_mut()
            .map(|g| g.plan_graph_batch(&mut encoder, n))
            .collect::<Result<Vec<_>, _>>()?;
        self.gpu.queue.submit([encoder.finish()]);
        let seconds = timer.time(|pass| self.record_batch(pass, &plans, n))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// Times each stream's ordering of the last step's firings alone, in stream order
    /// (seconds each, the median of `repeats`). The state does not change: it orders the
    /// same firings again.
    pub fn time_orders(
        &self,
        timer: &PassTimer<'_>,
        repeats: u32,
    ) -> Result<Vec<f64>, RuntimeError> {
        self.orders
            .iter()
            .map(|s| {
                median_after_warmup(repeats, || {
                    timer.time(|pass| {
                        s.order.record(pass);
                        Ok(())
                    })
                })
            })
            .collect()
    }
}
