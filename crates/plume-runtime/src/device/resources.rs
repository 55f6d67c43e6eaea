//! An effect's GPU resources: the buffers its compiled layout names, the compute module, and
//! one bind group per particle buffer. Particle state is split into chunks of at most one
//! storage binding each, so capacities past the binding limit (2 GiB on Vulkan) run; the free
//! list, counters and the other buffers are shared by every chunk.
//!
//! A stateless effect keeps no particle state: its `particles` binding is a *view* that only a
//! readback needs, so the view is allocated the first time something reads particles back, and
//! never for an effect that is only drawn.

use plume_compiler::passes::layout::Role;
use std::sync::OnceLock;

use plume_compiler::passes::layout::COUNTERS_BYTES;
use plume_compiler::CompiledEffect;

use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// Steps recorded per submission: bounds the parameter buffer (256 B a step) and how long
/// one submission keeps the GPU busy.
pub(crate) const STEPS_PER_SUBMIT: u32 = 256;

/// Steps one plan of a batch holds ([`crate::sim::batch`]): a batch's step parameters are a row
/// per instance, so its buffer holds fewer steps than an effect's.
pub(crate) const BATCH_STEPS: u32 = 8;

/// Bytes of the `params` binding: one step's parameters (a batch's: every instance's rows,
/// as the batch sized the binding).
pub(crate) fn params_binding_bytes(effect: &CompiledEffect) -> u64 {
    match effect.layout.batched {
        true => binding_bytes(effect, Role::Params),
        false => effect.layout.params_bytes(),
    }
}

/// Bytes of `effect`'s binding of `role` (0 when it has none).
pub(crate) fn binding_bytes(effect: &CompiledEffect, role: Role) -> u64 {
    effect.layout.binding_of(role).map_or(0, |b| b.bytes)
}

/// One particle buffer: global slots `base .. base + len`, and the compute bind group that
/// binds it (with every shared buffer).
pub(crate) struct Chunk {
    /// First global slot.
    pub base: u64,
    /// Slots held.
    pub len: u64,
    /// The particles (or, stateless, the view).
    pub buffer: wgpu::Buffer,
    /// The chunk's trail ring (`render.trail`): entry r of chunk slot i at i · (points − 1) + r.
    pub trail: Option<wgpu::Buffer>,
    /// Group 0 of the compute module, for this chunk.
    pub(crate) bind_group: wgpu::BindGroup,
}

/// The depth sort's buffers (for `sort: true`): one key and one slot per padded slot, and the
/// depth axis uniform the keys are measured along.
pub(crate) struct SortBuffers {
    /// Depth keys, farthest first after the sort; padding holds the largest key.
    pub keys: wgpu::Buffer,
    /// Slots, in draw order after the sort.
    pub vals: wgpu::Buffer,
    /// `DepthAxis` (16 bytes).
    pub depth_axis: wgpu::Buffer,
}

/// The buffers and bind groups of one effect on one device.
pub(crate) struct Resources {
    gpu: Gpu,
    /// Slots per particle buffer (all but the last).
    pub chunk_slots: u64,
    chunk_count: u64,
    chunks: OnceLock<Vec<Chunk>>,
    /// The stack of free slots (stateful effects).
    pub free_list: Option<wgpu::Buffer>,
    /// The counters (stateful effects).
    pub counters: Option<wgpu::Buffer>,
    /// The per-step parameters, [`STEPS_PER_SUBMIT`] slots of `params_stride` bytes (stateful).
    pub params: Option<wgpu::Buffer>,
    /// Bytes between two steps' parameters (the uniform offset alignment).
    pub params_stride: u64,
    /// Each chunk's `Chunk` uniform (base, len), one aligned entry per chunk.
    chunk_params: wgpu::Buffer,
    uniform_align: u64,
    /// The segment table of a stateless effect.
    pub frame: Option<wgpu::Buffer>,
    /// The depth sort's buffers.
    pub sort: Option<SortBuffers>,
    /// Buffers past the core bindings (7 up: flocking's and the baked field's), by binding.
    pub extra: Vec<(u32, wgpu::Buffer)>,
    /// The compiled compute module.
    pub module: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    /// The layout every compute pipeline of the module shares.
    pub pipeline_layout: wgpu::PipelineLayout,
}

