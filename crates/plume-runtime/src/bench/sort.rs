//! `plume bench --sort-keys N`: the radix sort alone on N random (key, value) pairs, with each
//! ranking the adapter can run, on full 32-bit keys (4 passes) and on 16-bit keys (2 passes, the
//! precision a quantised depth key would have). Every timed sort starts from the same unsorted
//! input (copied in before the timed pass), and the last result of each is checked: keys in
//! order, and every value (the input position) present once with its own key.

use wgpu::util::DeviceExt;

use crate::bench::timer::{median_after_warmup, PassTimer};
use crate::device::gpu::Gpu;
use crate::device::readback::read_buffer;
use crate::error::RuntimeError;
use crate::sort::radix::{GpuSorter, Ranking};

/// One sort configuration's time.
#[derive(Clone, Debug)]
pub struct SortTime {
    /// The ranking it used.
    pub ranking: Ranking,
    /// Bits of key sorted (32: four 8-bit passes; 16: two).
    pub key_bits: u32,
    /// Median seconds per sort over the timed repeats.
    pub seconds: f64,
    /// Median seconds of the first stages (`first_stages`), timed by difference: (name,
    /// seconds).
    pub stages: [(&'static str, f64); 3],
}

/// The sort benchmark's result.
#[derive(Clone, Debug)]
pub struct SortBench {
    /// Pairs sorted.
    pub keys: u64,
    /// One entry per (ranking, key bits).
    pub times: Vec<SortTime>,
}

/// The stages a sort's first dispatches make, timed by difference: (name, dispatches up to
/// its end). Reduce-then-scan: the first pass's upsweep, digit scan and downsweep; OneSweep: the
/// counts of every pass (a clear and the histogram), their scan, the first pass.
pub(crate) fn first_stages(ranking: Ranking) -> [(&'static str, usize); 3] {
    match ranking {
        Ranking::OneSweep => [("histogram", 2), ("offsets", 3), ("first_sweep", 4)],
        Ranking::Subgroup | Ranking::Portable => {
            [("upsweep", 1), ("digit_scan", 2), ("downsweep", 3)]
        }
    }
}

/// Times the radix sort of `n` random pairs, `repeats` times each (the median is kept), with
/// every ranking `gpu` can run.
pub fn bench_sort(gpu: &Gpu, n: u64, repeats: u32) -> Result<SortBench, RuntimeError> {
    let keys: Vec<u32> = (0..n as u32)
        .map(|i| plume_compiler::rng::pcg(i ^ 0x5eed_5eed))
        .collect();
    let storage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let upload = |label, words: &[u32]| {
        gpu.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(words),
                usage: storage,
            })
    };
    let source_keys = upload("bench keys", &keys);
    let source_vals = upload("bench vals", &(0..n as u32).collect::<Vec<_>>());
    let work = |label| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: n * 4,
            usage: storage,
            mapped_at_creation: false,
        })
    };
    let (work_keys, work_vals) = (work("sorted keys"), work("sorted vals"));
    let timer = PassTimer::new(gpu);
    let mut times = Vec::new();
    for ranking in Ranking::runnable_on(gpu) {
        let sorter = GpuSorter::with_ranking(gpu, ranking)?;
        for key_bits in [32, 16] {
            let program = sorter.radix_program(&work_keys, &work_vals, n, key_bits)?;
            // Median time of the program's first `count` dispatches from the unsorted input.
            let time = |count: usize| -> Result<f64, RuntimeError> {
                median_after_warmup(repeats, || {
                    let mut encoder = gpu.device.create_command_encoder(&Default::default());
                    encoder.copy_buffer_to_buffer(&source_keys, 0, &work_keys, 0, n * 4);
                    encoder.copy_buffer_to_buffer(&source_vals, 0, &work_vals, 0, n * 4);
                    gpu.queue.submit([encoder.finish()]);
                    timer.time(|pass| {
                        program.record_first(pass, count);
                        Ok(())
                    })
                })
            };
            let stages = first_stages(ranking);
            let prefix = [time(stages[0].1)?, time(stages[1].1)?, time(stages[2].1)?];
            let seconds = time(usize::MAX)?;
            gpu.take_error()?;
            check_sorted(gpu, &keys, &work_keys, &work_vals, key_bits)?;
            times.push(SortTime {
                ranking,
                key_bits,
                seconds,
                stages: [
                    (stages[0].0, prefix[0]),
                    (stages[1].0, prefix[1] - prefix[0]),
                    (stages[2].0, prefix[2] - prefix[1]),
                ],
            });
        }
    }
    Ok(SortBench { keys: n, times })
}

/// Checks that the sorted buffers hold every input pair once, ordered by the low `key_bits`
/// bits of the key, stably (equal keys by input position).
fn check_sorted(
    gpu: &Gpu,
    input: &[u32],
    keys: &wgpu::Buffer,
    vals: &wgpu::Buffer,
    key_bits: u32,
) -> Result<(), RuntimeError> {
    let words = |b| -> Result<Vec<u32>, RuntimeError> {
        Ok(bytemuck::pod_collect_to_vec(&read_buffer(gpu, b)?))
    };
    let (keys, vals) = (words(keys)?, words(vals)?);
    let mask = if key_bits >= 32 {
        u32::MAX
    } else {
        (1 << key_bits) - 1
    };
    let mut seen = vec![false; input.len()];
    let mut last = (0u32, 0u32);
    for (i, (&k, &v)) in keys.iter().zip(&vals).enumerate() {
        let wrong = |what: &str| {
            RuntimeError::Gpu(format!(
                "the sort benchmark's output is wrong at {i} ({key_bits}-bit keys): {what}"
            ))
        };
        let Some(&original) = input.get(v as usize) else {
            return Err(wrong("a value out of range"));
        };
        if seen[v as usize] || original != k {
            return Err(wrong("a value twice, or with another key"));
        }
        seen[v as usize] = true;
        let here = (k & mask, v);
        if i > 0 && here < last {
            return Err(wrong("out of order"));
        }
        last = here;
    }
    Ok(())
}
