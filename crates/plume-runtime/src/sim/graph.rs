//! An effect graph's event streams (plume_compiler::events has the contract), and the steps
//! of several groups recorded together. Each stream owns buffers that both groups bind: the
//! firing group notes each firing's id and slot and writes its record in the slot; at the
//! start of the next step [`crate::sim::events`] puts the firing slots in id order (its first
//! kernel also pops the children's slots), and the child's `event_spawn` turns them, in that
//! order, into particles. Every
//! step of every group and every stream is recorded into one compute pass per submission of
//! steps: nothing is read back between steps.

use plume_compiler::events::{
    in_binding, out_binding, Ordering, COUNTED_MAX, RECORDS_HEADER_BYTES, RECORD_BYTES,
};
use plume_compiler::graph::{CompiledGraph, Stream};
use plume_compiler::schedule::StepPlan;

use crate::device::buffers::STORAGE;
use crate::device::gpu::Gpu;
use crate::device::resources::STEPS_PER_SUBMIT;
use crate::error::RuntimeError;
use crate::sim::events::EventOrder;
use crate::sim::group::Group;
use crate::sim::reports::ReportGather;

/// One event stream and the ordering of its firings.
pub(crate) struct StreamOrder {
    pub(crate) stream: Stream,
    pub(crate) order: EventOrder,
    /// For a bucketed stream whose firing group is stateless, the same firings' ordering by
    /// counting, which a step takes when the host knows it orders at most
    /// [`COUNTED_MAX`] firings: a stateless group fires over a table whose size the host sets
    /// each submission (one dispatch, not three: fireworks' rockets fire over a few hundred threads of
    /// their 9,403 slots at 10M).
    pub(crate) counted: Option<EventOrder>,
}

impl StreamOrder {
    /// The ordering that step `j` of the planned submission records, given the firing group.
    pub(crate) fn for_step(&self, parent: &Group, j: usize) -> &EventOrder {
        match (&self.counted, parent.firings_bound(j)) {
            (Some(counted), Some(bound)) if bound <= u64::from(COUNTED_MAX) => counted,
            _ => &self.order,
        }
    }
}

/// A storage buffer of `size` bytes for an event stream (zeroed, as wgpu makes them).
fn storage_buffer(gpu: &Gpu, label: &str, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: STORAGE,
        mapped_at_creation: false,
    })
}

/// Buffers a group binds instead of allocating them, by binding index.
pub(crate) type SharedBuffers = Vec<(u32, wgpu::Buffer)>;

/// The event streams of an effect graph, in the order children are spawned each step, and the
/// gathers of its reported events.
pub(crate) struct Events {
    pub(crate) orders: Vec<StreamOrder>,
    pub(crate) reports: Vec<ReportGather>,
}

