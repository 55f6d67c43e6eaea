//! The per-step flocking pass of an effect with a Flock force, recorded between the spawn and
//! the update: snapshot (+ partial sums), global means, then all pairs or the grid (bucket
//! keys, their radix sort, bucket ranges, search). The kernels are the compiler's
//! (`forces/flock.rs`); this module only dispatches them.

use plume_compiler::forces::flock::{FlockIr, Neighbors, Scope};
use plume_compiler::CompiledEffect;

use crate::error::RuntimeError;
use crate::gpu::Gpu;
use crate::resources::{Chunk, Resources};
use crate::sort::{GpuSorter, SortAlgorithm, SortProgram};

/// The uniform grid's extra kernels and its (bucket, slot) sort.
struct GridPass {
    bucket: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    ranges: wgpu::ComputePipeline,
    buckets: u64,
    sort: SortProgram,
}

/// The flocking kernels of one effect.
pub struct FlockPass {
    snapshot: wgpu::ComputePipeline,
    reduce: Option<wgpu::ComputePipeline>,
    neighbours: wgpu::ComputePipeline,
    grid: Option<GridPass>,
}

impl FlockPass {
    /// The pass for `flock` of `effect`, whose buffers `res` holds.
    pub fn new(
        gpu: &Gpu,
        res: &Resources,
        effect: &CompiledEffect,
        flock: &FlockIr,
    ) -> Result<Self, RuntimeError> {
        let grid = match flock.neighbors {
            Neighbors::Grid { .. } => {
                let find = |name: &str| {
                    res.extra_named(effect, name)
                        .expect("the layout binds the grid's buffers")
                };
                Some(GridPass {
                    bucket: res.pipeline("grid_bucket"),
                    clear: res.pipeline("grid_clear"),
                    ranges: res.pipeline("grid_ranges"),
                    buckets: FlockIr::grid_buckets(effect.ir.capacity),
                    sort: GpuSorter::new(gpu).program(
                        SortAlgorithm::Radix,
                        find("grid_keys"),
                        find("grid_vals"),
                        u64::from(effect.ir.capacity),
                    )?,
                })
            }
            Neighbors::AllPairs => None,
        };
        Ok(Self {
            snapshot: res.pipeline("flock_snapshot"),
            reduce: (flock.scope == Scope::Global).then(|| res.pipeline("flock_reduce")),
            neighbours: res.pipeline(if grid.is_some() {
                "flock_grid"
            } else {
                "flock_pairs"
            }),
            grid,
        })
    }

    /// Records one step's flocking pass (one chunk: boids index slots globally) with the
    /// step's parameters at `offset`: snapshot, means, neighbour search.
    pub fn record(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunk: &Chunk,
        offset: u32,
    ) -> Result<(), RuntimeError> {
        let (x, y) = gpu.grid(chunk.len, u64::from(plume_compiler::wgsl::WORKGROUP))?;
        pass.set_bind_group(0, &chunk.bind_group, &[offset]);
        pass.set_pipeline(&self.snapshot);
        pass.dispatch_workgroups(x, y, 1);
        if let Some(reduce) = &self.reduce {
            pass.set_pipeline(reduce);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if let Some(grid) = &self.grid {
            pass.set_pipeline(&grid.bucket);
            pass.dispatch_workgroups(x, y, 1);
            grid.sort.record(pass);
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
            let (bx, by) = gpu.grid(grid.buckets, u64::from(plume_compiler::wgsl::WORKGROUP))?;
            pass.set_pipeline(&grid.clear);
            pass.dispatch_workgroups(bx, by, 1);
            pass.set_pipeline(&grid.ranges);
            pass.dispatch_workgroups(x, y, 1);
        }
        pass.set_pipeline(&self.neighbours);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }
}
