//! GPU sorts of (key, value) pairs, ascending by key: a stable LSD radix sort (8-bit digits,
//! one pass each; the default) and a bitonic sort (the baseline it is measured against). Keys
//! are u32; equal keys keep their input order (radix) or are ordered by value (bitonic): the
//! same result when values start as 0, 1, 2, ... as they do for depth sorting.
//!
//! The radix sort is reduce-then-scan (radix.wgsl: count digits per partition, scan the counts,
//! rank and scatter), with two ways to rank keys within a partition ([`Ranking`]): subgroup
//! ballots where the adapter's subgroups are exactly 32 wide (NVIDIA, AMD RDNA in wave32), and
//! a workgroup-memory sorting network everywhere else (llvmpipe included). On NVIDIA the
//! subgroup ranking runs in one dispatch a pass instead ([`Ranking::OneSweep`],
//! [`crate::sort::onesweep`]). All give the same output, bit for bit: the sort is stable, so its
//! result is fully determined by its input.

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;
use crate::sort::onesweep::SweepKernels;
use crate::sort::program;
pub(crate) use crate::sort::program::SortProgram;

/// Which sort.
// The benchmarks (feature `tools`) choose the sort and its ranking; the draw takes the defaults.
#[cfg_attr(not(feature = "tools"), allow(dead_code))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortAlgorithm {
    /// Stable LSD radix sort, 4 passes of 8 bits.
    Radix,
    /// Bitonic sorting network on the power-of-two padded array.
    Bitonic,
}

/// How the radix sort ranks keys within a partition, and how a pass learns where each
/// partition's keys go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ranking {
    /// [`Ranking::Subgroup`]'s ranking in one dispatch a pass (OneSweep: every pass's digits
    /// counted at once beforehand, each partition's offsets by decoupled look-back on the
    /// partitions before it). A workgroup waits on workgroups that started before it, which
    /// neither WebGPU nor Vulkan promises will progress; NVIDIA GPUs do, so only they get it.
    OneSweep,
    /// Subgroup ballots (8 per 32 keys) and per-subgroup digit counters; needs
    /// `wgpu::Features::SUBGROUP` and subgroups of exactly 32 invocations.
    Subgroup,
    /// Tiles of 256 keys ranked by a bitonic network over (digit, lane) in workgroup memory; no
    /// subgroup operations, so every adapter runs it.
    Portable,
}

impl Ranking {
    /// The label of its radix module.
    fn module_label(self) -> &'static str {
        match self {
            Ranking::OneSweep => "radix (OneSweep)",
            Ranking::Subgroup => "radix (subgroup ranking)",
            Ranking::Portable => "radix (portable ranking)",
        }
    }
}

/// The radix module of `ranking`: the workgroup scan, the kernels every ranking shares and its
/// downsweep (OneSweep's on top of the subgroup ranking). naga 30 takes subgroup builtins
/// without WGSL's `enable subgroups;` (it refuses the directive); the device's SUBGROUP
/// feature is what allows them.
pub(super) fn radix_source(ranking: Ranking) -> String {
    let downsweep = match ranking {
        Ranking::OneSweep => concat!(
            include_str!("radix_subgroup.wgsl"),
            "\n",
            include_str!("radix_onesweep.wgsl")
        ),
        Ranking::Subgroup => include_str!("radix_subgroup.wgsl"),
        Ranking::Portable => include_str!("radix_portable.wgsl"),
    };
    format!(
        "{}\n{}\n{}",
        include_str!("../device/workgroup_scan.wgsl"),
        include_str!("radix.wgsl"),
        downsweep
    )
}

impl Ranking {
    /// The fastest ranking `gpu` can run.
    pub fn best_for(gpu: &Gpu) -> Self {
        Self::runnable_on(gpu)[0]
    }

    /// Every ranking `gpu` can run, the fastest first.
    pub fn runnable_on(gpu: &Gpu) -> Vec<Self> {
        let mut out = Vec::new();
        if gpu.has_subgroups_of(32) {
            if gpu.info.vendor == NVIDIA {
                out.push(Ranking::OneSweep);
            }
            out.push(Ranking::Subgroup);
        }
        out.push(Ranking::Portable);
        out
    }
}

/// PCI vendor id of NVIDIA, whose GPUs run [`Ranking::OneSweep`].
const NVIDIA: u32 = 0x10de;