/// Bytes between two steps' words in a firing stateless group's `fire_state`: the adapter's
/// storage offset alignment, so that each step's can be bound at a dynamic offset.
pub(crate) fn fire_state_stride(gpu: &Gpu) -> u64 {
    u64::from(gpu.limits.min_storage_buffer_offset_alignment).max(16)
}

fn sized(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset,
        size: wgpu::BufferSize::new(size),
    })
}

impl Resources {
    /// Allocates `effect`'s buffers on `gpu`, with at most `max_chunk_slots` particles per
    /// buffer when given (tests use it to exercise the split on small effects). `shared` holds
    /// buffers made elsewhere for some bindings (an effect graph's event buffers, which two
    /// groups bind); the others are allocated here.
    pub(crate) fn new(
        gpu: &Gpu,
        effect: &CompiledEffect,
        max_chunk_slots: Option<u64>,
        shared: &[(u32, wgpu::Buffer)],
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let cap = u64::from(effect.ir.capacity);
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size);
        let stateless = effect.layout.stateless();
        // The free list is one binding of 4 bytes a slot: that bounds the capacity.
        if !stateless && cap * 4 > limit {
            return Err(RuntimeError::CapacityTooLarge {
                capacity: effect.ir.capacity,
                bytes_per_particle: 4,
                bytes: cap * 4,
                limit,
                max_capacity: limit / 4,
            });
        }
        // A trail's ring is split with the particles, so both must fit a binding.
        let trail_bpp = u64::from(effect.layout.trail_bytes_per_particle);
        // The most slots whose buffer fits a binding (`Layout::buffer_bytes`: a half-motion
        // layout's last planes round up to whole vec4s), and whose trail ring does.
        let trail_slots = limit.checked_div(trail_bpp).unwrap_or(u64::MAX);
        let chunk_slots = effect
            .layout
            .slots_in(limit)
            .min(trail_slots)
            .min(max_chunk_slots.unwrap_or(u64::MAX))
            .max(1);
        let chunk_count = cap.div_ceil(chunk_slots);
        if effect.ir.flock.is_some() && chunk_count > 1 {
            return Err(RuntimeError::FlockTooLarge {
                capacity: effect.ir.capacity,
                max_capacity: chunk_slots,
            });
        }
        // Allocation failures (the driver's out-of-memory) are caught here and reported with
        // the sizes, instead of surfacing later as an invalid-buffer error.
        let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let frame = effect.ir.stateless.as_ref().map(|plan| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame"),
                size: plan.table_bytes(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let free_list = (!stateless).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("free_list"),
                size: cap * 4,
                usage: STORAGE,
                mapped_at_creation: false,
            })
        });
        // A batch's counters are an array, one per instance, filled by its `init`.
        let counters_bytes = match effect.layout.batched {
            true => binding_bytes(effect, Role::Counters),
            false => COUNTERS_BYTES,
        };
        let counters = (!stateless)
            .then(|| {
                filled_buffer(
                    gpu,
                    "counters",
                    counters_bytes.next_multiple_of(16),
                    STORAGE,
                    |bytes| {
                        bytes.fill(0);
                        bytes[..4].copy_from_slice(&effect.ir.capacity.to_le_bytes());
                    },
                )
            })
            .transpose()?;
        // A batch binds its step parameters as storage: offsets aligned for both kinds.
        let uniform_align = u64::from(gpu.limits.min_uniform_buffer_offset_alignment)
            .max(u64::from(gpu.limits.min_storage_buffer_offset_alignment))
            .max(16);
        let params_stride = params_binding_bytes(effect).next_multiple_of(uniform_align);
        let (params_steps, params_usage) = match effect.layout.batched {
            true => (BATCH_STEPS, wgpu::BufferUsages::STORAGE),
            false => (STEPS_PER_SUBMIT, wgpu::BufferUsages::UNIFORM),
        };
        let params = (!stateless).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("params"),
                size: params_stride * u64::from(params_steps),
                usage: params_usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let chunk_params = filled_buffer(
            gpu,
            "chunks",
            uniform_align * chunk_count,
            wgpu::BufferUsages::UNIFORM,
            |bytes| {
                for k in 0..chunk_count {
                    let (base, len) = (k * chunk_slots, chunk_slots.min(cap - k * chunk_slots));
                    let at = (k * uniform_align) as usize;
                    bytes[at..at + 4].copy_from_slice(&(base as u32).to_le_bytes());
                    bytes[at + 4..at + 8].copy_from_slice(&(len as u32).to_le_bytes());
                }
            },
        )?;
        // Sort keys and slots, padded to a power of two for the bitonic baseline; the padding
        // holds the largest key so it always sorts last.
        let sort = match effect.layout.sorts() {
            true => {
                let padded = cap.next_power_of_two();
                Some(SortBuffers {
                    keys: filled_buffer(gpu, "sort_keys", padded * 4, STORAGE, |b| b.fill(0xff))?,
                    vals: filled_buffer(gpu, "sort_vals", padded * 4, STORAGE, |b| {
                        for (j, w) in b.chunks_exact_mut(4).enumerate() {
                            w.copy_from_slice(&(j as u32).to_le_bytes());
                        }
                    })?,
                    depth_axis: device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("depth_axis"),
                        size: 16,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                })
            }
            false => None,
        };
        // The buffers past those made above (flocking's, the baked field's, the colliders'
        // data, ...), sized by the layout and shared by every chunk. Boids index slots
        // globally, so a flocking effect must fit in one particle buffer.
        let extra: Vec<(u32, wgpu::Buffer)> = effect
            .layout
            .bindings
            .iter()
            .filter(|b| !made_apart(b.role))
            .map(|b| {
                let size = match b.role {
                    // A step of the submission at each storage offset (`fire_state_stride`).
                    Role::FireState => {
                        plume_compiler::passes::stateless::FIRE_BATCH_STEPS * fire_state_stride(gpu)
                    }
                    _ => b.bytes.max(16),
                };
                if let Some((_, buffer)) = shared.iter().find(|(at, _)| *at == b.binding) {
                    return Ok((b.binding, buffer.clone()));
                }
                if b.role == Role::SpawnData {
                    // The mesh emitters' surfaces, written once here.
                    let data = plume_compiler::emitter::spawn_data(&effect.ir.emitters)
                        .unwrap_or_default();
                    let buffer = filled_buffer(gpu, b.name(), size, STORAGE, |bytes| {
                        for (dst, v) in bytes.chunks_exact_mut(4).zip(&data) {
                            dst.copy_from_slice(&v.to_le_bytes());
                        }
                    })?;
                    return Ok((b.binding, buffer));
                }
                let samples = match b.role {
                    // The height fields' samples and the mesh colliders' fields, written once here.
                    Role::ColliderData => {
                        Some(plume_compiler::colliders::data(&effect.ir.colliders))
                    }
                    // The vector field's, likewise.
                    Role::ForceData => plume_compiler::forces::force_data(&effect.ir.terms),
                    _ => None,
                };
                let buffer = if let Some(data) = samples {
                    filled_buffer(gpu, b.name(), size, STORAGE, |bytes| {
                        for (dst, h) in bytes.chunks_exact_mut(4).zip(&data) {
                            dst.copy_from_slice(&h.to_le_bytes());
                        }
                    })?
                } else {
                    let usage = match b.role {
                        // Written by Effect::set_scene_depth, read as a uniform.
                        Role::SceneCamera => {
                            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST
                        }
                        _ => STORAGE,
                    };
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(b.name()),
                        size,
                        usage,
                        mapped_at_creation: false,
                    })
                };
                Ok((b.binding, buffer))
            })
            .collect::<Result<_, RuntimeError>>()?;
        let module = gpu.shader_module(&effect.ir.name, &effect.wgsl);
        let layout = gpu.bind_group_layout("plume", &crate::device::bind_layout::entries(effect));
        let pipeline_layout = gpu.pipeline_layout("plume", &layout);
        let resources = Self {
            gpu: gpu.clone(),
            chunk_slots,
            chunk_count,
            chunks: OnceLock::new(),
            free_list,
            counters,
            params,
            params_stride,
            chunk_params,
            uniform_align,
            frame,
            sort,
            extra,
            module,
            layout,
            pipeline_layout,
        };
        // A stateful effect's particles are its state: allocate them now, so an out-of-memory
        // is reported when the effect is created.
        if !stateless {
            resources.chunks(effect)?;
        }
        if let Some(e) = pollster::block_on(out_of_memory.pop()) {
            let free_list_bytes = resources.free_list.as_ref().map_or(0, |b| b.size());
            return Err(RuntimeError::OutOfMemory {
                what: format!(
                    "{chunk_count} particle buffer(s) of up to {} bytes and a {free_list_bytes}-byte free list ({e})",
                    effect.layout.buffer_bytes(chunk_slots),
                ),
                bytes: effect.layout.buffer_bytes(cap) + free_list_bytes,
                bytes_per_particle: effect.layout.bytes_per_particle,
            });
        }
        Ok(resources)
    }

    /// Number of particle buffers the state (or the stateless view) is split into.
    pub(crate) fn chunk_count(&self) -> usize {
        self.chunk_count as usize
    }

    /// Whether the particle buffers exist yet (always for a stateful effect; for a stateless
    /// one, once something has read particles back).
    pub(crate) fn has_chunks(&self) -> bool {
        self.chunks.get().is_some()
    }

    /// The particle buffers with their bind groups, allocated on first use.
    pub(crate) fn chunks(&self, effect: &CompiledEffect) -> Result<&[Chunk], RuntimeError> {
        if let Some(c) = self.chunks.get() {
            return Ok(c);
        }
        let chunks = self.allocate_chunks(effect)?;
        Ok(self.chunks.get_or_init(|| chunks))
    }

    fn allocate_chunks(&self, effect: &CompiledEffect) -> Result<Vec<Chunk>, RuntimeError> {
        let device = &self.gpu.device;
        let cap = u64::from(effect.ir.capacity);
        let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let mut chunks = Vec::new();
        for k in 0..self.chunk_count {
            let base = k * self.chunk_slots;
            let len = self.chunk_slots.min(cap - base);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("particles"),
                size: effect.layout.buffer_bytes(len),
                usage: STORAGE,
                mapped_at_creation: false,
            });
            // Zeroed by wgpu: id + 1 = 0 marks an entry no particle has written.
            let trail_bpp = u64::from(effect.layout.trail_bytes_per_particle);
            let trail = (trail_bpp > 0).then(|| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("trail"),
                    size: len * trail_bpp,
                    usage: STORAGE,
                    mapped_at_creation: false,
                })
            });
            let bind_group = self.bind_group(effect, &buffer, trail.as_ref(), k);
            chunks.push(Chunk {
                base,
                len,
                buffer,
                trail,
                bind_group,
            });
        }
        if let Some(e) = pollster::block_on(out_of_memory.pop()) {
            let trail_bpp = u64::from(effect.layout.trail_bytes_per_particle);
            return Err(RuntimeError::OutOfMemory {
                what: format!(
                    "{} particle buffer(s) of up to {} bytes{} ({e})",
                    self.chunk_count,
                    effect.layout.buffer_bytes(self.chunk_slots),
                    if trail_bpp > 0 {
                        format!(
                            " and as many trail rings of up to {} bytes",
                            self.chunk_slots * trail_bpp
                        )
                    } else {
                        String::new()
                    }
                ),
                bytes: effect.layout.buffer_bytes(cap) + cap * trail_bpp,
                bytes_per_particle: effect.layout.bytes_per_particle,
            });
        }
        Ok(chunks)
    }

    /// Group 0 of the compute module with `particles` (and `trail`) bound to chunk `k`'s.
    fn bind_group(
        &self,
        effect: &CompiledEffect,
        particles: &wgpu::Buffer,
        trail: Option<&wgpu::Buffer>,
        k: u64,
    ) -> wgpu::BindGroup {
        let sort = self.sort.as_ref();
        let entries: Vec<wgpu::BindGroupEntry<'_>> = effect
            .layout
            .bindings
            .iter()
            .map(|b| wgpu::BindGroupEntry {
                binding: b.binding,
                resource: match b.role {
                    Role::Particles => particles.as_entire_binding(),
                    Role::Trail => trail
                        .expect("a layout with a trail gets trail rings")
                        .as_entire_binding(),
                    Role::FreeList => self
                        .free_list
                        .as_ref()
                        .expect("stateful")
                        .as_entire_binding(),
                    Role::Counters => self
                        .counters
                        .as_ref()
                        .expect("stateful")
                        .as_entire_binding(),
                    Role::Params => sized(
                        self.params.as_ref().expect("stateful"),
                        0,
                        params_binding_bytes(effect),
                    ),
                    Role::Chunk => sized(&self.chunk_params, k * self.uniform_align, 16),
                    // Bound at a dynamic offset: the step's (`fire_state_stride`).
                    Role::FireState => sized(
                        self.extra_buffer(b.binding).expect("a firing group's step"),
                        0,
                        b.bytes,
                    ),
                    Role::Frame => self.frame.as_ref().expect("stateless").as_entire_binding(),
                    Role::SortKeys => sort.expect("sorts").keys.as_entire_binding(),
                    Role::SortVals => sort.expect("sorts").vals.as_entire_binding(),
                    Role::DepthAxis => sort.expect("sorts").depth_axis.as_entire_binding(),
                    _ => self
                        .extra_buffer(b.binding)
                        .expect("every other binding is an extra buffer")
                        .as_entire_binding(),
                },
            })
            .collect();
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("plume"),
                layout: &self.layout,
                entries: &entries,
            })
    }

    /// Puts `buffer` in the place of the extra buffer at `binding` (one that grew: the scene
    /// depth's copy), rebuilding the chunks' bind groups.
    pub(crate) fn replace_extra(
        &mut self,
        effect: &CompiledEffect,
        binding: u32,
        buffer: wgpu::Buffer,
    ) {
        match self.extra.iter_mut().find(|(b, _)| *b == binding) {
            Some(slot) => slot.1 = buffer,
            None => self.extra.push((binding, buffer)),
        }
        if let Some(mut chunks) = self.chunks.take() {
            for (k, chunk) in chunks.iter_mut().enumerate() {
                chunk.bind_group =
                    self.bind_group(effect, &chunk.buffer, chunk.trail.as_ref(), k as u64);
            }
            let _ = self.chunks.set(chunks);
        }
    }

    /// The extra buffer at `binding` (flocking's or the baked field's).
    pub(crate) fn extra_buffer(&self, binding: u32) -> Option<&wgpu::Buffer> {
        self.extra
            .iter()
            .find(|(b, _)| *b == binding)
            .map(|(_, buffer)| buffer)
    }

    /// The extra buffer of the layout's binding of `role`.
    pub(crate) fn extra_of(&self, effect: &CompiledEffect, role: Role) -> Option<&wgpu::Buffer> {
        self.extra_buffer(effect.layout.binding_of(role)?.binding)
    }

    /// A compute pipeline of the module's entry point `entry`, on the shared layout.
    pub(crate) fn pipeline(&self, entry: &str) -> wgpu::ComputePipeline {
        self.gpu
            .compute_pipeline(&self.module, entry, Some(&self.pipeline_layout))
    }

    /// A compute pipeline of `entry` with a layout of only the bindings it uses, and a bind
    /// group for it from this effect's buffers: for kernels that run with no particle buffer
    /// bound (a stateless effect's depth keys).
    pub(crate) fn standalone(
        &self,
        effect: &CompiledEffect,
        entry: &str,
    ) -> (wgpu::ComputePipeline, wgpu::BindGroup) {
        let device = &self.gpu.device;
        let pipeline = self.gpu.compute_pipeline(&self.module, entry, None);
        let sort = self.sort.as_ref();
        let used = [Role::Frame, Role::SortKeys, Role::DepthAxis];
        let entries: Vec<wgpu::BindGroupEntry<'_>> = effect
            .layout
            .bindings
            .iter()
            .filter(|b| used.contains(&b.role))
            .map(|b| wgpu::BindGroupEntry {
                binding: b.binding,
                resource: match b.role {
                    Role::Frame => self.frame.as_ref().expect("stateless").as_entire_binding(),
                    Role::SortKeys => sort.expect("sorts").keys.as_entire_binding(),
                    _ => sort.expect("sorts").depth_axis.as_entire_binding(),
                },
            })
            .collect();
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(entry),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        (pipeline, group)
    }
}

/// Whether the buffer of a binding of `role` is one [`Resources`] makes in a field of its own
/// (the particles, the bookkeeping, the sort's, the trails), not among the extra buffers the
/// layout sizes.
fn made_apart(role: Role) -> bool {
    matches!(
        role,
        Role::Particles
            | Role::Frame
            | Role::FreeList
            | Role::Counters
            | Role::Params
            | Role::Chunk
            | Role::Trail
            | Role::SortKeys
            | Role::SortVals
            | Role::DepthAxis
    )
}
