//! The depth sort of an effect with `sort: true`: the compute module's `depth_keys` kernel gives
//! every slot a key (farthest first along the camera's depth axis; free slots last),
//! [`DepthQuantise`] finds the live depth range, then the radix sort orders (key, slot) pairs
//! in two passes, the first mapping each key to 16 bits over that range as it reads it and
//! pairing it with its index, the slot. The sorted slots are the draw order the vertex shader
//! follows. A stateless effect's keys come from its closed form evaluated in place, so sorting
//! costs 8 bytes a slot of per-frame scratch and no state.

use plume_compiler::wgsl::WORKGROUP;
use plume_compiler::CompiledEffect;

use crate::device::gpu::Gpu;
use crate::device::resources::{Chunk, Resources, SortBuffers};
use crate::error::RuntimeError;
use crate::sort::quantise::DepthQuantise;
use crate::sort::radix::{GpuSorter, SortAlgorithm, SortProgram};

/// The depth sort's stages in recording order: the keys of every slot, their live range, the
/// radix sort (whose first pass maps the keys to 16 bits over that range).
pub(crate) const DEPTH_SORT_STAGES: [&str; 3] = ["keys", "range", "sort"];

/// How the keys kernel reads the particles.
enum Keys {
    /// One dispatch per particle buffer, on the compute module's shared bind groups.
    PerChunk(wgpu::ComputePipeline),
    /// A stateless effect: one dispatch over the capacity, evaluating the closed form, with a
    /// bind group of only the frame table and the sort's buffers.
    Evaluated(wgpu::ComputePipeline, wgpu::BindGroup),
}

/// The depth keys and sorts of one effect.
pub(crate) struct DepthSort {
    keys: Keys,
    /// The keys to 16 bits, built once.
    quantise: DepthQuantise,
    /// The radix sort of every slot's key mapped to 16 bits, built once: scratch buffers and
    /// bind groups reused.
    radix: SortProgram,
    sorter: GpuSorter,
    capacity: u64,
}

impl DepthSort {
    /// The sort stage of `effect`, whose buffers `res` holds.
    pub(crate) fn new(
        gpu: &Gpu,
        res: &Resources,
        effect: &CompiledEffect,
    ) -> Result<Self, RuntimeError> {
        let buffers = sort_buffers(res)?;
        let keys = if effect.layout.stateless() {
            let (pipeline, group) = res.standalone(effect, "depth_keys");
            Keys::Evaluated(pipeline, group)
        } else {
            Keys::PerChunk(res.pipeline("depth_keys"))
        };
        let sorter = GpuSorter::new(gpu);
        let capacity = u64::from(effect.ir.capacity);
        let quantise = DepthQuantise::new(gpu, &buffers.keys, &buffers.vals, capacity)?;
        Ok(Self {
            radix: sorter.depth_program(
                &buffers.keys,
                &buffers.vals,
                capacity,
                quantise.range(),
            )?,
            quantise,
            keys,
            sorter,
            capacity,
        })
    }

    /// Records the keys of every slot and their sort into `pass`. `chunks` are the particle
    /// buffers (unused by a stateless effect, which evaluates its particles in place).
    pub(crate) fn record(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        res: &Resources,
        chunks: &[Chunk],
        algorithm: SortAlgorithm,
    ) -> Result<(), RuntimeError> {
        self.record_stages(gpu, pass, res, chunks, algorithm, DEPTH_SORT_STAGES.len())
    }

    /// Records the first `stages` of [`DEPTH_SORT_STAGES`] (the benchmark times them by
    /// difference).
    pub(crate) fn record_stages(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        res: &Resources,
        chunks: &[Chunk],
        algorithm: SortAlgorithm,
        stages: usize,
    ) -> Result<(), RuntimeError> {
        if stages == 0 {
            return Ok(());
        }
        match &self.keys {
            Keys::PerChunk(pipeline) => {
                pass.set_pipeline(pipeline);
                for chunk in chunks {
                    let (x, y) = gpu.grid(chunk.len, u64::from(WORKGROUP))?;
                    // Stateful bind groups carry the step parameters' dynamic offset.
                    let offsets: &[u32] = if res.params.is_some() { &[0] } else { &[] };
                    pass.set_bind_group(0, &chunk.bind_group, offsets);
                    pass.dispatch_workgroups(x, y, 1);
                }
            }
            Keys::Evaluated(pipeline, group) => {
                let (x, y) = gpu.grid(self.capacity, u64::from(WORKGROUP))?;
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        if stages == 1 {
            return Ok(());
        }
        match algorithm {
            SortAlgorithm::Radix => {
                self.quantise.record_range(pass);
                if stages > 2 {
                    self.radix.record(pass);
                }
            }
            SortAlgorithm::Bitonic => {
                self.quantise.record_in_place(pass);
                let buffers = sort_buffers(res)?;
                self.sorter
                    .record(pass, algorithm, &buffers.keys, &buffers.vals, self.capacity)?
            }
        }
        Ok(())
    }
}

/// The effect's sort buffers, or the error of asking a `sort: false` effect for its order.
pub(crate) fn sort_buffers(res: &Resources) -> Result<&SortBuffers, RuntimeError> {
    res.sort
        .as_ref()
        .ok_or_else(|| RuntimeError::Output("this effect has no sort stage (sort: false)".into()))
}
