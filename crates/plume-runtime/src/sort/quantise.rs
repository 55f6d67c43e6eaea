//! Depth keys quantised to 16 bits over the live particles' depth range, so that the depth
//! sort is two 8-bit radix passes instead of four (half the sort's time).
//!
//! What the draw loses: two live particles whose depths differ by less than one step,
//! (farthest − nearest live depth) / 65,533, may share a key and are then drawn in slot order
//! instead of depth order; particles more than one step apart are always drawn farther first.
//! Over a 100 m deep cloud a step is 1.5 mm, and two sprites that close in depth blend to
//! colours that differ by a fraction of an 8-bit step unless they are large and opaque and
//! their colours very different. The f32 depth itself resolves 7.6 µm at 100 m, so 16 bits
//! keep about 1/200 of the f32 order; 24 bits would keep it all but take as long as 32 (the
//! radix sort runs an even number of passes).
//!
//! Two kernels (depth_quantise.wgsl) between the effect's `depth_keys` and the sort: reset the
//! range, reduce it over the live keys (one atomic pair per workgroup of 4,096 keys). The radix
//! sort maps each key as its first pass reads it
//! ([`crate::sort::radix::GpuSorter::depth_program`]); for the bitonic sort two more map every
//! key in place and give every slot its own index as its value first.

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// One recorded dispatch: pipeline, its bind group, its workgroups.
type Dispatch = (wgpu::ComputePipeline, wgpu::BindGroup, (u32, u32));

/// The quantising kernels of one sort buffer, built once.
pub(crate) struct DepthQuantise {
    /// The range's reset and reduction, in recording order.
    range_dispatches: [Dispatch; 2],
    /// The map of every key in place and every slot's value (the bitonic sort's path).
    map: [Dispatch; 2],
    /// The live range: the smallest and largest live key (8 bytes).
    range: wgpu::Buffer,
}

/// Threads per workgroup of the reduce and quantise kernels (depth_quantise.wgsl).
const WORKGROUP: u64 = 256;

/// Keys a workgroup of `range_reduce` reads (depth_quantise.wgsl's RANGE_KEYS_PER_THREAD times
/// its threads).
const RANGE_KEYS_PER_WORKGROUP: u64 = 16 * WORKGROUP;

/// The bits of a quantised key the radix sort must order.
pub(crate) const KEY_BITS: u32 = 16;

impl DepthQuantise {
    /// The kernels that quantise the first `n` keys of `keys` in place (and, for the bitonic
    /// sort, give `vals` every slot's index).
    pub(crate) fn new(
        gpu: &Gpu,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let module = gpu.shader_module("depth quantise", include_str!("depth_quantise.wgsl"));
        let pipeline = |entry| gpu.compute_pipeline(&module, entry, None);
        let (reset, reduce, quantise, identity) = (
            pipeline("range_reset"),
            pipeline("range_reduce"),
            pipeline("quantise"),
            pipeline("identity_vals"),
        );
        let grid = gpu.grid(n, WORKGROUP)?;
        let range_grid = gpu.grid(n.div_ceil(RANGE_KEYS_PER_WORKGROUP), 1)?;
        let range = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("live depth range"),
            size: 8,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let words = [n as u32, grid.0 * WORKGROUP as u32, 0, 0];
        let params = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("depth quantise params"),
                contents: &words
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .collect::<Vec<u8>>(),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        // Each pipeline's layout is derived from its entry point: a bind group per pipeline,
        // of only the bindings it uses.
        let bind = |pipeline: &wgpu::ComputePipeline, entries: &[(u32, &wgpu::Buffer)]| {
            gpu.bind_buffers(
                "depth quantise",
                &pipeline.get_bind_group_layout(0),
                entries,
            )
        };
        let all = [(0, keys), (1, &range), (2, &params)];
        Ok(Self {
            range_dispatches: [
                (reset.clone(), bind(&reset, &[(1, &range)]), (1, 1)),
                (reduce.clone(), bind(&reduce, &all), range_grid),
            ],
            map: [
                (quantise.clone(), bind(&quantise, &all), grid),
                (
                    identity.clone(),
                    bind(&identity, &[(2, &params), (3, vals)]),
                    grid,
                ),
            ],
            range,
        })
    }

    /// The live range the reduction leaves: the smallest and largest live key, for the radix
    /// sort's first pass to map the keys by.
    pub(crate) fn range(&self) -> &wgpu::Buffer {
        &self.range
    }

    /// Records the range's reset and reduction into `pass`.
    pub(crate) fn record_range(&self, pass: &mut wgpu::ComputePass<'_>) {
        for dispatch in &self.range_dispatches {
            record(pass, dispatch);
        }
    }

    /// Records the range, then the map of every key in place and the slots as values into
    /// `pass` (before a sort that does not map the keys itself).
    pub(crate) fn record_in_place(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.record_range(pass);
        for dispatch in &self.map {
            record(pass, dispatch);
        }
    }
}

fn record(pass: &mut wgpu::ComputePass<'_>, (pipeline, group, (x, y)): &Dispatch) {
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(*x, *y, 1);
}
