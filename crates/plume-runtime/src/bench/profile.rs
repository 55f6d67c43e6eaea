//! `plume bench --profile`: one timed batch of steps run again with a GPU timestamp after
//! every dispatch (`device::dispatch_marks`), for where a step's time goes.

pub use crate::device::dispatch_marks::DispatchTime;

use crate::device::dispatch_marks;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Runs `time` (a timed batch of `steps` steps) with this thread's marks collected, and
/// returns each dispatch's time a step. An adapter without timestamps inside passes is an
/// error that says so.
pub(crate) fn profiled(
    gpu: &Gpu,
    steps: u32,
    time: impl FnOnce() -> Result<f64, RuntimeError>,
) -> Result<Vec<DispatchTime>, RuntimeError> {
    if !dispatch_marks::supported(gpu) {
        return Err(RuntimeError::Output(format!(
            "--profile needs timestamps inside compute passes (TIMESTAMP_QUERY_INSIDE_PASSES), which {} does not offer",
            gpu.describe()
        )));
    }
    dispatch_marks::begin(gpu);
    let timed = time();
    // Closed whether or not the batch ran, so no later pass writes marks.
    let times = dispatch_marks::finish(gpu, steps);
    timed?;
    times
}
