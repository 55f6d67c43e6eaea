//! Readback: copying GPU buffers to host memory, and decoding the particle buffers' bytes into
//! [`ParticleRecord`]s and the counters into [`Totals`]. Only `plume run --export`, the tests and
//! the measurements read particles back; drawing never does.

use glam::DVec3;
use plume_compiler::passes::layout::Attribute;
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::schedule::Schedule;
use plume_compiler::CompiledEffect;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Marks a free slot (the `id` field) and a particle that never dies.
pub(crate) const DEAD: u32 = u32::MAX;

/// Copies a GPU buffer to host memory (waits for the GPU).
pub fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RuntimeError> {
    let size = buffer.size();
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    submit_and_map(gpu, encoder, &staging, |data| data.to_vec())
}

/// Submits `encoder` (whose last command copies into `staging`, a `MAP_READ` buffer), waits
/// for the GPU, and returns what `read` makes of the mapped bytes.
fn submit_and_map<T>(
    gpu: &Gpu,
    encoder: wgpu::CommandEncoder,
    staging: &wgpu::Buffer,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T, RuntimeError> {
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|e| RuntimeError::Readback(e.to_string()))?
        .map_err(|e| RuntimeError::Readback(e.to_string()))?;
    let data = staging
        .get_mapped_range(..)
        .map_err(|e| RuntimeError::Readback(e.to_string()))?;
    let out = read(&data);
    drop(data);
    staging.unmap();
    Ok(out)
}