/// The sort kernels.
#[cfg_attr(not(feature = "tools"), allow(dead_code))]
pub struct GpuSorter {
    pub(super) gpu: Gpu,
    ranking: Ranking,
    upsweep: wgpu::ComputePipeline,
    digit_scan: wgpu::ComputePipeline,
    digit_scan_small: wgpu::ComputePipeline,
    downsweep: wgpu::ComputePipeline,
    /// The radix module, for the depth sort's first-pass entry points (built on demand: most
    /// sorters never sort depths).
    radix: wgpu::ShaderModule,
    /// The OneSweep kernels ([`Ranking::OneSweep`]).
    sweep: Option<SweepKernels>,
    scan_blocks: wgpu::ComputePipeline,
    scan_blocks_from: wgpu::ComputePipeline,
    add_block_prefix: wgpu::ComputePipeline,
    scan_reduce: wgpu::ComputePipeline,
    scan_reduce_from: wgpu::ComputePipeline,
    scan_totals: wgpu::ComputePipeline,
    scan_apply: wgpu::ComputePipeline,
    scan_apply_from: wgpu::ComputePipeline,
    bitonic: wgpu::ComputePipeline,
}

/// Words a workgroup of a short exclusive scan (`scan_program`) takes, and threads of the
/// bitonic kernel's workgroups.
const TILE: u64 = 256;

/// Words a workgroup of a long exclusive scan takes (sort.wgsl's 2,048: eight a thread).
const SCAN_BLOCK: u64 = 2048;

/// The longest short scan: 256 blocks of 256 words, scanned in a dispatch and added up in
/// another (sort.wgsl's `scan_blocks`, `add_block_prefix`). Longer ones reduce then scan, eight
/// words a thread. Up to this length the short scan is the faster (the long one's few
/// workgroups wait on their own steps more than on memory); past it the long one is
/// (docs/performance.md, "Depth sort and the radix sort").
const SCAN_SHORT_MAX: u64 = 65_536;

/// The most blocks whose scan adds up the totals before each block in the block's own
/// workgroup (sort.wgsl's `scan_apply`, params.shift 0) instead of scanning the totals in a
/// dispatch of their own first: 4M words, each workgroup reading at most 2,048 totals. For the
/// flock grid's 2M + 1 bucket counts, reading up to 2,048 totals a workgroup cost no more than
/// the extra dispatch that a limit of 1,024 blocks needs.
const SCAN_PREFIX_MAX: u64 = 2048;

/// Keys per radix partition (radix.wgsl's PART).
const PARTITION: u64 = 2048;

/// The most partitions whose digit counts one workgroup scans (`rs_scan_small`, a thread a
/// digit walking its row) instead of one workgroup a digit (`rs_scan`): 65,536 keys.
const SMALL_SCAN_PARTITIONS: u64 = 32;

/// The first pass of a depth sort: entry points that map each key to 16 bits over the live
/// depth range as they read it (radix.wgsl's `quantised`).
struct DepthPass<'a> {
    upsweep: wgpu::ComputePipeline,
    downsweep: wgpu::ComputePipeline,
    range: &'a wgpu::Buffer,
}

impl GpuSorter {
    /// Builds the kernels on `gpu`, ranking the fastest way it can ([`Ranking::best_for`]).
    pub fn new(gpu: &Gpu) -> Self {
        Self::build(gpu, Ranking::best_for(gpu))
    }

    /// Builds the kernels with the given ranking; an error when `gpu` cannot run it.
    #[cfg(feature = "tools")]
    pub fn with_ranking(gpu: &Gpu, ranking: Ranking) -> Result<Self, RuntimeError> {
        if !Ranking::runnable_on(gpu).contains(&ranking) {
            return Err(RuntimeError::Gpu(format!(
                "{} cannot run the {ranking:?} ranking (subgroup ranking needs subgroups of exactly 32 invocations; OneSweep an NVIDIA GPU as well)",
                gpu.info.name
            )));
        }
        Ok(Self::build(gpu, ranking))
    }

    /// The ranking this sorter's radix sort uses.
    #[cfg(feature = "tools")]
    pub fn ranking(&self) -> Ranking {
        self.ranking
    }

