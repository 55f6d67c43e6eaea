//! Small buffers every stage makes: one created filled ([`filled_buffer`], or with 32-bit
//! words: [`words_buffer`]), the staging copy
//! that carries per-call parameters inside the caller's encoder ([`staging`]), and the usage
//! set of a storage buffer that is also copied and read back ([`STORAGE`]).

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Usage of every storage buffer the runtime makes: kernels read and write it, readback copies
/// from it, and the draw's vertex shader reads it as read-only storage.
pub(crate) const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A buffer created mapped and filled by `fill`. Fails (rather than panics) when the device
/// cannot map it, as after a device loss, which it then reports.
pub(crate) fn filled_buffer(
    gpu: &Gpu,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
    fill: impl FnOnce(&mut [u8]),
) -> Result<wgpu::Buffer, RuntimeError> {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: true,
    });
    let mut bytes = vec![0u8; size as usize];
    fill(&mut bytes);
    match buffer.slice(..).get_mapped_range_mut() {
        Ok(mut range) => range.copy_from_slice(&bytes),
        Err(e) => {
            // A lost device is only reported once polled: poll, so the error says so.
            let _ = gpu.device.poll(wgpu::PollType::Poll);
            gpu.take_error()?;
            return Err(RuntimeError::Gpu(format!(
                "cannot fill the {label} buffer: {e}"
            )));
        }
    }
    buffer.unmap();
    Ok(buffer)
}

/// A buffer created holding `words` (little-endian), at least 16 bytes long.
pub(crate) fn words_buffer(
    gpu: &Gpu,
    label: &str,
    words: impl ExactSizeIterator<Item = u32>,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, RuntimeError> {
    let size = (words.len() as u64 * 4).max(16);
    filled_buffer(gpu, label, size, usage, |b| {
        for (chunk, word) in b.chunks_exact_mut(4).zip(words) {
            chunk.copy_from_slice(&word.to_le_bytes());
        }
    })
}

/// A small buffer holding `bytes`, to copy from inside an encoder: per-call parameters are
/// copied in the caller's encoder, in order, rather than written with `Queue::write_buffer`
/// (which would apply every write before any of the submission's commands run).
pub(crate) fn staging(gpu: &Gpu, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, RuntimeError> {
    filled_buffer(
        gpu,
        label,
        (bytes.len() as u64).next_multiple_of(4).max(4),
        wgpu::BufferUsages::COPY_SRC,
        |b| b[..bytes.len()].copy_from_slice(bytes),
    )
}
