//! The sorts and scans of words from the CPU: upload, run, read back (for tests and the
//! benchmark's checks; the draw and the simulation record the programs into their own passes).

use wgpu::util::DeviceExt;

use crate::error::RuntimeError;
use crate::sort::radix::{GpuSorter, SortAlgorithm};

impl GpuSorter {
    /// Sorts `pairs` on the GPU and returns them sorted (for tests and the CPU side).
    pub fn sort_pairs(
        &self,
        algorithm: SortAlgorithm,
        keys: &[u32],
        vals: &[u32],
    ) -> Result<(Vec<u32>, Vec<u32>), RuntimeError> {
        let n = keys.len() as u64;
        let len = if algorithm == SortAlgorithm::Bitonic {
            n.next_power_of_two()
        } else {
            n
        };
        let mut k = keys.to_vec();
        let mut v = vals.to_vec();
        // Padding sorts last: the largest key, and values past every real one.
        k.resize(len as usize, u32::MAX);
        v.extend((n..len).map(|i| i as u32));
        let (kb, vb) = (self.upload("keys", &k), self.upload("vals", &v));
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record(&mut pass, algorithm, &kb, &vb, n)?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        Ok((self.read(&kb, n as usize)?, self.read(&vb, n as usize)?))
    }

    /// The exclusive prefix sum of `words` on the GPU: in place, or (`from_source`) of a source
    /// buffer into another, returning the source as the scan left it too (zeroed).
    pub fn scan_words(
        &self,
        words: &[u32],
        from_source: bool,
    ) -> Result<(Vec<u32>, Vec<u32>), RuntimeError> {
        let (data, source) = (
            self.upload("scanned", words),
            self.upload("scan source", words),
        );
        let program = match from_source {
            true => self.scan_program_from(Some(&source), &data, words.len() as u64)?,
            false => self.scan_program(&data, words.len() as u64)?,
        };
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        program.record(&mut encoder.begin_compute_pass(&Default::default()));
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        Ok((
            self.read(&data, words.len())?,
            self.read(&source, words.len())?,
        ))
    }

    /// A storage buffer holding `data` (one word when empty: a binding may not be empty).
    fn upload(&self, label: &str, data: &[u32]) -> wgpu::Buffer {
        let bytes: Vec<u8> = data.iter().flat_map(|w| w.to_le_bytes()).collect();
        self.gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if bytes.is_empty() { &[0; 4] } else { &bytes },
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// The first `n` words of `buffer`.
    fn read(&self, buffer: &wgpu::Buffer, n: usize) -> Result<Vec<u32>, RuntimeError> {
        let bytes = crate::device::readback::read_buffer(&self.gpu, buffer)?;
        Ok(bytes
            .chunks_exact(4)
            .take(n)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}