impl Events {
    /// Allocates every stream's buffers on `gpu` and builds its ordering; returns the streams
    /// and, per group, the buffers it binds (by binding index) instead of allocating them.
    pub(crate) fn new(
        gpu: &Gpu,
        graph: &CompiledGraph,
    ) -> Result<(Self, Vec<SharedBuffers>), RuntimeError> {
        let mut shared: Vec<SharedBuffers> = vec![Vec::new(); graph.groups.len()];
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
            let buffer = |label: &str, size: u64| storage_buffer(gpu, label, size);
            let keys = buffer("event keys", parent * 4);
            let vals = buffer("event slots", parent * 4);
            // Where the child reads the firing slots in id order.
            let order = buffer("event order", parent * 4);
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
            // The attributes the stream passes, where its children inherit some.
            let passes = &graph.groups[s.parent].effect.ir.events[s.out_slot].passes;
            if !passes.is_empty() {
                let stride = u64::from(plume_compiler::inherit::stride(passes.len()));
                let attrs = buffer("event attributes", parent * stride * 4);
                shared[s.parent].push((
                    plume_compiler::inherit::out_binding(s.out_slot),
                    attrs.clone(),
                ));
                shared[s.child].push((plume_compiler::inherit::in_binding(s.in_slot), attrs));
            }
            let stateless_parent = graph.groups[s.parent].effect.ir.stateless.is_some();
            let counted = (s.ordering == Ordering::Bucketed && stateless_parent)
                .then(|| {
                    let buffers = (&keys, &vals, &records);
                    EventOrder::new(gpu, Ordering::Counted, parent, buffers, &order, s.count)
                })
                .transpose()?;
            orders.push(StreamOrder {
                stream: s.clone(),
                order: EventOrder::new(
                    gpu,
                    s.ordering,
                    parent,
                    (&keys, &vals, &records),
                    &order,
                    s.count,
                )?,
                counted,
            });
        }
        let reports = Self::reports(gpu, graph, &mut shared, &orders)?;
        Ok((Self { orders, reports }, shared))
    }

    /// The gathers of every reported event, in group order then event order. An event that
    /// only reports has no stream: its firings' buffers are made here, for its group to bind.
    fn reports(
        gpu: &Gpu,
        graph: &CompiledGraph,
        shared: &mut [SharedBuffers],
        orders: &[StreamOrder],
    ) -> Result<Vec<ReportGather>, RuntimeError> {
        let mut reports = Vec::new();
        for (g, group) in graph.groups.iter().enumerate() {
            let n = u64::from(group.effect.ir.capacity);
            for (j, event) in group.effect.ir.events.iter().enumerate() {
                if event.stream.is_some() && event.report == 0 {
                    continue;
                }
                let at = out_binding(j);
                let bound = |k: u32| {
                    shared[g]
                        .iter()
                        .find(|(b, _)| *b == at + k)
                        .map(|(_, buffer)| buffer.clone())
                };
                let buffers = match (bound(0), bound(1), bound(2)) {
                    (Some(keys), Some(slots), Some(records)) => [keys, slots, records],
                    _ => {
                        let buffer = |label: &str, size: u64| storage_buffer(gpu, label, size);
                        let made = [
                            buffer("event keys", n * 4),
                            buffer("event slots", n * 4),
                            buffer("event records", RECORDS_HEADER_BYTES + n * RECORD_BYTES),
                        ];
                        for (k, b) in made.iter().enumerate() {
                            shared[g].push((at + k as u32, b.clone()));
                        }
                        made
                    }
                };
                if event.report > 0 {
                    let clears = !orders
                        .iter()
                        .any(|o| o.stream.parent == g && o.stream.out_slot == j);
                    reports.push(ReportGather::new(
                        gpu,
                        (g, j, event.report),
                        (&buffers[0], &buffers[1], &buffers[2]),
                        clears,
                    )?);
                }
            }
        }
        Ok(reports)
    }

    /// Binds each stream's ordering to its child group's counters (its first kernel prepares
    /// the children's spawn), once `groups` exist.
    pub(crate) fn bind_children(
        &mut self,
        gpu: &Gpu,
        groups: &[Group],
    ) -> Result<(), RuntimeError> {
        for s in &mut self.orders {
            let counters = groups[s.stream.child].event_counters()?;
            s.order.bind_child(gpu, counters);
            if let Some(counted) = &mut s.counted {
                counted.bind_child(gpu, counters);
            }
        }
        Ok(())
    }

    /// Records `steps` steps of every group into `encoder` (a compute pass per
    /// [`STEPS_PER_SUBMIT`] steps), with GPU timestamps when given (as
    /// [`Group::advance_timed`]). Per step: each stream's ordering and its child's event spawn,
    /// in stream order, then each group's own step (spawn, update), in group order. Returns
    /// whether any pass was recorded (none when every group is stateless, or for 0 steps).
    pub(crate) fn advance_timed(
        &self,
        groups: &mut [Group],
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) -> Result<bool, RuntimeError> {
        let gpu_work = groups.iter().any(Group::steps_on_gpu);
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let plans = groups
                .iter_mut()
                .map(|g| g.plan_graph_submission(encoder, n))
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
                self.record_submission(groups, &mut pass, &plans, n)?;
            }
            done += n;
        }
        Ok(gpu_work && steps > 0)
    }

    /// Records a planned submission of `steps` steps (each group's plans, from `plan_graph_submission`):
    /// per step, each stream's ordering and its child's event spawn, in stream order, then each
    /// group's own step.
    pub(crate) fn record_submission(
        &self,
        groups: &[Group],
        pass: &mut wgpu::ComputePass<'_>,
        plans: &[Vec<StepPlan>],
        steps: u64,
    ) -> Result<(), RuntimeError> {
        for j in 0..steps as usize {
            crate::device::dispatch_marks::boundary(pass);
            for (k, s) in self.orders.iter().enumerate() {
                crate::device::dispatch_marks::scope('s', k);
                s.for_step(&groups[s.stream.parent], j).record(pass);
                groups[s.stream.child].record_event_spawn(pass, s.stream.in_slot, j)?;
            }
            for (g, group) in groups.iter().enumerate() {
                crate::device::dispatch_marks::scope('g', g);
                group.record_graph_step(pass, &plans[g], j)?;
            }
            for (k, report) in self.reports.iter().enumerate() {
                crate::device::dispatch_marks::scope('r', k);
                report.record(pass);
            }
        }
        Ok(())
    }
}
