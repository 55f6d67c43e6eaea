//! The radix sort in one dispatch a pass (OneSweep, `radix_onesweep.wgsl`): every pass's digit
//! counts in one read of the keys beforehand, then per pass one kernel that ranks a partition,
//! learns how many keys of each digit the partitions before it hold by decoupled look-back, and
//! scatters. Reduce-then-scan (`radix.wgsl`) takes three dispatches a pass and reads the keys
//! twice; this takes one and reads them once, but a workgroup waits on others that started
//! before it, so it runs only where the GPU lets those progress (`Ranking::OneSweep`).

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sort::program::{self, SortProgram};

/// Partitions one workgroup of `rs_sweep_histogram` counts (radix_onesweep.wgsl's HIST_PARTS).
const HIST_PARTS: u64 = 4;

/// The OneSweep kernels of a sorter.
pub(crate) struct SweepKernels {
    clear: wgpu::ComputePipeline,
    histogram: wgpu::ComputePipeline,
    offsets: wgpu::ComputePipeline,
    sweep: wgpu::ComputePipeline,
}

impl SweepKernels {
    /// The kernels of `module` (`radix_source(Ranking::OneSweep)`).
    pub(super) fn new(gpu: &Gpu, module: &wgpu::ShaderModule) -> Self {
        let pipeline = |entry: &str| gpu.compute_pipeline(module, entry, None);
        Self {
            clear: pipeline("rs_sweep_clear"),
            histogram: pipeline("rs_sweep_histogram"),
            offsets: pipeline("rs_sweep_offsets"),
            sweep: pipeline("rs_sweep"),
        }
    }

    /// Records `passes` OneSweep passes over the first `n` pairs, in partitions of `partition`
    /// keys (radix.wgsl's PART): the counts' clear, the histogram of every pass, its scan, then
    /// one dispatch a pass. With `depth_range`, the keys are depth keys mapped to 16 bits over
    /// that range as the histogram and the first pass read them, each paired with its index
    /// (`GpuSorter::depth_program`); `module` has the depth entry points.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record_passes(
        &self,
        gpu: &Gpu,
        module: &wgpu::ShaderModule,
        program: &mut SortProgram,
        (keys, vals): (&wgpu::Buffer, &wgpu::Buffer),
        n: u64,
        partition: u64,
        passes: u32,
        depth_range: Option<&wgpu::Buffer>,
    ) -> Result<(), RuntimeError> {
        let partitions = n.div_ceil(partition);
        let buffer = |label, words| program::buffer(gpu, label, words);
        let (keys2, vals2) = (buffer("keys tmp", n), buffer("vals tmp", n));
        let hist = buffer("sweep digit counts", 256 * u64::from(passes));
        let status = buffer("sweep look-back", 256 * partitions * u64::from(passes));
        let next = buffer("sweep partition tickets", u64::from(passes));
        let depth = |entry: &str| gpu.compute_pipeline(module, &format!("{entry}_depth"), None);
        let (histogram, first_sweep) = match depth_range {
            Some(_) => (depth("rs_sweep_histogram"), depth("rs_sweep")),
            None => (self.histogram.clone(), self.sweep.clone()),
        };
        let range: Vec<(u32, &wgpu::Buffer)> = depth_range.map(|r| (7, r)).into_iter().collect();
        let p = program::uniform(gpu, &[n as u32, 0, partitions as u32, 0]);
        program.push(gpu, &self.clear, &[(8, &hist), (10, &next)], 1)?;
        let mut entries = vec![(0, keys), (5, &p), (8, &hist), (9, &status), (10, &next)];
        entries.extend(range.iter().copied());
        program.push(gpu, &histogram, &entries, partitions.div_ceil(HIST_PARTS))?;
        program.push(gpu, &self.offsets, &[(8, &hist), (10, &next)], 1)?;
        for pass_index in 0..passes {
            let (ki, vi, ko, vo) = if pass_index % 2 == 0 {
                (keys, vals, &keys2, &vals2)
            } else {
                (&keys2, &vals2, keys, vals)
            };
            let p = program::uniform(gpu, &[n as u32, 8 * pass_index, partitions as u32, 0]);
            let mut entries = vec![
                (0, ki),
                (1, vi),
                (2, ko),
                (3, vo),
                (5, &p),
                (8, &hist),
                (9, &status),
                (10, &next),
            ];
            let kernel = if pass_index == 0 {
                entries.extend(range.iter().copied());
                &first_sweep
            } else {
                &self.sweep
            };
            program.push(gpu, kernel, &entries, partitions)?;
        }
        Ok(())
    }
}
