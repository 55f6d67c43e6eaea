//! Additive light's tile lists, placed without a sort: the kernels of `additive_lists.wgsl` and
//! the stages they take in the compute renderer's order. The composites (the generated one of quads and
//! ribbon segments, and `splat.wgsl`'s raster of discs) sum additive light in fixed point
//! (`plume_compiler`'s splat `light`), exactly, so a tile's list may hold its
//! entries in any order; counting and placing them replaces the scan, emit, radix sort and
//! ranges of the sorted lists, and costs less than they did (docs/performance.md, "What bounds
//! sparks and orbit").

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Sprites a workgroup of `count_entries` and `place` takes (256 threads times the shader's
/// PER).
const CHUNK: u64 = 1024;

/// Tiles those kernels count in workgroup memory at once (the shader's BAND): an image of
/// more tiles runs them once per band.
const BAND: u64 = 4096;

/// The four kernels on the tile kernels' layout.
pub(super) struct AdditiveLists {
    clear_cursors: wgpu::ComputePipeline,
    count_entries: wgpu::ComputePipeline,
    place_runs: wgpu::ComputePipeline,
    place: wgpu::ComputePipeline,
}

impl AdditiveLists {
    /// The kernels of `additive_lists.wgsl` on `layout` (the tile kernels' layout).
    pub(super) fn new(gpu: &Gpu, layout: &wgpu::BindGroupLayout) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let module = gpu.shader_module(
            "additive lists",
            concat!(
                include_str!("../../device/workgroup_scan.wgsl"),
                include_str!("tiles_shared.wgsl"),
                include_str!("additive_lists.wgsl")
            ),
        );
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("additive lists"),
            bind_group_layouts: &[Some(layout)],
            immediate_size: 0,
        });
        let kernel = |entry| gpu.compute_pipeline(&module, entry, Some(&pipeline_layout));
        let lists = Self {
            clear_cursors: kernel("clear_cursors"),
            count_entries: kernel("count_entries"),
            place_runs: kernel("place_runs"),
            place: kernel("place"),
        };
        gpu.take_error()?;
        Ok(lists)
    }

    /// Records what `stage` of the compute renderer's stages does for additive lists into `pass`, with
    /// the tile kernels' bind `group`, for `sprites` sprites over `tiles` tiles: "scan" counts
    /// the entries and finds each tile's run, "emit" places them, "sort" and "ranges" do
    /// nothing. `false`: the stage is not one of these (the group records it as for any list).
    pub(super) fn record_stage(
        &self,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        group: &wgpu::BindGroup,
        stage: &str,
        sprites: u32,
        tiles: u64,
    ) -> Result<bool, RuntimeError> {
        let chunks = gpu.grid(u64::from(sprites).div_ceil(CHUNK), 1)?;
        let bands = u32::try_from(tiles.div_ceil(BAND)).map_err(|_| {
            RuntimeError::Output(format!(
                "{tiles} tiles are more than the compute renderer counts"
            ))
        })?;
        let mut dispatch = |kernel: &wgpu::ComputePipeline, (x, y): (u32, u32), z: u32| {
            pass.set_bind_group(0, group, &[]);
            pass.set_pipeline(kernel);
            pass.dispatch_workgroups(x, y, z);
        };
        match stage {
            "scan" => {
                dispatch(&self.clear_cursors, gpu.grid(tiles, 256)?, 1);
                dispatch(&self.count_entries, chunks, bands);
                dispatch(&self.place_runs, (1, 1), 1);
            }
            "emit" => dispatch(&self.place, chunks, bands),
            "sort" | "ranges" => {}
            _ => return Ok(false),
        }
        Ok(true)
    }
}
