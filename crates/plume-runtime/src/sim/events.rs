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
//! Either costs what fired, not the firing group's slots: a radix sort of a key per slot
//! would take its passes over every slot whether 5 or 50,000 fired (docs/performance.md,
//! "Events", measures both).

use plume_compiler::events::Ordering;
use plume_compiler::wgsl::counter_word;

use crate::device::buffers::STORAGE;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Threads of every ordering kernel's workgroup.
const THREADS: u64 = 256;
/// The most groups of words whose counts every workgroup of `bucket_place` scans
/// (event_buckets.wgsl's GROUPS).
const BUCKET_GROUPS: u64 = 2048;
/// The most workgroups of a bucket kernel: its threads stride over the firings (a grid over
/// every slot launched millions that had nothing to do). 256 rather than the 1,024 an H100
/// holds at once: fewer idle workgroups for the usual few thousand firings, and fewer
/// workgroups scanning the groups' counts in `bucket_place` when a million fire; 128 was no
/// better (docs/performance.md, "Events"; benchmarks/h100-events/ordering-ab/).
const BUCKET_WORKGROUPS: u64 = 256;

/// One dispatch: a kernel, its bind group and its workgroups.
struct Dispatch {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    grid: (u32, u32),
    /// The kernel's name, for `plume bench --profile`.
    entry: &'static str,
}

/// The ordering's first kernel, whose first thread also prepares the children's spawn
/// (event_prepare.wgsl): its pipeline that does, and one that does not (for timing the
/// ordering alone), each bound to the parent's buffers and, once the child exists
/// ([`EventOrder::bind_child`]), the child's counters.
struct First {
    pipelines: [wgpu::ComputePipeline; 2],
    groups: Option<[wgpu::BindGroup; 2]>,
    parent: Vec<(u32, wgpu::Buffer)>,
    grid: (u32, u32),
    entry: &'static str,
}

/// One stream's ordering: its dispatches, in order.
pub(crate) struct EventOrder {
    first: First,
    rest: Vec<Dispatch>,
}

/// The child's counters, where the first kernel binds them.
const CHILD_COUNTERS: u32 = 10;

impl EventOrder {
    /// The ordering of a stream whose firing group has `n` slots: `keys`, `vals` (n each) and
    /// `records` (the count, the id range, then the records) are the firing group's. The firing
    /// slots, in id order, go to `order` (n). Each firing asks for `count` children.
    pub(crate) fn new(
        gpu: &Gpu,
        ordering: Ordering,
        n: u64,
        (keys, vals, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        order: &wgpu::Buffer,
        count: u32,
    ) -> Result<Self, RuntimeError> {
        let module = |label: &str, source: &'static str| gpu.shader_module(label, source);
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
        let first = |module: &wgpu::ShaderModule,
                     entry: &'static str,
                     entries: &[(u32, &wgpu::Buffer)],
                     grid: (u32, u32)| {
            let pipeline = |prepare: bool| {
                let mut constants = vec![
                    ("PREPARE", if prepare { 1.0 } else { 0.0 }),
                    ("CHILD_COUNT", f64::from(count)),
                ];
                for (name, field) in PREPARED_COUNTERS {
                    let word = counter_word(field).expect("a counter the compiler declares");
                    constants.push((name, f64::from(word)));
                }
                gpu.compute_pipeline_with(module, entry, None, &constants)
            };
            First {
                pipelines: [pipeline(true), pipeline(false)],
                groups: None,
                parent: entries.iter().map(|(at, b)| (*at, (*b).clone())).collect(),
                grid,
                entry,
            }
        };
        let (first, rest) = match ordering {
            Ordering::Counted => {
                let module = module(
                    "event order",
                    concat!(
                        include_str!("event_prepare.wgsl"),
                        include_str!("event_order.wgsl")
                    ),
                );
                let rank = first(
                    &module,
                    "order_rank",
                    &[(0, keys), (1, vals), (2, records), (3, order)],
                    gpu.grid(n, THREADS)?,
                );
                (rank, Vec::new())
            }
            Ordering::Bucketed => {
                let module = module(
                    "event buckets",
                    concat!(
                        include_str!("../device/workgroup_scan.wgsl"),
                        include_str!("event_prepare.wgsl"),
                        include_str!("event_buckets.wgsl")
                    ),
                );
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
                let count = first(
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
                );
                let rest = vec![
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
                ];
                (count, rest)
            }
        };
        Ok(Self { first, rest })
    }

    /// Binds the first kernel to the child group's `counters`, once the child exists.
    pub(crate) fn bind_child(&mut self, gpu: &Gpu, counters: &wgpu::Buffer) {
        let mut entries: Vec<(u32, &wgpu::Buffer)> =
            self.first.parent.iter().map(|(at, b)| (*at, b)).collect();
        entries.push((CHILD_COUNTERS, counters));
        let group = |pipeline: &wgpu::ComputePipeline| {
            gpu.bind_buffers(
                self.first.entry,
                &pipeline.get_bind_group_layout(0),
                &entries,
            )
        };
        self.first.groups = Some([
            group(&self.first.pipelines[0]),
            group(&self.first.pipelines[1]),
        ]);
    }

    /// Records the ordering of this step's firings, and the preparation of the children's
    /// spawn, into `pass`.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.record_with(pass, true);
    }

    /// Records the ordering alone (the children's spawn not prepared: the state does not
    /// change), for timing it.
    #[cfg(feature = "tools")]
    pub(crate) fn record_alone(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.record_with(pass, false);
    }

    fn record_with(&self, pass: &mut wgpu::ComputePass<'_>, prepare: bool) {
        let at = usize::from(!prepare);
        let groups = self
            .first
            .groups
            .as_ref()
            .expect("an ordering is bound to its child before it is recorded");
        pass.set_pipeline(&self.first.pipelines[at]);
        pass.set_bind_group(0, &groups[at], &[]);
        pass.dispatch_workgroups(self.first.grid.0, self.first.grid.1, 1);
        crate::device::dispatch_marks::mark(pass, self.first.entry);
        for d in &self.rest {
            pass.set_pipeline(&d.pipeline);
            pass.set_bind_group(0, &d.group, &[]);
            pass.dispatch_workgroups(d.grid.0, d.grid.1, 1);
            crate::device::dispatch_marks::mark(pass, d.entry);
        }
    }
}

/// The child's counters the preparation writes: the override constant of each, and the
/// counter's name (plume_compiler::wgsl::COUNTER_FIELDS).
const PREPARED_COUNTERS: [(&str, &str); 7] = [
    ("FREE_COUNT", "free_count"),
    ("SPAWN_BASE", "spawn_base"),
    ("SPAWN_COUNT", "spawn_count"),
    ("SPAWNED", "spawned"),
    ("DROPPED", "dropped"),
    ("NEXT_ID", "next_id"),
    ("EVENT_FIRST_ID", "event_first_id"),
];