/// Reads a buffer of u32 words and returns the first `n`.
pub(crate) fn read_words(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    n: usize,
) -> Result<Vec<u32>, RuntimeError> {
    Ok(read_buffer(gpu, buffer)?
        .chunks_exact(4)
        .take(n)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// The totals from the counters' bytes (free count, spawn base, spawn count, spawned,
/// dropped, died): alive is the capacity less the free count.
pub(crate) fn decode_totals(counters: &[u8], capacity: u32, steps: u64) -> Totals {
    let word = |i: usize| {
        u64::from(u32::from_le_bytes([
            counters[4 * i],
            counters[4 * i + 1],
            counters[4 * i + 2],
            counters[4 * i + 3],
        ]))
    };
    Totals {
        steps,
        alive: u64::from(capacity) - word(0),
        spawned: word(3),
        dropped: word(4),
        died: word(5),
    }
}

/// Every slot's particle in the particle buffers' bytes, one entry of `buffers` per buffer in
/// slot order (None for a free slot), with velocity as the integrator knows it (Verlet's
/// displacement divided by h) and age and lifetime from the schedule. Each buffer holds its
/// slots word-major ([`plume_compiler::wgsl::word_index`]): 16-byte word k of its slot i at
/// k · slots + i.
pub(crate) fn decode_slots(
    effect: &CompiledEffect,
    schedule: &Schedule,
    buffers: &[Vec<u8>],
) -> Result<Vec<Option<ParticleRecord>>, RuntimeError> {
    let layout = &effect.layout;
    let stride = layout.bytes_per_particle as usize;
    let missing = |what| RuntimeError::Readback(format!("layout has no {what}"));
    let id_at = layout
        .word_offset(Attribute::Id)
        .ok_or_else(|| missing("id"))?;
    let pos_at = layout
        .word_offset(Attribute::Position)
        .ok_or_else(|| missing("position"))?;
    // Verlet stores the displacement over one substep: velocity is displacement / h.
    let (vel_at, scale) = match layout.word_offset(Attribute::Velocity) {
        Some(at) => (at, 1.0),
        None => (
            layout
                .word_offset(Attribute::Displacement)
                .ok_or_else(|| missing("velocity"))?,
            1.0 / effect.ir.h(),
        ),
    };
    let die_at = layout.word_offset(Attribute::DeathStep);
    // A particle that stores its spawn step ages from it; one of a group fed by events that
    // does not (`fed_ages_derived`) from its death step and the lifetime its id draws, as the
    // draw does; the others from the schedule, which gives the same for them.
    let born_at = layout.word_offset(Attribute::SpawnStep);
    let derived = (born_at.is_none() && !effect.ir.event_inputs.is_empty())
        .then(|| plume_compiler::passes::layout::shared_lifetime(&effect.ir))
        .flatten();
    let tint_at = layout.word_offset(Attribute::Tint);
    // The declared attributes' words, in layout order.
    let user_words: Vec<usize> = layout
        .attributes
        .iter()
        .filter(|a| matches!(a, Attribute::User { .. }))
        .flat_map(|a| {
            let at = layout.word_offset(*a).unwrap_or(0);
            at..at + a.fields().0.len()
        })
        .collect();
    let done = schedule.steps_done() as u32;
    let dt = effect.ir.dt;
    let total: usize = buffers.iter().map(|b| b.len()).sum();
    let mut out = Vec::with_capacity(total / stride.max(1));
    for (bytes, i, slots) in buffers.iter().flat_map(|b| {
        let slots = layout.slots_in(b.len() as u64);
        (0..slots).map(move |i| (b, i, slots))
    }) {
        // Stored word w of slot i, wherever its plane keeps it.
        let u = |w: usize| {
            let at = layout.word_byte(w, i, slots) as usize;
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        let f = |w: usize| f64::from(f32::from_bits(u(w)));
        // The two halves of a stored word (x in the low half).
        let halves = |w: usize| {
            let word = u(w);
            (
                f64::from(half::f16::from_bits(word as u16).to_f32()),
                f64::from(half::f16::from_bits((word >> 16) as u16).to_f32()),
            )
        };
        let velocity = if layout.half_motion {
            let ((x, y), (z, _)) = (halves(vel_at), halves(vel_at + 1));
            DVec3::new(x, y, z)
        } else {
            DVec3::new(f(vel_at), f(vel_at + 1), f(vel_at + 2))
        };
        let id = u(id_at);
        if id == DEAD {
            out.push(None);
            continue;
        }
        out.push(Some(ParticleRecord {
            id,
            position: DVec3::new(f(pos_at), f(pos_at + 1), f(pos_at + 2)),
            velocity: velocity * scale,
            age: match (born_at, derived, die_at) {
                (Some(b), _, _) => f64::from(done.wrapping_sub(u(b))) * dt,
                (None, Some(draw), Some(w)) => {
                    let (lived, _) = derived_steps(draw, effect.ir.seed_mix, id, u(w), done);
                    f64::from(lived) * dt
                }
                _ => schedule.age(id),
            },
            lifetime: die_at.and_then(|w| match (born_at, derived) {
                _ if u(w) == DEAD => None,
                (Some(b), _) => Some(f64::from(u(w).wrapping_sub(u(b)).wrapping_add(1)) * dt),
                (None, Some(draw)) => {
                    let (_, life) = derived_steps(draw, effect.ir.seed_mix, id, u(w), done);
                    Some(f64::from(life) * dt)
                }
                (None, None) => schedule.lifetime(id, u(w)),
            }),
            // A stored tint, or the one the draw derives from the id.
            tint: match tint_at {
                Some(t) => plume_compiler::tint::unpack(u(t)),
                None => plume_compiler::tint::own(effect.ir.tint(), id),
            },
            attributes: {
                let mut words = plume_compiler::attributes::Words::default();
                for (slot, &w) in words.iter_mut().zip(&user_words) {
                    *slot = f(w);
                }
                words
            },
        }));
    }
    Ok(out)
}

/// (Whole steps lived, whole steps of life) of particle `id`, dying in the update of step
/// `die_at`, after `done` steps, from the lifetime its id draws: the draw's `life_fraction`.
fn derived_steps(
    draw: plume_compiler::lifetime::LifetimeSteps,
    seed_mix: u32,
    id: u32,
    die_at: u32,
    done: u32,
) -> (u32, u32) {
    let life = draw.draw(plume_compiler::rng::rand_u32(
        seed_mix,
        id,
        plume_compiler::rng::stream::LIFETIME,
    ));
    // Steps still to live, the update of step `done` included; wraps like die_at.
    let left = die_at.wrapping_add(1).wrapping_sub(done);
    (life - left.min(life), life)
}

/// Reads an RGBA8 texture back as rows, top row first (waits for the GPU).
pub fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, RuntimeError> {
    let device = &gpu.device;
    let row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("frame readback"),
        size: u64::from(row) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    // Rows are padded to the copy alignment; the image keeps only each row's pixels.
    submit_and_map(gpu, encoder, &readback, |data| {
        let mut pixels = Vec::with_capacity((width * height * 4) as usize);
        for y in 0..height as usize {
            let start = y * row as usize;
            pixels.extend_from_slice(&data[start..start + width as usize * 4]);
        }
        pixels
    })
}
