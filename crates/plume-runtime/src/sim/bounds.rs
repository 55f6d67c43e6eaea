//! The box that holds an effect's live particles, measured on the GPU ([`Effect::live_bounds`]):
//! for a host's culling and for writing a file's `bounds` (`plume run --bounds`). One pass over
//! each particle buffer: every live slot with a finite position takes part, each workgroup
//! reduces its box in workgroup memory, and one thread a workgroup folds it into six global
//! atomics (each coordinate as an order-preserving u32, so integer min and max order the
//! floats). Only 24 bytes come back, whatever the capacity.
//!
//! [`Effect::live_bounds`]: crate::sim::effect::Effect::live_bounds

use plume_compiler::passes::layout::Attribute;

use crate::device::async_read::AsyncRead;
use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::device::readback::read_buffer;
use crate::device::resources::Chunk;
use crate::error::RuntimeError;

const BOUNDS_WGSL: &str = r#"
// One particle buffer's slots, word-major: the position in lanes x, y, z of 16-byte word 0,
// the id in lane `id_lane` of word `id_vec4` (0xffffffff: a free slot).
struct Part {
    len: u32,
    id_vec4: u32,
    id_lane: u32,
    pad: u32,
}

@group(0) @binding(0) var<storage, read> particles: array<vec4<u32>>;
// min x, y, z, then max x, y, z, as ordered keys.
@group(0) @binding(1) var<storage, read_write> box_keys: array<atomic<u32>, 6>;
@group(0) @binding(2) var<uniform> part: Part;

var<workgroup> group_keys: array<atomic<u32>, 6>;

// A float as a u32 whose unsigned order is the float's order.
fn ordered(bits: u32) -> u32 {
    return select(bits | 0x80000000u, ~bits, (bits & 0x80000000u) != 0u);
}

@compute @workgroup_size(256)
fn bounds(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
          @builtin(local_invocation_index) lane: u32) {
    if (lane < 3u) {
        atomicStore(&group_keys[lane], 0xffffffffu);
        atomicStore(&group_keys[lane + 3u], 0u);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < part.len) {
        let id = particles[part.id_vec4 * part.len + i][part.id_lane];
        let w = particles[i];
        let x = bitcast<vec3<f32>>(w.xyz);
        // Finite: not NaN (x == x) and not infinite (|x| <= the largest f32).
        let finite = all(x == x) && all(abs(x) <= vec3<f32>(3.4028235e38));
        if (id != 0xffffffffu && finite) {
            for (var k = 0u; k < 3u; k++) {
                let key = ordered(w[k]);
                atomicMin(&group_keys[k], key);
                atomicMax(&group_keys[k + 3u], key);
            }
        }
    }
    workgroupBarrier();
    if (lane < 3u) {
        let lo = atomicLoad(&group_keys[lane]);
        // A workgroup with no live particle leaves the box alone.
        if (lo != 0xffffffffu) {
            atomicMin(&box_keys[lane], lo);
            atomicMax(&box_keys[lane + 3u], atomicLoad(&group_keys[lane + 3u]));
        }
    }
}
"#;

/// A box that holds particles: its corners (m, in the effect's space), as
/// [`Effect::live_bounds`](crate::Effect::live_bounds) measures it.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::{Effect, Gpu};
/// let source = r#"Effect(name: "puff", capacity: 64,
///     emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 2.0, 0.0), radius: 0.5),
///                        velocity: Constant((1.0, 0.0, 0.0)))])"#;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut puff = Effect::from_source(&gpu, source, &Default::default())?;
/// puff.run(30, |_| {})?;
/// // Half a second at 1 m/s along x: the ball of radius 0.5 has moved 0.5 m.
/// let bounds = puff.live_bounds()?.expect("64 particles alive");
/// assert!(bounds.min[0] > -0.01 && bounds.max[0] < 1.01);
/// assert!(bounds.min[1] > 1.49 && bounds.max[1] < 2.51);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveBounds {
    /// The smallest x, y and z.
    pub min: [f32; 3],
    /// The largest x, y and z.
    pub max: [f32; 3],
}

impl LiveBounds {
    /// The smallest box holding both.
    pub fn union(self, other: LiveBounds) -> LiveBounds {
        LiveBounds {
            min: std::array::from_fn(|k| self.min[k].min(other.min[k])),
            max: std::array::from_fn(|k| self.max[k].max(other.max[k])),
        }
    }
}

/// The inverse of the kernel's `ordered`.
fn float_of(key: u32) -> f32 {
    f32::from_bits(if key & 0x8000_0000 != 0 {
        key & 0x7fff_ffff
    } else {
        !key
    })
}

/// The reduction over a fixed set of particle buffers: its pipeline, a bind group and grid
/// per buffer (made once: an effect's buffers never move), and its six-word result.
pub(crate) struct BoundsProbe {
    pipeline: wgpu::ComputePipeline,
    keys: wgpu::Buffer,
    /// The keys of an empty box, copied over `keys` before each watched reduction.
    empty: wgpu::Buffer,
    /// The watched reductions' box, read back without waiting.
    reading: AsyncRead,
    /// Per particle buffer: its bind group, its grid, and the uniform the group holds.
    parts: Vec<(wgpu::BindGroup, (u32, u32), wgpu::Buffer)>,
    gpu: Gpu,
}

