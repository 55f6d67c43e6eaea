//! The per-step flocking pass of an effect with a Flock force, recorded between the spawn and
//! the update: snapshot (+ partial sums), global means, then all pairs or the grid (bucket
//! keys and counts, their radix sort, the counts' scan into run starts, the snapshot reordered
//! by bucket, search). The kernels are the compiler's
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
    reorder: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    buckets: u64,
    sort: SortProgram,
    /// The exclusive scan of the bucket counts into run starts.
    scan: SortProgram,
    /// Whether the search runs nine threads a boid (`FlockIr::split_search`).
    split_search: bool,
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
                let sorter = GpuSorter::new(gpu);
                let find = |name: &str| {
                    res.extra_named(effect, name)
                        .expect("the layout binds the grid's buffers")
                };
                Some(GridPass {
                    bucket: res.pipeline("grid_bucket"),
                    reorder: res.pipeline("grid_reorder"),
                    clear: res.pipeline("grid_clear"),
                    split_search: FlockIr::split_search(effect.ir.capacity),
                    buckets: FlockIr::grid_buckets(effect.ir.capacity),
                    sort: sorter.program(
                        SortAlgorithm::Radix,
                        find("grid_keys"),
                        find("grid_vals"),
                        u64::from(effect.ir.capacity),
                    )?,
                    scan: sorter.scan_program(
                        find("cell_start"),
                        FlockIr::grid_buckets(effect.ir.capacity) + 1,
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

    /// The pass's stages in recording order, for timing them one by one.
    pub fn stage_names(&self) -> &'static [&'static str] {
        match (&self.grid, &self.reduce) {
            (Some(_), None) => &[
                "snapshot",
                "bucket keys",
                "sort",
                "scan",
                "reorder",
                "search",
            ],
            (Some(_), Some(_)) => &[
                "snapshot and sums",
                "bucket keys",
                "sort",
                "scan",
                "reorder",
                "search",
            ],
            (None, None) => &["snapshot", "all pairs"],
            (None, Some(_)) => &["snapshot and sums", "all pairs"],
        }
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
        self.record_stages(gpu, pass, chunk, offset, usize::MAX)
    }

    /// Records only the first `stages` stages of [`FlockPass::stage_names`] (the benchmark
    /// times each stage by difference; the pass writes only its own buffers, so it can be
    /// recorded again without changing the simulation).
    pub fn record_stages(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        chunk: &Chunk,
        offset: u32,
        stages: usize,
    ) -> Result<(), RuntimeError> {
        let (x, y) = gpu.grid(chunk.len, u64::from(plume_compiler::wgsl::WORKGROUP))?;
        pass.set_bind_group(0, &chunk.bind_group, &[offset]);
        let mut stage = 0;
        // Whether stage `stage` is recorded; counts it.
        let mut next = || {
            stage += 1;
            stage <= stages
        };
        if !next() {
            return Ok(());
        }
        pass.set_pipeline(&self.snapshot);
        pass.dispatch_workgroups(x, y, 1);
        if let Some(reduce) = &self.reduce {
            pass.set_pipeline(reduce);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if let Some(grid) = &self.grid {
            if !next() {
                return Ok(());
            }
            let (bx, by) =
                gpu.grid(grid.buckets + 1, u64::from(plume_compiler::wgsl::WORKGROUP))?;
            pass.set_pipeline(&grid.clear);
            pass.dispatch_workgroups(bx, by, 1);
            pass.set_pipeline(&grid.bucket);
            pass.dispatch_workgroups(x, y, 1);
            if !next() {
                return Ok(());
            }
            grid.sort.record(pass);
            if !next() {
                return Ok(());
            }
            grid.scan.record(pass);
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
            if !next() {
                return Ok(());
            }
            pass.set_pipeline(&grid.reorder);
            pass.dispatch_workgroups(x, y, 1);
        }
        if !next() {
            return Ok(());
        }
        // The grid's split search runs nine threads a boid, a fixed number of boids a group.
        let (x, y) = match &self.grid {
            Some(grid) if grid.split_search => gpu.grid(
                chunk.len,
                u64::from(plume_compiler::forces::flock::GRID_BOIDS_PER_GROUP),
            )?,
            _ => (x, y),
        };
        pass.set_pipeline(&self.neighbours);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }
}
