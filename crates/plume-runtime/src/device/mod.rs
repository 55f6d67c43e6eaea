//! Device and resources: the GPU handle ([`gpu::Gpu`]: Plume's own device or a host's), a
//! group's buffers and compute module sized from its layout ([`resources`]), the small
//! buffers every stage makes ([`buffers`]: filled, staging), a depth texture copied into a
//! buffer ([`depth_copy`]), per-dispatch timestamps ([`dispatch_marks`]), a host's work timed without waiting
//! ([`gpu_timer`]), the modules and pipelines shared by everything on one device
//! ([`pipeline_cache`]), and copying buffers back to the
//! CPU with the decoding of particles and counters ([`readback`]).
//!
//! Imports nothing of the crate but [`crate::error`]: every other folder builds on it.

pub(crate) mod async_read;
pub(crate) mod bind_layout;
pub(crate) mod buffers;
pub(crate) mod depth_copy;
pub(crate) mod dispatch_marks;
pub(crate) mod gpu;
pub(crate) mod gpu_timer;
pub(crate) mod pipeline_cache;
pub(crate) mod readback;
pub(crate) mod resources;