    fn build(gpu: &Gpu, ranking: Ranking) -> Self {
        let module = |label: &str, source: String| gpu.shader_module(label, &source);
        let sort = module(
            "sort",
            format!(
                "{}\n{}",
                include_str!("../device/workgroup_scan.wgsl"),
                include_str!("sort.wgsl")
            ),
        );
        // The shared kernels and one downsweep: a subgroup module only on adapters with them.
        let radix = module(ranking.module_label(), radix_source(ranking));
        let pipeline =
            |module: &wgpu::ShaderModule, entry: &str| gpu.compute_pipeline(module, entry, None);
        Self {
            gpu: gpu.clone(),
            ranking,
            upsweep: pipeline(&radix, "rs_upsweep"),
            digit_scan: pipeline(&radix, "rs_scan"),
            digit_scan_small: pipeline(&radix, "rs_scan_small"),
            downsweep: pipeline(&radix, "rs_downsweep"),
            sweep: (ranking == Ranking::OneSweep).then(|| SweepKernels::new(gpu, &radix)),
            radix: radix.clone(),
            scan_blocks: pipeline(&sort, "scan_blocks"),
            scan_blocks_from: pipeline(&sort, "scan_blocks_from"),
            add_block_prefix: pipeline(&sort, "add_block_prefix"),
            scan_reduce: pipeline(&sort, "scan_reduce"),
            scan_reduce_from: pipeline(&sort, "scan_reduce_from"),
            scan_totals: pipeline(&sort, "scan_totals"),
            scan_apply: pipeline(&sort, "scan_apply"),
            scan_apply_from: pipeline(&sort, "scan_apply_from"),
            bitonic: pipeline(&sort, "bitonic_step"),
        }
    }

    fn params(&self, n: u64, shift: u32, tiles: u64, j: u64, k: u64) -> wgpu::Buffer {
        self.uniform(&[n as u32, shift, tiles as u32, j as u32, k as u32, 0, 0, 0])
    }

    fn uniform(&self, words: &[u32]) -> wgpu::Buffer {
        program::uniform(&self.gpu, words)
    }

    fn buffer(&self, label: &str, words: u64) -> wgpu::Buffer {
        program::buffer(&self.gpu, label, words)
    }

    /// Adds `pipeline` over `groups` workgroups with the given (binding, buffer) entries.
    fn dispatch(
        &self,
        program: &mut SortProgram,
        pipeline: &wgpu::ComputePipeline,
        entries: &[(u32, &wgpu::Buffer)],
        groups: u64,
    ) -> Result<(), RuntimeError> {
        program.push(&self.gpu, pipeline, entries, groups)
    }

    /// Exclusive scan of the first `len` words of `data`, in place, or (`from`) of `from` into
    /// `data`, zeroing `from`. Up to [`SCAN_SHORT_MAX`] words, blocks of 256 each scanned in
    /// one dispatch and given the sum of the totals before it in another (one block: one
    /// dispatch). Longer, reduce then scan, 2,048 words a workgroup: the blocks' totals
    /// (`scan_reduce`), then each block scanned from its prefix (`scan_apply`), which up to
    /// [`SCAN_PREFIX_MAX`] blocks adds up the totals before its own and past that reads them
    /// as `scan_totals`, one workgroup, scanned them in a dispatch between. (Short scans applied
    /// level by level are slower on long scans such as the compute renderer's: docs/performance.md, "Depth
    /// sort and the radix sort".)
    fn scan(
        &self,
        pass: &mut SortProgram,
        from: Option<&wgpu::Buffer>,
        data: &wgpu::Buffer,
        len: u64,
    ) -> Result<(), RuntimeError> {
        let short = len <= SCAN_SHORT_MAX;
        let blocks = len.div_ceil(if short { TILE } else { SCAN_BLOCK });
        let totals = self.buffer("scan totals", blocks);
        let scanned_totals = !short && blocks > SCAN_PREFIX_MAX;
        let p = self.params(len, u32::from(scanned_totals), blocks, 0, 0);
        let with_source: Option<Vec<(u32, &wgpu::Buffer)>> =
            from.map(|source| vec![(6, source), (4, data), (2, &totals), (5, &p)]);
        let in_place = vec![(4, data), (2, &totals), (5, &p)];
        if short {
            match &with_source {
                Some(entries) => self.dispatch(pass, &self.scan_blocks_from, entries, blocks)?,
                None => self.dispatch(pass, &self.scan_blocks, &in_place, blocks)?,
            }
            if blocks > 1 {
                self.dispatch(pass, &self.add_block_prefix, &in_place, blocks)?;
            }
            return Ok(());
        }
        match from {
            Some(source) => {
                let reduce = [(6, source), (2, &totals), (5, &p)];
                self.dispatch(pass, &self.scan_reduce_from, &reduce, blocks)?;
            }
            None => self.dispatch(pass, &self.scan_reduce, &in_place, blocks)?,
        }
        if scanned_totals {
            self.dispatch(pass, &self.scan_totals, &[(2, &totals), (5, &p)], 1)?;
        }
        match &with_source {
            Some(entries) => self.dispatch(pass, &self.scan_apply_from, entries, blocks),
            None => self.dispatch(pass, &self.scan_apply, &in_place, blocks),
        }
    }

