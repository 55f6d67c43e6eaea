//! `plume bench --profile`: one timed submission of steps run again with a GPU timestamp after
//! every dispatch (`device::dispatch_marks`), for where a step's time goes.

pub use crate::device::dispatch_marks::DispatchTime;

use crate::device::dispatch_marks;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Steps a profile times at most: a step's share of each dispatch needs few, and a graph's
/// few dozen dispatches a step stay well inside the timestamps one profile takes.
const PROFILE_STEPS: u32 = 16;

/// Runs `time(n)` (a timed submission of n steps: `steps`, at most [`PROFILE_STEPS`]) with this
/// thread's marks collected, and returns each dispatch's time a step. An adapter without
/// timestamps inside passes is an error that says so.
pub(crate) fn profiled(
    gpu: &Gpu,
    steps: u32,
    time: impl FnOnce(u32) -> Result<f64, RuntimeError>,
) -> Result<Vec<DispatchTime>, RuntimeError> {
    let steps = steps.clamp(1, PROFILE_STEPS);
    if !dispatch_marks::supported(gpu) {
        return Err(RuntimeError::Output(format!(
            "--profile needs timestamps inside compute passes (TIMESTAMP_QUERY_INSIDE_PASSES), which {} does not offer",
            gpu.describe()
        )));
    }
    dispatch_marks::begin(gpu);
    let timed = time(steps);
    // Closed whether or not the submission ran, so no later pass writes marks.
    let times = dispatch_marks::finish(gpu, steps);
    timed?;
    times
}
