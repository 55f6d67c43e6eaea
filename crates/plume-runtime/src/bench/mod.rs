//! Benchmarks and measurements, for `plume bench`, `plume accuracy` and the tools in
//! `examples/`: the update against a copy kernel ([`bench`](fn@bench)), the draw ([`DrawTimes`]), the
//! events' cost ([`bench_graph`]), each dispatch's share of a step ([`DispatchTime`],
//! `--profile`), the radix sort alone ([`bench_sort`], with the sorter itself, [`GpuSorter`]), the integrators' error against time per step ([`measure`], plotted
//! by [`accuracy_svg`]), an accuracy budget checked on the GPU ([`check_budget`]), and the GPU pass timer they share ([`PassTimer`]). Also the knobs the
//! measurements turn: a renderer with other [`DrawOptions`] ([`renderer_with`]), a GPU buffer
//! read back ([`read_buffer`]), and the dispatch helpers the layout experiments in `examples/`
//! share with Plume's kernels ([`grid`], [`bind_buffers`], [`compute_pipeline`]).
//!
//! Imports every other folder; nothing imports it.

pub(crate) mod accuracy;
pub(crate) mod budget;
pub(crate) mod copy;
pub(crate) mod draw;
pub(crate) mod effect_copy;
pub(crate) mod graph;
pub(crate) mod plot;
pub(crate) mod profile;
pub(crate) mod sort;
pub(crate) mod timer;
pub(crate) mod timing;
pub(crate) mod update;

pub use crate::device::readback::read_buffer;
pub use crate::draw::raster::{DeadSlots, DrawOptions};
pub use crate::sort::radix::{GpuSorter, Ranking, SortAlgorithm};
pub use accuracy::{
    field_sweep, measure, measured_effect, pareto_front, reference, AccuracyPlan, AccuracyRow,
    Engine, FieldRow, ReferenceKind,
};
pub use budget::{check_budget, BudgetCheck, CHECKED};
pub use draw::{DrawTimes, DRAW_REPEATS};
pub use effect_copy::{bench_effect, bench_effect_occupied, compile_bench, draw_copy};
pub use graph::{bench_graph, scaled, GraphBench};
pub use plot::accuracy_svg;
pub use profile::DispatchTime;
pub use sort::{bench_sort, SortBench, SortTime};
pub use timer::{median_after_warmup, PassTimer, TimingSource};
pub use update::{bench, BenchOptions, BenchResult, FIELD_ERROR_SAMPLES, ROUNDS};

use crate::device::gpu::Gpu;
use crate::draw::renderer::EffectRenderer;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;

/// A renderer of `effect` into targets like `target` with other choices than the default
/// ([`DrawOptions`]: another blend, hidden free slots, triangles).
pub fn renderer_with(
    effect: &Effect,
    target: &DrawTarget,
    options: &DrawOptions,
) -> Result<EffectRenderer, RuntimeError> {
    effect.renderer_with(target, options)
}

/// A 2D dispatch of `threads` threads in workgroups of `workgroup` (x capped at the adapter's
/// per-dimension limit), as Plume's kernels are dispatched.
pub fn grid(gpu: &Gpu, threads: u64, workgroup: u64) -> Result<(u32, u32), RuntimeError> {
    gpu.grid(threads, workgroup)
}

/// A bind group of `layout` binding whole buffers (by binding index).
pub fn bind_buffers(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    gpu.bind_buffers(label, layout, entries)
}

/// The compute pipeline of `module`'s entry point `entry` (also its label), on `layout`, or
/// on the layout derived from the bindings the entry point uses when `None`.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let gpu = plume_runtime::Gpu::new(&Default::default())?;
/// let module = gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
///     label: Some("double"),
///     source: wgpu::ShaderSource::Wgsl(
///         "@group(0) @binding(0) var<storage, read_write> xs: array<f32>;
///          @compute @workgroup_size(64)
///          fn double(@builtin(global_invocation_id) id: vec3<u32>) { xs[id.x] *= 2.0; }"
///             .into(),
///     ),
/// });
/// let pipeline = plume_runtime::bench::compute_pipeline(&gpu, &module, "double", None);
/// let _layout = pipeline.get_bind_group_layout(0); // derived: binding 0 only
/// gpu.take_error()?;
/// # Ok(())
/// # }
/// ```
pub fn compute_pipeline(
    gpu: &Gpu,
    module: &wgpu::ShaderModule,
    entry: &str,
    layout: Option<&wgpu::PipelineLayout>,
) -> wgpu::ComputePipeline {
    gpu.compute_pipeline(module, entry, layout)
}
