//! The order of an event stream's firings: the firing group's update appends (id, slot) pairs,
//! in whatever order its threads ran; the child group spawns their children in id order, so
//! that ids and drops are the same every run. Up to [`RANK_MAX`] firings a step are ranked by
//! counting in one dispatch (event_order.wgsl); more are padded to the firing group's capacity
//! and sorted with the radix sort (crate::sort). `order_prepare` reads the count on the GPU and
//! writes the indirect arguments of both ways, zero for the one not taken, so the choice costs
//! no readback. A firing group too small to fire more than [`RANK_MAX`] is always counted.

use wgpu::util::DeviceExt;

use crate::error::RuntimeError;
use crate::gpu::Gpu;
use crate::resources::STORAGE;
use crate::sort::{GpuSorter, SortProgram};

/// The most firings a step ranked by counting (each compares its id with every other: 67M
/// comparisons at the most, about the radix sort's fixed cost on an H100).
pub const RANK_MAX: u32 = 8192;

/// Dispatches before the radix sort's in the arguments buffer: rank, pad, copy.
const OWN_DISPATCHES: u64 = 3;

/// One stream's ordering kernels and buffers.
pub enum EventOrder {
    /// A firing group of at most [`RANK_MAX`] slots never fires more: its firings are always
    /// ranked by counting, in one direct dispatch over its slots (whole workgroups past the
    /// count return at once). No indirect dispatch: on a CPU adapter each costs a wait for the
    /// work before it.
    Counted {
        /// `order_rank` and its bind group.
        rank: (wgpu::ComputePipeline, wgpu::BindGroup),
        /// Its workgroups.
        groups: (u32, u32),
    },
    /// A larger one: counted or sorted as the step's count decides, on the GPU.
    Either(Box<Gated>),
}

/// The kernels of [`EventOrder::Either`], each run with indirect arguments that
/// `order_prepare` writes.
pub struct Gated {
    prepare: (wgpu::ComputePipeline, wgpu::BindGroup),
    rank: (wgpu::ComputePipeline, wgpu::BindGroup),
    pad: (wgpu::ComputePipeline, wgpu::BindGroup),
    copy: (wgpu::ComputePipeline, wgpu::BindGroup),
    sort: SortProgram,
    args: wgpu::Buffer,
}

impl EventOrder {
    /// The ordering of a stream whose firing group has `n` slots: `keys`, `vals` (n each) and
    /// `records` (the count in its first word) are the firing group's; `order` (n) is where
    /// the firing slots land in id order.
    pub fn new(
        gpu: &Gpu,
        sorter: &GpuSorter,
        n: u64,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        records: &wgpu::Buffer,
        order: &wgpu::Buffer,
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("event order"),
            source: wgpu::ShaderSource::Wgsl(include_str!("event_order.wgsl").into()),
        });
        // Each kernel with a bind group of only what it uses: the arguments buffer is storage
        // for `order_prepare` and indirect for the others.
        let kernel = |entry: &str, entries: &[(u32, &wgpu::Buffer)]| {
            let pipeline = gpu.compute_pipeline(&module, entry, None);
            let group = gpu.bind_buffers(entry, &pipeline.get_bind_group_layout(0), entries);
            (pipeline, group)
        };
        let rank = kernel(
            "order_rank",
            &[(0, keys), (1, vals), (2, records), (3, order)],
        );
        if n <= u64::from(RANK_MAX) {
            return Ok(EventOrder::Counted {
                rank,
                groups: gpu.grid(n, 256)?,
            });
        }
        let sort = sorter.radix_program(keys, vals, n, 32)?;
        let sort_args: Vec<u8> = sort
            .dispatch_args()
            .iter()
            .flatten()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        let dispatches = sort.dispatch_args().len() as u64;
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let sort_args = init(
            "event sort arguments",
            &if sort_args.is_empty() {
                vec![0; 12]
            } else {
                sort_args
            },
            wgpu::BufferUsages::STORAGE,
        );
        let params: Vec<u8> = [n as u32, RANK_MAX, dispatches as u32, 0]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        let params = init("event order params", &params, wgpu::BufferUsages::UNIFORM);
        let args = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("event order arguments"),
            size: 12 * (OWN_DISPATCHES + dispatches),
            usage: STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        Ok(EventOrder::Either(Box::new(Gated {
            prepare: kernel(
                "order_prepare",
                &[(2, records), (4, &args), (5, &sort_args), (6, &params)],
            ),
            rank,
            pad: kernel("order_pad", &[(0, keys), (2, records), (6, &params)]),
            copy: kernel("order_copy", &[(1, vals), (2, records), (3, order)]),
            sort,
            args,
        })))
    }

    /// Records the ordering of this step's firings into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        match self {
            EventOrder::Counted { rank, groups } => {
                pass.set_pipeline(&rank.0);
                pass.set_bind_group(0, &rank.1, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
            EventOrder::Either(gated) => gated.record(pass),
        }
    }
}

impl Gated {
    fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.prepare.0);
        pass.set_bind_group(0, &self.prepare.1, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        for (k, (pipeline, group)) in [&self.rank, &self.pad].into_iter().enumerate() {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups_indirect(&self.args, 12 * k as u64);
        }
        self.sort
            .record_indirect(pass, &self.args, 12 * OWN_DISPATCHES);
        pass.set_pipeline(&self.copy.0);
        pass.set_bind_group(0, &self.copy.1, &[]);
        pass.dispatch_workgroups_indirect(&self.args, 24);
    }
}
