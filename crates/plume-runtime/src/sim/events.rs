//! The order of an event stream's firings: the child group spawns their children in the firing
//! particles' id order, so that ids and drops are the same every run, whatever order the
//! firing group's threads ran in. The firing group's update appended (id, slot) pairs; how
//! they are put in order, the compiler decided by the firing group's capacity
//! (plume_compiler::events::Ordering): up to `COUNTED_MAX` slots, `order_rank`
//! (event_order.wgsl) ranks them by counting, in one dispatch; past that, each firing sets its
//! id's bit in a bitmap (or, where the ids span more than 32 bits a slot, drops into a bucket of
//! ids) and each firing's place is counted from the words' counts (event_buckets.wgsl: a stream
//! compaction in id order, three dispatches, no sort). A stateless firing group's stream may
//! take the counting kernel in steps whose firings the host bounds (crate::sim::graph).
//!
//! (Until 2026-11 a large group wrote a key per slot and the radix sort ordered every slot:
//! four passes of 8 bits whether 5 or 50,000 fired; docs/performance.md, "Events", has both.)

use plume_compiler::events::Ordering;

use crate::device::buffers::STORAGE;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Threads of every ordering kernel's workgroup.
const THREADS: u64 = 256;
/// The most groups of words whose counts every workgroup of `bucket_place` scans
/// (event_buckets.wgsl's GROUPS).
const BUCKET_GROUPS: u64 = 2048;
/// The most workgroups of a bucket kernel: its threads stride over the firings (about the
/// threads an H100 holds at once; a grid over every slot launched millions that had nothing
/// to do).
const BUCKET_WORKGROUPS: u64 = 1024;

/// One dispatch: a kernel, its bind group and its workgroups.
struct Dispatch {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    grid: (u32, u32),
    /// The kernel's name, for `plume bench --profile`.
    entry: &'static str,
}

/// One stream's ordering: its dispatches, in order.
pub struct EventOrder {
    dispatches: Vec<Dispatch>,
}

impl EventOrder {
    /// The ordering of a stream whose firing group has `n` slots: `keys`, `vals` (n each) and
    /// `records` (the count, the id range, then the records) are the firing group's. The firing
    /// slots, in id order, go to `order` (n).
    pub fn new(
        gpu: &Gpu,
        ordering: Ordering,
        n: u64,
        (keys, vals, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        order: &wgpu::Buffer,
    ) -> Result<Self, RuntimeError> {
        let module = |label: &str, source: &'static str| {
            crate::device::gpu::shader_module(&gpu.device, label, source)
        };
        let dispatch = |module: &wgpu::ShaderModule,
                        entry: &'static str,
                        entries: &[(u32, &wgpu::Buffer)],
                        grid: (u32, u32)| {
            let pipeline = gpu.compute_pipeline(module, entry, None);
            let group = gpu.bind_buffers(entry, &pipeline.get_bind_group_layout(0), entries);
            Dispatch {
                pipeline,
                group,
                grid,
                entry,
            }
        };
        let dispatches = match ordering {
            Ordering::Counted => {
                let module = module("event order", include_str!("event_order.wgsl"));
                vec![dispatch(
                    &module,
                    "order_rank",
                    &[(0, keys), (1, vals), (2, records), (3, order)],
                    gpu.grid(n, THREADS)?,
                )]
            }
            Ordering::Bucketed => {
                let module = module("event buckets", include_str!("event_buckets.wgsl"));
                let buffer = |label: &str, words: u64| {
                    gpu.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size: words.max(1) * 4,
                        usage: STORAGE,
                        mapped_at_creation: false,
                    })
                };
                // Created zeroed, as the counts are between steps.
                let counts = buffer("event bucket counts", n);
                let group_counts = buffer("event bucket group counts", BUCKET_GROUPS + n / 4 + 1);
                let within = buffer("event bucket places", n);
                let staged = buffer("event bucket staging", 2 * n);
                let runs = buffer("event bucket runs", 2 * n);
                let over_firings = gpu.grid(n.min(BUCKET_WORKGROUPS * THREADS), THREADS)?;
                vec![
                    dispatch(
                        &module,
                        "bucket_count",
                        &[
                            (0, keys),
                            (2, records),
                            (4, &counts),
                            (5, &group_counts),
                            (6, &within),
                        ],
                        over_firings,
                    ),
                    dispatch(
                        &module,
                        "bucket_place",
                        &[
                            (0, keys),
                            (1, vals),
                            (2, records),
                            (3, order),
                            (4, &counts),
                            (5, &group_counts),
                            (6, &within),
                            (7, &staged),
                            (8, &runs),
                        ],
                        over_firings,
                    ),
                    dispatch(
                        &module,
                        "bucket_rank",
                        &[
                            (0, keys),
                            (2, records),
                            (3, order),
                            (4, &counts),
                            (5, &group_counts),
                            (7, &staged),
                            (8, &runs),
                        ],
                        over_firings,
                    ),
                ]
            }
        };
        Ok(Self { dispatches })
    }

    /// Records the ordering of this step's firings into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        for d in &self.dispatches {
            pass.set_pipeline(&d.pipeline);
            pass.set_bind_group(0, &d.group, &[]);
            pass.dispatch_workgroups(d.grid.0, d.grid.1, 1);
            crate::device::dispatch_marks::mark(pass, d.entry);
        }
    }
}
