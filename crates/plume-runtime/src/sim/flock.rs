//! The per-step flocking pass of an effect with a Flock force, recorded between the spawn and
//! the update: the snapshot (+ partial sums) where all pairs or the global means need it, the
//! global means, then all pairs or the grid (bucket counts, their scan into run starts, which
//! also zeroes the counts for the next step, the scatter of the boids into their runs, each run
//! put in slot order with the snapshot, the search by tiles). The kernels are the compiler's (`forces/flock.rs`); this module only
//! dispatches them.

use plume_compiler::forces::flock::{FlockIr, Neighbors, Scope, GRID_TILE, SEARCH_BUFFERS};
use plume_compiler::passes::layout::Role;
use plume_compiler::CompiledEffect;

use crate::device::gpu::Gpu;
use crate::device::resources::{Chunk, Resources};
use crate::error::RuntimeError;
use crate::sort::radix::{GpuSorter, SortProgram};

/// The uniform grid's extra kernels and its scan.
struct GridPass {
    bucket: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    rank: wgpu::ComputePipeline,
    /// The exclusive scan of the bucket counts into run starts, zeroing the counts.
    scan: SortProgram,
    /// Whether the search runs nine threads a boid (`FlockIr::split_search`).
    split_search: bool,
    /// The search, from its own module (`CompiledEffect::flock_search_wgsl`), and its bind
    /// group: the grid's buffers, read-only but for the results.
    search: wgpu::ComputePipeline,
    search_group: wgpu::BindGroup,
}

/// The flocking kernels of one effect.
pub(crate) struct FlockPass {
    snapshot: Option<wgpu::ComputePipeline>,
    reduce: Option<wgpu::ComputePipeline>,
    /// All pairs (None with the grid, whose search is its own).
    pairs: Option<wgpu::ComputePipeline>,
    grid: Option<GridPass>,
}

impl FlockPass {
    /// The pass for `flock` of `effect`, whose buffers `res` holds.
    pub(crate) fn new(
        gpu: &Gpu,
        res: &Resources,
        effect: &CompiledEffect,
        flock: &FlockIr,
    ) -> Result<Self, RuntimeError> {
        let grid = match flock.neighbors {
            Neighbors::Grid { .. } => {
                let find = |role| {
                    res.extra_of(effect, role)
                        .expect("the layout binds the grid's buffers")
                };
                let source = effect
                    .flock_search_wgsl
                    .as_deref()
                    .expect("the compiler emits a grid flock's search module");
                let module = gpu.shader_module("flock search", source);
                let search = gpu.compute_pipeline(&module, "flock_grid", None);
                let entries: Vec<(u32, &wgpu::Buffer)> = effect
                    .layout
                    .bindings
                    .iter()
                    .filter(|b| SEARCH_BUFFERS.contains(&b.role))
                    .map(|b| (b.binding, find(b.role)))
                    .collect();
                let search_group =
                    gpu.bind_buffers("flock search", &search.get_bind_group_layout(0), &entries);
                Some(GridPass {
                    search,
                    search_group,
                    bucket: res.pipeline("grid_bucket"),
                    scatter: res.pipeline("grid_scatter"),
                    rank: res.pipeline("grid_rank"),
                    split_search: FlockIr::split_search(effect.ir.capacity),
                    scan: GpuSorter::new(gpu).scan_program_from(
                        Some(find(Role::CellCounts)),
                        find(Role::CellStart),
                        FlockIr::grid_buckets(effect.ir.capacity) + 1,
                    )?,
                })
            }
            Neighbors::AllPairs => None,
        };
        // The grid reads the particles itself; the snapshot is for all pairs and the sums.
        let snapshot = grid.is_none() || flock.scope == Scope::Global;
        Ok(Self {
            snapshot: snapshot.then(|| res.pipeline("flock_snapshot")),
            reduce: (flock.scope == Scope::Global).then(|| res.pipeline("flock_reduce")),
            pairs: grid.is_none().then(|| res.pipeline("flock_pairs")),
            grid,
        })
    }

    /// The pass's stages in recording order, for timing them one by one.
    #[cfg(feature = "tools")]
    pub(crate) fn stage_names(&self) -> &'static [&'static str] {
        match (&self.grid, &self.reduce) {
            (Some(_), None) => &["bucket counts", "scan", "scatter", "rank", "search"],
            (Some(_), Some(_)) => &[
                "snapshot and sums",
                "bucket counts",
                "scan",
                "scatter",
                "rank",
                "search",
            ],
            (None, None) => &["snapshot", "all pairs"],
            (None, Some(_)) => &["snapshot and sums", "all pairs"],
        }
    }

    /// Records one step's flocking pass (one chunk: boids index slots globally) with the
    /// step's parameters at `offset`: snapshot, means, neighbour search.
    pub(crate) fn record(
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
    pub(crate) fn record_stages(
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
        if let Some(snapshot) = &self.snapshot {
            if !next() {
                return Ok(());
            }
            pass.set_pipeline(snapshot);
            pass.dispatch_workgroups(x, y, 1);
            if let Some(reduce) = &self.reduce {
                pass.set_pipeline(reduce);
                pass.dispatch_workgroups(1, 1, 1);
            }
            crate::device::dispatch_marks::mark(pass, "flock_snapshot");
        }
        if let Some(grid) = &self.grid {
            if !next() {
                return Ok(());
            }
            // The counts start at zero: the last step's scan cleared them (and a new buffer is
            // zeroed).
            pass.set_pipeline(&grid.bucket);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "flock_bucket");
            if !next() {
                return Ok(());
            }
            grid.scan.record(pass);
            crate::device::dispatch_marks::mark(pass, "flock_scan");
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
            if !next() {
                return Ok(());
            }
            pass.set_pipeline(&grid.scatter);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "flock_scatter");
            if !next() {
                return Ok(());
            }
            pass.set_pipeline(&grid.rank);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "flock_rank");
        }
        if !next() {
            return Ok(());
        }
        if let Some(grid) = &self.grid {
            // The split search runs nine threads a boid, a tile of boids a workgroup.
            let (x, y) = match grid.split_search {
                true => gpu.grid(chunk.len, u64::from(GRID_TILE))?,
                false => (x, y),
            };
            pass.set_pipeline(&grid.search);
            pass.set_bind_group(0, &grid.search_group, &[]);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "flock_search");
            // What the caller records next runs on the effect's own bind group.
            pass.set_bind_group(0, &chunk.bind_group, &[offset]);
        } else if let Some(pairs) = &self.pairs {
            pass.set_pipeline(pairs);
            pass.dispatch_workgroups(x, y, 1);
            crate::device::dispatch_marks::mark(pass, "flock_pairs");
        }
        Ok(())
    }
}
