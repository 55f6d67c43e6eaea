//! Runtime errors: each says what went wrong and, where it can, what to do.

/// Why running an effect failed.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// An effect file could not be read ([`crate::Effect::from_file`]).
    #[error("{path}: error: cannot read file: {message}")]
    Read {
        /// The path as given.
        path: String,
        /// The system's message.
        message: String,
    },
    /// The effect does not compile: its diagnostics, rendered against the file or source
    /// ([`crate::Effect::from_file`], [`crate::Effect::from_source`]).
    #[error("{0}")]
    Compile(String),
    /// No adapter with compute shaders was found.
    #[error("no GPU adapter with compute shaders found (backends tried: {backends}).\n  \
             Without a GPU, install a software driver: Debian/Ubuntu `apt-get install mesa-vulkan-drivers` \
             (lavapipe, Vulkan) or `apt-get install libegl1 libgl1-mesa-dri` (llvmpipe, OpenGL), \
             then run again (choose one with --backend vulkan|gl or WGPU_BACKEND)")]
    NoAdapter {
        /// The backends that were searched.
        backends: String,
    },
    /// The adapter refused to create a device.
    #[error("the adapter {adapter} could not open a device: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// The free list (one binding, 4 bytes a slot) does not fit on this adapter. Particle
    /// state itself is split across bindings; the free list is not.
    #[error("capacity {capacity} needs a {bytes}-byte free list ({bytes_per_particle} bytes per slot, one binding), but this adapter's max_storage_buffer_binding_size is {limit} bytes: at most {max_capacity} particles fit; lower capacity or use an adapter with larger bindings")]
    CapacityTooLarge {
        /// Requested capacity.
        capacity: u32,
        /// Bytes per particle of the layout.
        bytes_per_particle: u32,
        /// Bytes the particle buffer would need.
        bytes: u64,
        /// The adapter's limit.
        limit: u64,
        /// The largest capacity that fits.
        max_capacity: u64,
    },
    /// The device was lost (driver reset, GPU removed, or destroyed); nothing more can run on it.
    #[error("the GPU device ({adapter}) was lost ({reason}); results from this run are incomplete and nothing was written. Run again; if it repeats, the driver is resetting the GPU (check the system log) or try another adapter (--backend)")]
    DeviceLost {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason and message.
        reason: String,
    },
    /// A GPU allocation failed for lack of memory.
    #[error("the GPU ran out of memory allocating {what} ({bytes} bytes); lower capacity (the particle state takes {bytes_per_particle} bytes a slot) or free GPU memory")]
    OutOfMemory {
        /// What was being allocated.
        what: String,
        /// Its size.
        bytes: u64,
        /// Bytes per particle slot of the layout.
        bytes_per_particle: u32,
    },
    /// A flocking effect's particle state does not fit in one storage binding.
    #[error("capacity {capacity} is too large for a flocking effect on this adapter: boids must fit in one storage binding, at most {max_capacity} here; lower capacity")]
    FlockTooLarge {
        /// Requested capacity.
        capacity: u32,
        /// The most that fit.
        max_capacity: u64,
    },
    /// The adapter lacks a capability the work needs; the message says which and what to use.
    #[error("{0}")]
    Unsupported(String),
    /// wgpu reported a validation or out-of-memory error.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// Reading results back from the GPU failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// A control from the host was refused (a burst or a parameter the effect cannot take,
    /// [`crate::Effect::burst`]); the message says why and what the effect offers.
    #[error("{0}")]
    Control(String),
    /// Writing an output file failed.
    #[error("{0}")]
    Output(String),
}
