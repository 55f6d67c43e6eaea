//! Per-dispatch GPU times (`plume bench --profile`): while a collection is open on this
//! thread, the recording code writes a timestamp into the compute pass after each dispatch
//! ([`mark`], labelled) and at the start of each step's work ([`boundary`]); [`finish`]
//! resolves them into each label's time since the mark before it. A thread-local collection
//! (like a tracing span) keeps the recording functions' signatures as they are: with none
//! open, a mark is one thread-local check. Each timestamp also costs the GPU a few
//! microseconds (docs/performance.md, "Events"), so the times are relative:
//! they show where a step's time goes, not what it costs without them.

// Only the benchmarks (feature `tools`) open a collection; without them every mark is a no-op.
#![cfg_attr(not(feature = "tools"), allow(dead_code))]

use std::cell::RefCell;

use crate::device::gpu::Gpu;
use crate::device::readback::read_buffer;
use crate::error::RuntimeError;

/// The most timestamps one collection takes (wgpu's limit for a query set); a submission that
/// records more is an error (`finish`), not a profile that silently misses its last steps.
const MOST_MARKS: u32 = 4096;

/// One kind of dispatch's time in a profiled submission of steps: what `plume bench --profile`
/// prints, and what a host reads from [`crate::bench::BenchResult::dispatches`]:
///
/// ```no_run
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::bench::{bench, BenchOptions};
/// let gpu = plume_runtime::Gpu::new(&Default::default())?;
/// let effect = plume_compiler::parse(&std::fs::read_to_string("effects/fountain.ron")?)
///     .map_err(|d| format!("{d:?}"))?;
/// let options = BenchOptions {
///     profile: true,
///     ..BenchOptions::new(1_000_000, 50)
/// };
/// for d in bench(&gpu, &effect, &options)?.dispatches {
///     println!("{:<20} {:6.1} µs a step", d.label, d.us_per_step);
/// }
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DispatchTime {
    /// The kernel, prefixed by its scope (`s0.` event stream 0, `g1.` group 1).
    pub label: String,
    /// Microseconds a step, timestamp included.
    pub us_per_step: f64,
    /// How many of them a step records.
    pub per_step: f64,
}

struct Collection {
    set: wgpu::QuerySet,
    /// Each timestamp's label; None for a boundary.
    labels: Vec<Option<String>>,
    /// Marks past [`MOST_MARKS`], not written.
    dropped: usize,
    prefix: String,
}

thread_local! {
    static OPEN: RefCell<Option<Collection>> = const { RefCell::new(None) };
}

/// Whether `gpu` can take timestamps inside a compute pass.
pub(crate) fn supported(gpu: &Gpu) -> bool {
    gpu.device
        .features()
        .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
}

/// Opens a collection on this thread (replacing any open one).
pub(crate) fn begin(gpu: &Gpu) {
    let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("dispatch marks"),
        ty: wgpu::QueryType::Timestamp,
        count: MOST_MARKS,
    });
    OPEN.with(|o| {
        *o.borrow_mut() = Some(Collection {
            set,
            labels: Vec::new(),
            dropped: 0,
            prefix: String::new(),
        })
    });
}

fn write(pass: &mut wgpu::ComputePass<'_>, label: Option<&str>) {
    OPEN.with(|o| {
        if let Some(c) = o.borrow_mut().as_mut() {
            let at = c.labels.len() as u32;
            if at < MOST_MARKS {
                pass.write_timestamp(&c.set, at);
                let label = label.map(|l| format!("{}{l}", c.prefix));
                c.labels.push(label);
            } else {
                c.dropped += 1;
            }
        }
    });
}

/// A timestamp after the work recorded so far, which is `label`'s.
pub(crate) fn mark(pass: &mut wgpu::ComputePass<'_>, label: &str) {
    write(pass, Some(label));
}

/// A timestamp that starts the next label's time (the work before it is no label's).
pub(crate) fn boundary(pass: &mut wgpu::ComputePass<'_>) {
    write(pass, None);
}

/// What the next labels start with: `kind`, `index` and a dot (`s0.`: event stream 0).
/// Formats nothing unless a collection is open.
pub(crate) fn scope(kind: char, index: usize) {
    OPEN.with(|o| {
        if let Some(c) = o.borrow_mut().as_mut() {
            c.prefix = format!("{kind}{index}.");
        }
    });
}

/// Closes this thread's collection after its work was submitted, and returns each label's
/// time a step over `steps` steps, in the order the labels first appear.
pub(crate) fn finish(gpu: &Gpu, steps: u32) -> Result<Vec<DispatchTime>, RuntimeError> {
    let Some(c) = OPEN.with(|o| o.borrow_mut().take()) else {
        return Ok(Vec::new());
    };
    if c.dropped > 0 {
        return Err(RuntimeError::Output(format!(
            "the profiled steps recorded {} dispatches, more than the {MOST_MARKS} timestamps a profile takes",
            c.labels.len() + c.dropped
        )));
    }
    let n = c.labels.len() as u64;
    if n < 2 {
        return Ok(Vec::new());
    }
    let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("dispatch marks"),
        size: n * 8,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.resolve_query_set(&c.set, 0..n as u32, &resolve, 0);
    gpu.queue.submit([encoder.finish()]);
    let ticks: Vec<u64> = read_buffer(gpu, &resolve)?
        .chunks_exact(8)
        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    let us_per_tick = f64::from(gpu.queue.get_timestamp_period()) * 1e-3;
    let steps = f64::from(steps.max(1));
    let mut out: Vec<DispatchTime> = Vec::new();
    for (i, label) in c.labels.iter().enumerate().skip(1) {
        let Some(label) = label else { continue };
        let us = ticks[i].saturating_sub(ticks[i - 1]) as f64 * us_per_tick / steps;
        match out.iter_mut().find(|d| d.label == *label) {
            Some(d) => {
                d.us_per_step += us;
                d.per_step += 1.0 / steps;
            }
            None => out.push(DispatchTime {
                label: label.clone(),
                us_per_step: us,
                per_step: 1.0 / steps,
            }),
        }
    }
    Ok(out)
}