    /// A program that replaces the first `len` words of `data` by their exclusive prefix sum
    /// (the scan the radix sort uses for its digit counts).
    pub fn scan_program(&self, data: &wgpu::Buffer, len: u64) -> Result<SortProgram, RuntimeError> {
        self.scan_program_from(None, data, len)
    }

    /// A program that writes the exclusive prefix sum of the first `len` words of `from` into
    /// `data` and zeroes them in `from` (counts scanned and cleared for the next counting, with
    /// no dispatch of their own to clear them); in place when `from` is `None`.
    pub(crate) fn scan_program_from(
        &self,
        from: Option<&wgpu::Buffer>,
        data: &wgpu::Buffer,
        len: u64,
    ) -> Result<SortProgram, RuntimeError> {
        let mut program = SortProgram::default();
        if len > 0 {
            self.scan(&mut program, from, data, len)?;
        }
        Ok(program)
    }

    /// A stable LSD radix sort of the first `n` pairs ordering only the low `key_bits` bits of
    /// the keys (8 bits a pass, an even number of passes so the result ends in `keys`/`vals`).
    pub(crate) fn radix_program(
        &self,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
        key_bits: u32,
    ) -> Result<SortProgram, RuntimeError> {
        let mut program = SortProgram::default();
        if n >= 2 {
            let passes = key_bits.clamp(1, 32).div_ceil(8).next_multiple_of(2);
            self.radix_passes(&mut program, keys, vals, n, passes)?;
        }
        Ok(program)
    }

    /// The depth sort's radix sort of the first `n` pairs: 32-bit depth keys (the effect's
    /// `depth_keys`) mapped to 16 bits over the live range `depth_range` (8 bytes: the smallest
    /// and largest live key, as depth_quantise.wgsl's `range_reduce` leaves them) as the first
    /// pass reads them, then two 8-bit passes. The keys end quantised, as
    /// `DepthQuantise`'s map would leave them; no pass of its own
    /// rewrites them first.
    pub fn depth_program(
        &self,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
        depth_range: &wgpu::Buffer,
    ) -> Result<SortProgram, RuntimeError> {
        let mut program = SortProgram::default();
        if n >= 1 {
            let passes = crate::sort::quantise::KEY_BITS.div_ceil(8);
            if let Some(sweep) = &self.sweep {
                sweep.record_passes(
                    &self.gpu,
                    &self.radix,
                    &mut program,
                    (keys, vals),
                    n,
                    PARTITION,
                    passes,
                    Some(depth_range),
                )?;
                return Ok(program);
            }
            // Even one key is mapped (the sort itself needs two): the keys always end quantised.
            let first = DepthPass {
                upsweep: self
                    .gpu
                    .compute_pipeline(&self.radix, "rs_upsweep_depth", None),
                downsweep: self
                    .gpu
                    .compute_pipeline(&self.radix, "rs_downsweep_depth", None),
                range: depth_range,
            };
            self.radix_passes_mapped(&mut program, keys, vals, n, passes, Some(first))?;
        }
        Ok(program)
    }

    /// Records `passes` 8-bit digit passes of the radix sort, from the lowest digit up: per
    /// pass, the digit counts of each partition, their scan, and the ranked scatter.
    fn radix_passes(
        &self,
        pass: &mut SortProgram,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
        passes: u32,
    ) -> Result<(), RuntimeError> {
        match &self.sweep {
            Some(sweep) => sweep.record_passes(
                &self.gpu,
                &self.radix,
                pass,
                (keys, vals),
                n,
                PARTITION,
                passes,
                None,
            ),
            None => self.radix_passes_mapped(pass, keys, vals, n, passes, None),
        }
    }

