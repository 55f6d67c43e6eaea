//! The IR of a stateless effect: what the state pass (`stages::passes::stateless`) decided
//! about evaluating its particles from their ids and ages, and the sizes of the segment
//! tables the runtime keeps for it.

/// Most segments the table holds: 65,536 × 32 bytes = 2 MiB of bookkeeping, whatever the
/// particle count.
pub(crate) const MAX_SEGMENTS: u64 = 65_536;

/// Bytes of one segment entry (two `vec4<u32>`).
pub const SEGMENT_BYTES: u64 = 32;

/// Bytes of the segment table's header (one `vec4<u32>`).
pub const FRAME_HEADER_BYTES: u64 = 16;

/// How a stateless effect is evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct StatelessIr {
    /// Per emitter, the most steps one of its particles lives (None: it never dies).
    pub lives: Vec<Option<u32>>,
    /// Most segments that can hold live particles at once (sizes the table).
    pub max_segments: u64,
    /// Most particles alive at once, an upper bound (no more than the capacity).
    pub peak: u64,
}

impl StatelessIr {
    /// Bytes of the segment table binding.
    pub fn table_bytes(&self) -> u64 {
        FRAME_HEADER_BYTES + SEGMENT_BYTES * self.max_segments.max(1)
    }

    /// Bytes of a firing group's `fire_frame`: the segments that may hold live particles at any
    /// step of a batch of up to [`FIRE_BATCH_STEPS`] steps (those live at its start, and those
    /// its steps spawn: one an emitter a step).
    pub fn fire_table_bytes(&self) -> u64 {
        self.table_bytes() + SEGMENT_BYTES * FIRE_BATCH_STEPS * self.lives.len().max(1) as u64
    }
}

/// The most steps a firing stateless group's batch (one `fire_frame`) covers: the runtime
/// records steps in batches of at most this many.
pub const FIRE_BATCH_STEPS: u64 = 256;
