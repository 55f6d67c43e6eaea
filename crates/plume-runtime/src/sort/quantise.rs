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
//! Three kernels (depth_quantise.wgsl) between the effect's `depth_keys` and the sort: reset
//! the range, reduce it over the live keys (one atomic per workgroup), map every key in place.

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// The quantising kernels of one sort buffer, built once.
pub struct DepthQuantise {
    /// (pipeline, its bind group, its workgroups) in recording order.
    dispatches: Vec<(wgpu::ComputePipeline, wgpu::BindGroup, (u32, u32))>,
}

/// Threads per workgroup of the reduce and quantise kernels (depth_quantise.wgsl).
const WORKGROUP: u64 = 256;

/// The bits of a quantised key the radix sort must order.
pub const KEY_BITS: u32 = 16;

impl DepthQuantise {
    /// The kernels that quantise the first `n` keys of `keys` in place.
    pub fn new(gpu: &Gpu, keys: &wgpu::Buffer, n: u64) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let module = crate::device::gpu::shader_module(
            device,
            "depth quantise",
            include_str!("depth_quantise.wgsl"),
        );
        let pipeline = |entry| gpu.compute_pipeline(&module, entry, None);
        let (reset, reduce, quantise) = (
            pipeline("range_reset"),
            pipeline("range_reduce"),
            pipeline("quantise"),
        );
        let grid = gpu.grid(n, WORKGROUP)?;
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
            dispatches: vec![
                (reset.clone(), bind(&reset, &[(1, &range)]), (1, 1)),
                (reduce.clone(), bind(&reduce, &all), grid),
                (quantise.clone(), bind(&quantise, &all), grid),
            ],
        })
    }

    /// Records the three kernels into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (pipeline, group, (x, y)) in &self.dispatches {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(*x, *y, 1);
        }
    }
}