impl BoundsProbe {
    /// The reduction over `buffers`: each group's layout and particle buffers.
    pub(crate) fn new(
        gpu: &Gpu,
        buffers: &[(&plume_compiler::Layout, &[Chunk])],
    ) -> Result<Self, RuntimeError> {
        let module = gpu.shader_module("live bounds", BOUNDS_WGSL);
        let pipeline = gpu.compute_pipeline(&module, "bounds", None);
        let keys = filled_buffer(gpu, "live bounds", 24, STORAGE, |_| {})?;
        let empty = filled_buffer(gpu, "empty bounds", 24, STORAGE, |b| {
            b.copy_from_slice(&empty_keys());
        })?;
        let mut parts = Vec::new();
        for (layout, chunks) in buffers {
            let id_word = layout
                .word_offset(Attribute::Id)
                .ok_or_else(|| RuntimeError::Gpu("the layout has no id".into()))?
                as u32;
            for chunk in *chunks {
                let words = [chunk.len as u32, id_word / 4, id_word % 4, 0];
                let part = filled_buffer(
                    gpu,
                    "live bounds part",
                    16,
                    wgpu::BufferUsages::UNIFORM,
                    |b| {
                        for (w, out) in words.iter().zip(b.chunks_exact_mut(4)) {
                            out.copy_from_slice(&w.to_le_bytes());
                        }
                    },
                )?;
                let group = gpu.bind_buffers(
                    "live bounds",
                    &pipeline.get_bind_group_layout(0),
                    &[(0, &chunk.buffer), (1, &keys), (2, &part)],
                );
                parts.push((group, gpu.grid(chunk.len, 256)?, part));
            }
        }
        Ok(Self {
            pipeline,
            keys,
            empty,
            reading: AsyncRead::new(gpu, "live bounds reading", 24),
            parts,
            gpu: gpu.clone(),
        })
    }

    /// Measures the buffers' live particles now: empties the box and runs the reduction over
    /// every buffer in one submission.
    pub(crate) fn measure(&self) -> Result<Option<LiveBounds>, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.record(&mut encoder);
        self.gpu.queue.submit([encoder.finish()]);
        Ok(decode(&read_buffer(&self.gpu, &self.keys)?))
    }

    /// Records the box emptied, then the reduction over every buffer, into `encoder`.
    fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        self.clear(encoder);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        self.dispatch(&mut pass);
    }

    /// Records the box emptied.
    fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.empty, 0, &self.keys, 0, 24);
    }

    /// Records the reduction over every buffer into `pass`.
    pub(crate) fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.pipeline);
        for (group, (x, y), _) in &self.parts {
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(*x, *y, 1);
        }
    }

    /// The first part of a watched reduction: the reading an earlier frame's reduction left,
    /// if it has come back, and whether a new reduction is to be recorded now (the last
    /// reading was taken), in which case the box is emptied in `encoder`.
    pub(crate) fn watch_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(BoundsWatch, bool), RuntimeError> {
        let taken = self.reading.poll()?;
        let now = self.reading.is_free();
        if now {
            self.clear(encoder);
        }
        let watch = match taken {
            Some(bytes) => BoundsWatch::Measured(decode(&bytes)),
            None => BoundsWatch::Waiting,
        };
        Ok((watch, now))
    }

    /// The last part of a watched reduction: its reading's copy, after the pass that reduced.
    pub(crate) fn watch_end(&self, encoder: &mut wgpu::CommandEncoder) {
        self.reading.record_copy(encoder, &self.keys);
    }
}

/// The six keys of an empty box (min at the largest key, max at the smallest).
fn empty_keys() -> Vec<u8> {
    [u32::MAX; 3]
        .into_iter()
        .chain([0; 3])
        .flat_map(u32::to_le_bytes)
        .collect()
}

/// The box the six keys in `bytes` hold: None when no live particle was seen.
fn decode(bytes: &[u8]) -> Option<LiveBounds> {
    let key = |k: usize| u32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
    if key(0) == u32::MAX && key(3) == 0 {
        return None;
    }
    let min = [float_of(key(0)), float_of(key(1)), float_of(key(2))];
    let max = [float_of(key(3)), float_of(key(4)), float_of(key(5))];
    Some(LiveBounds { min, max })
}

/// What `Effect::watch_live_bounds` knows this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundsWatch {
    /// No reading has come back since the last one.
    Waiting,
    /// The box of the live particles at a recent frame (None: none was alive).
    Measured(Option<LiveBounds>),
}

#[cfg(test)]
mod tests {
    use super::float_of;

    /// The kernel's `ordered`, on the CPU.
    fn ordered(bits: u32) -> u32 {
        if bits & 0x8000_0000 != 0 {
            !bits
        } else {
            bits | 0x8000_0000
        }
    }

    #[test]
    fn ordered_keys_order_floats_and_invert() {
        let xs = [-1e30f32, -2.5, -0.0, 0.0, 1e-30, 3.25, 7e37];
        for w in xs.windows(2) {
            assert!(ordered(w[0].to_bits()) <= ordered(w[1].to_bits()), "{w:?}");
        }
        for x in xs {
            assert_eq!(float_of(ordered(x.to_bits())).to_bits(), x.to_bits());
        }
    }
}
