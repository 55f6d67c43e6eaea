//! A few bytes of a buffer read back without waiting on the GPU: the copy is recorded into a
//! frame's encoder, mapped once the host has submitted that encoder (the next frame asks), and
//! read a frame or more later when the mapping is done. For what a renderer or a host learns
//! from the GPU every frame (how many tile entries the compute renderer needed, the live particles' box),
//! where `read_buffer`'s wait would stall the frame.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Free: the next frame may copy into it.
const IDLE: u8 = 0;
/// A copy is recorded (in an encoder the host submits before the next frame).
const COPIED: u8 = 1;
/// Mapping asked for.
const MAPPING: u8 = 2;
/// Mapped: the bytes can be taken.
const MAPPED: u8 = 3;

/// A mappable buffer of `len` bytes and where its reading stands.
pub(crate) struct AsyncRead {
    buffer: wgpu::Buffer,
    len: u64,
    /// IDLE, COPIED, MAPPING or MAPPED (the map callback sets the last).
    state: Arc<AtomicU8>,
}

impl AsyncRead {
    /// A reading of `len` bytes.
    pub(crate) fn new(gpu: &Gpu, label: &str, len: u64) -> Self {
        Self {
            buffer: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: len,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            len,
            state: Arc::new(AtomicU8::new(IDLE)),
        }
    }

    /// Call once a frame before [`Self::record_copy`]: asks for the mapping of the copy an
    /// earlier frame recorded (its encoder has been submitted since), and returns the bytes
    /// of a finished mapping, once each.
    pub(crate) fn poll(&self) -> Result<Option<Vec<u8>>, RuntimeError> {
        match self.state.load(Ordering::Acquire) {
            COPIED => {
                self.state.store(MAPPING, Ordering::Release);
                let state = self.state.clone();
                self.buffer
                    .slice(..)
                    .map_async(wgpu::MapMode::Read, move |result| {
                        // A failed mapping (a lost device) lets the next frame copy again.
                        let next = if result.is_ok() { MAPPED } else { IDLE };
                        state.store(next, Ordering::Release);
                    });
                Ok(None)
            }
            MAPPED => {
                let bytes = self
                    .buffer
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| RuntimeError::Readback(e.to_string()))?
                    .to_vec();
                self.buffer.unmap();
                self.state.store(IDLE, Ordering::Release);
                Ok(Some(bytes))
            }
            _ => Ok(None),
        }
    }

    /// Whether a new copy may be recorded now (the last reading was taken).
    pub(crate) fn is_free(&self) -> bool {
        self.state.load(Ordering::Acquire) == IDLE
    }

    /// Records the copies of `parts` (each a buffer and how many of its first bytes), one after
    /// another, into `encoder` when the last reading was taken; whether it did.
    pub(crate) fn record_copies(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[(&wgpu::Buffer, u64)],
    ) -> bool {
        if !self.is_free() {
            return false;
        }
        let mut at = 0;
        for (source, len) in parts {
            encoder.copy_buffer_to_buffer(source, 0, &self.buffer, at, *len);
            at += len;
        }
        debug_assert!(at <= self.len);
        self.state.store(COPIED, Ordering::Release);
        true
    }

    /// Records the copy of `source`'s first bytes into `encoder` when the last reading was
    /// taken; whether it did.
    pub(crate) fn record_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Buffer,
    ) -> bool {
        if !self.is_free() {
            return false;
        }
        encoder.copy_buffer_to_buffer(source, 0, &self.buffer, 0, self.len);
        self.state.store(COPIED, Ordering::Release);
        true
    }
}
