//! The order of an event stream's firings: the child group spawns their children in the firing
//! particles' id order, so that ids and drops are the same every run, whatever order the
//! firing group's threads ran in. How, the compiler decided by the firing group's capacity
//! (plume_compiler::events::Ordering): up to `COUNTED_MAX` slots, the update appended
//! (id, slot) pairs and `order_rank` (event_order.wgsl) ranks them by counting, in one
//! dispatch; past that, the update wrote a key per slot and the radix sort (crate::sort::radix) leaves
//! the firing slots first, in id order.
//!
//! (Both in one stream, chosen on the GPU by the step's count through indirect arguments, was
//! tried: on an H100 the fifteen indirect dispatches and the barriers between them cost more
//! than the radix sort they could skip; docs/performance.md, "Events".)

use plume_compiler::events::Ordering;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sort::radix::{GpuSorter, SortProgram};

/// One stream's ordering.
pub enum EventOrder {
    /// `order_rank` over every slot of the firing group (whole workgroups past the count
    /// return at once), with its bind group.
    Counted {
        /// The kernel and its bind group.
        rank: (wgpu::ComputePipeline, wgpu::BindGroup),
        /// Its workgroups.
        groups: (u32, u32),
    },
    /// The radix sort of the firing group's keys and values.
    Sorted(SortProgram),
}

impl EventOrder {
    /// The ordering of a stream whose firing group has `n` slots: `keys`, `vals` (n each) and
    /// `records` (the count in its first word) are the firing group's. A counted stream writes
    /// the firing slots in id order to `order` (n); a sorted one leaves them first in `vals`.
    pub fn new(
        gpu: &Gpu,
        sorter: &GpuSorter,
        ordering: Ordering,
        n: u64,
        (keys, vals, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        order: &wgpu::Buffer,
    ) -> Result<Self, RuntimeError> {
        Ok(match ordering {
            Ordering::Counted => {
                let module = gpu
                    .device
                    .create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some("event order"),
                        source: wgpu::ShaderSource::Wgsl(include_str!("event_order.wgsl").into()),
                    });
                let pipeline = gpu.compute_pipeline(&module, "order_rank", None);
                let group = gpu.bind_buffers(
                    "order_rank",
                    &pipeline.get_bind_group_layout(0),
                    &[(0, keys), (1, vals), (2, records), (3, order)],
                );
                EventOrder::Counted {
                    rank: (pipeline, group),
                    groups: gpu.grid(n, 256)?,
                }
            }
            Ordering::Sorted => EventOrder::Sorted(sorter.radix_program(keys, vals, n, 32)?),
        })
    }

    /// Records the ordering of this step's firings into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        match self {
            EventOrder::Counted { rank, groups } => {
                pass.set_pipeline(&rank.0);
                pass.set_bind_group(0, &rank.1, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
            EventOrder::Sorted(program) => program.record(pass),
        }
    }
}