    /// [`Self::radix_passes`], the first pass reading its keys through `first`'s map when given.
    fn radix_passes_mapped(
        &self,
        pass: &mut SortProgram,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
        passes: u32,
        first: Option<DepthPass<'_>>,
    ) -> Result<(), RuntimeError> {
        let partitions = n.div_ceil(PARTITION);
        let (keys2, vals2) = (self.buffer("keys tmp", n), self.buffer("vals tmp", n));
        let counts = self.buffer("partition digit counts", 256 * partitions);
        let totals = self.buffer("digit totals", 256);
        for pass_index in 0..passes {
            let (ki, vi, ko, vo) = if pass_index % 2 == 0 {
                (keys, vals, &keys2, &vals2)
            } else {
                (&keys2, &vals2, keys, vals)
            };
            let p = self.uniform(&[n as u32, 8 * pass_index, partitions as u32, 0]);
            let mapped = first.as_ref().filter(|_| pass_index == 0);
            let (upsweep, downsweep) = match mapped {
                Some(depth) => (&depth.upsweep, &depth.downsweep),
                None => (&self.upsweep, &self.downsweep),
            };
            let mut up_entries = vec![(0, ki), (4, &counts), (5, &p)];
            up_entries.extend(mapped.map(|depth| (7, depth.range)));
            self.dispatch(pass, upsweep, &up_entries, partitions)?;
            if partitions <= SMALL_SCAN_PARTITIONS {
                self.dispatch(
                    pass,
                    &self.digit_scan_small,
                    &[(4, &counts), (5, &p), (6, &totals)],
                    1,
                )?;
            } else {
                self.dispatch(
                    pass,
                    &self.digit_scan,
                    &[(4, &counts), (5, &p), (6, &totals)],
                    256,
                )?;
            }
            let mut down_entries = vec![
                (0, ki),
                (1, vi),
                (2, ko),
                (3, vo),
                (4, &counts),
                (5, &p),
                (6, &totals),
            ];
            down_entries.extend(mapped.map(|depth| (7, depth.range)));
            self.dispatch(pass, downsweep, &down_entries, partitions)?;
        }
        Ok(())
    }

    /// Records a sort of the first `n` pairs of `keys`/`vals` into `pass`.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        algorithm: SortAlgorithm,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
    ) -> Result<(), RuntimeError> {
        self.program(algorithm, keys, vals, n)?.record(pass);
        Ok(())
    }

    /// Builds the dispatches (with their scratch buffers and bind groups) that sort the first
    /// `n` pairs of `keys`/`vals`, to be recorded as often as needed without new allocations.
    pub fn program(
        &self,
        algorithm: SortAlgorithm,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        n: u64,
    ) -> Result<SortProgram, RuntimeError> {
        let mut program = SortProgram::default();
        let pass = &mut program;
        if n < 2 {
            return Ok(program);
        }
        match algorithm {
            SortAlgorithm::Radix => self.radix_passes(pass, keys, vals, n, 4)?,
            SortAlgorithm::Bitonic => {
                // The network needs a power-of-two length: the caller's buffers are padded.
                let len = n.next_power_of_two();
                if keys.size() < len * 4 || vals.size() < len * 4 {
                    return Err(RuntimeError::Gpu(format!(
                        "bitonic sort needs buffers of {len} pairs"
                    )));
                }
                let mut k = 2;
                while k <= len {
                    let mut j = k / 2;
                    while j > 0 {
                        let p = self.params(len, 0, 0, j, k);
                        self.dispatch(
                            pass,
                            &self.bitonic,
                            &[(0, keys), (1, vals), (5, &p)],
                            len.div_ceil(TILE),
                        )?;
                        j /= 2;
                    }
                    k *= 2;
                }
            }
        }
        Ok(program)
    }
}

#[cfg(test)]
mod tests {
    use naga::valid::{Capabilities, ValidationFlags, Validator};

    use super::{radix_source, Ranking};

    /// Parses and validates `source` with naga, allowing subgroup operations; panics with
    /// naga's located message otherwise.
    fn validate(source: &str) {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
        Validator::new(
            ValidationFlags::all(),
            Capabilities::SUBGROUP | Capabilities::SUBGROUP_BARRIER,
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    }

    // Every radix module validates here, on any machine: CI's adapter (llvmpipe) has no
    // subgroups, so it runs only the portable ranking, and this catches a broken subgroup or
    // OneSweep module before an adapter that runs them does.
    #[test]
    fn every_radix_module_validates() {
        for ranking in [Ranking::Portable, Ranking::Subgroup, Ranking::OneSweep] {
            validate(&radix_source(ranking));
        }
    }
}
