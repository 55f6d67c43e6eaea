//! A compiled effect running on the GPU. Buffers hold only the layout's attributes; spawning
//! pops slots from a GPU free list (never a readback per step); many steps are recorded into one
//! submission, their per-step parameters in one uniform buffer addressed by dynamic offsets.

use std::borrow::Cow;
use std::cell::Cell;

use glam::DVec3;
use plume_compiler::passes::layout::{Attribute, COUNTERS_BYTES};
use plume_compiler::passes::stateless::{FRAME_HEADER_BYTES, SEGMENT_BYTES};
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_compiler::schedule::{LiveSegments, Schedule, StepPlan};
use plume_compiler::wgsl::WORKGROUP;
use plume_compiler::CompiledEffect;

use crate::error::RuntimeError;
use crate::gpu::Gpu;
use crate::sort::{GpuSorter, SortAlgorithm};
use crate::timer::PassTimer;

/// Steps recorded per submission: bounds the parameter buffer (256 B a step) and how long
/// one submission keeps the GPU busy.
pub const STEPS_PER_SUBMIT: u32 = 256;

/// Marks a free slot (the `id` field) and a particle that never dies.
const DEAD: u32 = u32::MAX;

/// One particle buffer: global slots `base .. base + len`, and the bind group that binds it.
struct Chunk {
    len: u64,
    buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// An effect's GPU state and kernels. Particle state is split into chunks of at most one
/// storage binding each, so capacities past the binding limit (2 GiB on Vulkan) run; the free
/// list and counters are shared.
pub struct GpuSim<'g> {
    gpu: &'g Gpu,
    effect: CompiledEffect,
    schedule: Schedule,
    chunks: Vec<Chunk>,
    counters: wgpu::Buffer,
    params: wgpu::Buffer,
    params_stride: u64,
    kernels: Kernels,
    sort: Option<SortStage<'g>>,
    flock: Option<FlockStage>,
    /// The baked field's `bake` kernel, its node count, and whether it runs every step.
    bake: Option<(wgpu::ComputePipeline, u64, bool)>,
}

/// The kernels that advance an effect: the stateful spawn and update, or the stateless
/// evaluate with its bookkeeping.
enum Kernels {
    Stateful {
        prepare: wgpu::ComputePipeline,
        spawn: wgpu::ComputePipeline,
        update: wgpu::ComputePipeline,
    },
    Stateless(StatelessStage),
}

/// A stateless effect's `evaluate` kernel and its bookkeeping: steps only advance the schedule
/// and the live segments; the view is computed when it is read.
struct StatelessStage {
    evaluate: wgpu::ComputePipeline,
    /// The segment table (binding 1), written before each evaluation.
    frame: wgpu::Buffer,
    segments: LiveSegments,
    /// Steps done when the view was last evaluated.
    evaluated_at: Cell<Option<u64>>,
}

/// The per-step flocking pass of an effect with a Flock force: snapshot (+ partial sums),
/// global means, then all pairs or the grid (bucket keys, their sort, bucket ranges, search).
struct FlockStage {
    snapshot: wgpu::ComputePipeline,
    reduce: Option<wgpu::ComputePipeline>,
    neighbours: wgpu::ComputePipeline,
    grid: Option<GridStage>,
    /// The buffers (bindings 7 up), kept for the bind group's lifetime and for tests.
    buffers: Vec<(u32, wgpu::Buffer)>,
}

/// The uniform grid's extra kernels and its (bucket, slot) sort.
struct GridStage {
    bucket: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    ranges: wgpu::ComputePipeline,
    buckets: u64,
    sort: crate::sort::SortProgram,
}

/// The sort stage of an effect with `sort: true`: one key and one slot per (padded) slot.
struct SortStage<'g> {
    keys: wgpu::Buffer,
    vals: wgpu::Buffer,
    depth_keys: wgpu::ComputePipeline,
    /// Built once with the stage: every frame's sort reuses its pipelines.
    sorter: GpuSorter<'g>,
}

fn buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    dynamic: bool,
    min: Option<u64>,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: min.and_then(wgpu::BufferSize::new),
        },
        count: None,
    }
}

fn sized(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset,
        size: wgpu::BufferSize::new(size),
    })
}

impl<'g> GpuSim<'g> {
    /// Allocates buffers and builds the kernels of `effect` on `gpu`.
    pub fn new(gpu: &'g Gpu, effect: CompiledEffect) -> Result<Self, RuntimeError> {
        Self::with_chunk_slots(gpu, effect, None)
    }

    /// Like [`GpuSim::new`] with at most `max_chunk_slots` particles per buffer (tests use it
    /// to exercise the split on small effects).
    pub fn with_chunk_slots(
        gpu: &'g Gpu,
        effect: CompiledEffect,
        max_chunk_slots: Option<u64>,
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let cap = u64::from(effect.ir.capacity);
        let bpp = u64::from(effect.layout.bytes_per_particle);
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
        let chunk_slots = (limit / bpp)
            .min(max_chunk_slots.unwrap_or(u64::MAX))
            .max(1);
        let chunk_count = cap.div_ceil(chunk_slots);
        let storage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        // Allocation failures (the driver's out-of-memory) are caught here and reported with
        // the sizes, instead of surfacing later as an invalid-buffer error.
        let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        // A stateless effect has a segment table and no free list (nor any other per-particle
        // state); a stateful one the reverse.
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
                usage: storage,
                mapped_at_creation: false,
            })
        });
        let counters = filled_buffer(
            device,
            "counters",
            COUNTERS_BYTES.next_multiple_of(16),
            storage,
            |bytes| {
                bytes.fill(0);
                bytes[..4].copy_from_slice(&effect.ir.capacity.to_le_bytes());
            },
        );
        let align = u64::from(gpu.limits.min_uniform_buffer_offset_alignment).max(16);
        let params_stride = effect.layout.params_bytes().next_multiple_of(align);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: params_stride * u64::from(STEPS_PER_SUBMIT),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let chunk_params = filled_buffer(
            device,
            "chunks",
            align * chunk_count,
            wgpu::BufferUsages::UNIFORM,
            |bytes| {
                for k in 0..chunk_count {
                    let (base, len) = (k * chunk_slots, chunk_slots.min(cap - k * chunk_slots));
                    let at = (k * align) as usize;
                    bytes[at..at + 4].copy_from_slice(&(base as u32).to_le_bytes());
                    bytes[at + 4..at + 8].copy_from_slice(&(len as u32).to_le_bytes());
                }
            },
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&effect.ir.name),
            source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(&effect.wgsl)),
        });
        let rw = wgpu::BufferBindingType::Storage { read_only: false };
        // One entry per binding of the compiled layout, typed by what it holds.
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("plume"),
            entries: &effect
                .layout
                .bindings
                .iter()
                .map(|b| match b.name {
                    "params" => buffer_entry(
                        b.binding,
                        wgpu::BufferBindingType::Uniform,
                        true,
                        Some(effect.layout.params_bytes()),
                    ),
                    "chunk" => {
                        buffer_entry(b.binding, wgpu::BufferBindingType::Uniform, false, Some(16))
                    }
                    "frame" => buffer_entry(
                        b.binding,
                        wgpu::BufferBindingType::Storage { read_only: true },
                        false,
                        None,
                    ),
                    _ => buffer_entry(b.binding, rw, false, None),
                })
                .collect::<Vec<_>>(),
        });
        // Sort keys and slots, padded to a power of two for the bitonic baseline; the padding
        // holds the largest key so it always sorts last.
        let sort_buffers = effect.layout.sorts().then(|| {
            let padded = cap.next_power_of_two();
            let keys = filled_buffer(device, "sort_keys", padded * 4, storage, |b| b.fill(0xff));
            let vals = filled_buffer(device, "sort_vals", padded * 4, storage, |b| {
                for (j, w) in b.chunks_exact_mut(4).enumerate() {
                    w.copy_from_slice(&(j as u32).to_le_bytes());
                }
            });
            (keys, vals)
        });
        // The buffers past the core bindings (7 up: flocking's and the baked field's), sized by
        // the layout and shared by every chunk. Boids index slots globally, so a flocking
        // effect must fit in one particle buffer.
        let extra_buffers: Vec<(u32, wgpu::Buffer)> = effect
            .layout
            .bindings
            .iter()
            .filter(|b| b.binding >= 7)
            .map(|b| {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(b.name),
                    size: b.bytes.max(16),
                    usage: storage,
                    mapped_at_creation: false,
                });
                (b.binding, buffer)
            })
            .collect();
        if effect.ir.flock.is_some() && chunk_count > 1 {
            return Err(RuntimeError::FlockTooLarge {
                capacity: effect.ir.capacity,
                max_capacity: chunk_slots,
            });
        }
        let mut chunks = Vec::new();
        for k in 0..chunk_count {
            let len = chunk_slots.min(cap - k * chunk_slots);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("particles"),
                size: len * bpp,
                usage: storage,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("plume"),
                layout: &layout,
                entries: &effect
                    .layout
                    .bindings
                    .iter()
                    .map(|b| wgpu::BindGroupEntry {
                        binding: b.binding,
                        resource: match b.name {
                            "particles" => buffer.as_entire_binding(),
                            "free_list" => {
                                free_list.as_ref().expect("stateful").as_entire_binding()
                            }
                            "counters" => counters.as_entire_binding(),
                            "params" => sized(&params, 0, effect.layout.params_bytes()),
                            "chunk" => sized(&chunk_params, k * align, 16),
                            "frame" => frame.as_ref().expect("stateless").as_entire_binding(),
                            "sort_keys" => {
                                sort_buffers.as_ref().expect("sorts").0.as_entire_binding()
                            }
                            "sort_vals" => {
                                sort_buffers.as_ref().expect("sorts").1.as_entire_binding()
                            }
                            _ => extra_buffers
                                .iter()
                                .find(|(binding, _)| *binding == b.binding)
                                .map(|(_, buffer)| buffer.as_entire_binding())
                                .expect("every other binding is an extra buffer"),
                        },
                    })
                    .collect::<Vec<_>>(),
            });
            chunks.push(Chunk {
                len,
                buffer,
                bind_group,
            });
        }
        if let Some(e) = pollster::block_on(out_of_memory.pop()) {
            let free_list_bytes = free_list.as_ref().map_or(0, |b| b.size());
            return Err(RuntimeError::OutOfMemory {
                what: format!(
                    "{chunk_count} particle buffer(s) of up to {} bytes and a {free_list_bytes}-byte free list ({e})",
                    chunk_slots * bpp,
                ),
                bytes: cap * bpp + free_list_bytes,
                bytes_per_particle: effect.layout.bytes_per_particle,
            });
        }
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("plume"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let flock = match &effect.ir.flock {
            Some(f) => {
                let grid = match f.neighbors {
                    plume_compiler::forces::flock::Neighbors::Grid { .. } => {
                        let find = |name: &str| {
                            let binding = effect
                                .layout
                                .bindings
                                .iter()
                                .find(|b| b.name == name)
                                .map(|b| b.binding);
                            extra_buffers
                                .iter()
                                .find(|(b, _)| Some(*b) == binding)
                                .map(|(_, buffer)| buffer)
                                .expect("the layout binds the grid's buffers")
                        };
                        let sorter = GpuSorter::new(gpu);
                        Some(GridStage {
                            bucket: pipeline("grid_bucket"),
                            clear: pipeline("grid_clear"),
                            ranges: pipeline("grid_ranges"),
                            buckets: plume_compiler::forces::flock::FlockIr::grid_buckets(
                                effect.ir.capacity,
                            ),
                            sort: sorter.program(
                                SortAlgorithm::Radix,
                                find("grid_keys"),
                                find("grid_vals"),
                                cap,
                            )?,
                        })
                    }
                    plume_compiler::forces::flock::Neighbors::AllPairs => None,
                };
                Some(FlockStage {
                    snapshot: pipeline("flock_snapshot"),
                    reduce: (f.scope == plume_compiler::forces::flock::Scope::Global)
                        .then(|| pipeline("flock_reduce")),
                    neighbours: pipeline(if grid.is_some() {
                        "flock_grid"
                    } else {
                        "flock_pairs"
                    }),
                    grid,
                    buffers: extra_buffers,
                })
            }
            None => None,
        };
        let bake = effect.ir.field.as_ref().map(|f| {
            (
                pipeline("bake"),
                f.nodes(),
                f.refresh == plume_compiler::field::Refresh::EveryStep,
            )
        });
        let sim = Self {
            gpu,
            flock,
            bake,
            schedule: Schedule::new(&effect.ir),
            kernels: match &effect.ir.stateless {
                Some(plan) => Kernels::Stateless(StatelessStage {
                    evaluate: pipeline(if stateless_stores_staged(gpu) {
                        "evaluate"
                    } else {
                        "evaluate_direct"
                    }),
                    frame: frame.expect("a stateless layout binds a frame"),
                    segments: LiveSegments::new(plan.lives.clone()),
                    evaluated_at: Cell::new(None),
                }),
                None => Kernels::Stateful {
                    prepare: pipeline("spawn_prepare"),
                    spawn: pipeline("spawn"),
                    update: pipeline("update"),
                },
            },
            sort: sort_buffers.map(|(keys, vals)| SortStage {
                keys,
                vals,
                depth_keys: pipeline("depth_keys"),
                sorter: GpuSorter::new(gpu),
            }),
            effect,
            chunks,
            counters,
            params,
            params_stride,
        };
        if stateless {
            gpu.take_error()?;
            return Ok(sim);
        }
        // Mark every slot free and fill the free list, on the GPU: no host copy of the state.
        let init = pipeline("init");
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&init);
            for chunk in &sim.chunks {
                let (x, y) = sim.groups(chunk.len)?;
                sim.bind(&mut pass, chunk, 0);
                pass.dispatch_workgroups(x, y, 1);
            }
            // A field baked once is baked here, at time 0 (the params buffer starts zeroed).
            if let Some((bake, nodes, false)) = &sim.bake {
                let (x, y) = sim.groups(*nodes)?;
                sim.bind(&mut pass, &sim.chunks[0], 0);
                pass.set_pipeline(bake);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.take_error()?;
        Ok(sim)
    }

    /// Binds `chunk`'s group; `offset` is the step's parameters (stateful effects only: a
    /// stateless one binds no per-step parameters).
    fn bind(&self, pass: &mut wgpu::ComputePass<'_>, chunk: &Chunk, offset: u32) {
        match self.kernels {
            Kernels::Stateful { .. } => pass.set_bind_group(0, &chunk.bind_group, &[offset]),
            Kernels::Stateless(_) => pass.set_bind_group(0, &chunk.bind_group, &[]),
        }
    }

    /// Records the depth keys of every slot and their sort into `pass`.
    fn record_sort(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        algorithm: SortAlgorithm,
    ) -> Result<(), RuntimeError> {
        let stage = self.sort.as_ref().ok_or_else(|| {
            RuntimeError::Output("this effect has no sort stage (sort: false)".into())
        })?;
        pass.set_pipeline(&stage.depth_keys);
        for chunk in &self.chunks {
            let (x, y) = self.groups(chunk.len)?;
            self.bind(pass, chunk, 0);
            pass.dispatch_workgroups(x, y, 1);
        }
        stage.sorter.record(
            pass,
            algorithm,
            &stage.keys,
            &stage.vals,
            u64::from(self.effect.ir.capacity),
        )
    }

    /// Sorts every slot by view depth on the GPU (farthest first, free slots last) and returns
    /// the live slots in draw order, each with its key.
    pub fn draw_order(&self, algorithm: SortAlgorithm) -> Result<Vec<(u32, u32)>, RuntimeError> {
        self.evaluate_view()?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_sort(&mut pass, algorithm)?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        let alive = self.totals()?.alive as usize;
        let stage = self.sort.as_ref().expect("checked by record_sort");
        let words = |b: &wgpu::Buffer| -> Result<Vec<u32>, RuntimeError> {
            Ok(self
                .read(b)?
                .chunks_exact(4)
                .take(alive)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        };
        let (keys, slots) = (words(&stage.keys)?, words(&stage.vals)?);
        Ok(slots.into_iter().zip(keys).collect())
    }

    /// Times the depth keys and the sort of every slot in one pass (seconds).
    pub fn time_sort(
        &self,
        timer: &PassTimer<'_>,
        algorithm: SortAlgorithm,
    ) -> Result<f64, RuntimeError> {
        self.evaluate_view()?;
        let seconds = timer.time(|pass| self.record_sort(pass, algorithm))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// The live particles in draw order: sorted by depth on the GPU, farthest first; equal
    /// depths by id, so the order is the same run after run.
    pub fn records_in_draw_order(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let order = self.draw_order(SortAlgorithm::Radix)?;
        let by_slot = self.records_by_slot()?;
        let mut out: Vec<(u32, ParticleRecord)> = Vec::with_capacity(order.len());
        for (slot, key) in order {
            let record = by_slot
                .get(slot as usize)
                .copied()
                .flatten()
                .ok_or_else(|| {
                    RuntimeError::Readback(format!("sorted slot {slot} holds no live particle"))
                })?;
            out.push((key, record));
        }
        // Stable: equal keys (equal depths) by id.
        out.sort_by_key(|(key, r)| (*key, r.id));
        Ok(out.into_iter().map(|(_, r)| r).collect())
    }

    /// Number of particle buffers the state is split into.
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }

    /// The compiled effect being run.
    pub fn effect(&self) -> &CompiledEffect {
        &self.effect
    }

    /// The spawn schedule (steps done, ids requested, ages).
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Runs `steps` steps, [`STEPS_PER_SUBMIT`] per submission, calling `progress(done)` after
    /// each submission is recorded. Returns when the GPU has finished.
    pub fn run(&mut self, steps: u64, mut progress: impl FnMut(u64)) -> Result<(), RuntimeError> {
        let mut done = 0;
        if let Kernels::Stateless(stage) = &mut self.kernels {
            // Stateless: a step is bookkeeping only; the view is computed when it is read.
            while done < steps {
                let n = (steps - done).min(1 << 16);
                stage.segments.advance(&mut self.schedule, n);
                done += n;
                progress(done);
            }
            return Ok(());
        }
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let plans: Vec<StepPlan> = (0..n).map(|_| self.schedule.next_plan()).collect();
            self.submit(&plans)?;
            done += n;
            progress(done);
        }
        self.gpu.wait()
    }

    fn submit(&self, plans: &[StepPlan]) -> Result<(), RuntimeError> {
        self.write_params(plans);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("steps"),
                timestamp_writes: None,
            });
            self.record(&mut pass, plans)?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()
    }

    /// Writes the steps' parameters at their dynamic offsets.
    fn write_params(&self, plans: &[StepPlan]) {
        let slots = self.effect.layout.emitter_slots as usize;
        let mut bytes = vec![0u8; self.params_stride as usize * plans.len()];
        for (j, plan) in plans.iter().enumerate() {
            let at = j * self.params_stride as usize;
            let mut words: Vec<u32> = vec![
                plan.first_id,
                plan.requested(),
                plan.kernel_time().to_bits(),
                plan.step as u32,
            ];
            for e in 0..slots {
                let (count, k0) = plan.emitters.get(e).copied().unwrap_or((0, 0));
                words.extend([count, k0, 0, 0]);
            }
            for (w, chunk) in words.iter().zip(bytes[at..].chunks_exact_mut(4)) {
                chunk.copy_from_slice(&w.to_le_bytes());
            }
        }
        self.gpu.queue.write_buffer(&self.params, 0, &bytes);
    }

    /// Records the steps' dispatches into `pass`: per step, the spawn kernels when something
    /// spawns (a step that requests nothing changes no counter), then the update per chunk.
    fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        plans: &[StepPlan],
    ) -> Result<(), RuntimeError> {
        let Kernels::Stateful {
            prepare,
            spawn,
            update,
        } = &self.kernels
        else {
            return Err(RuntimeError::Gpu(
                "a stateless effect records no steps".into(),
            ));
        };
        for (j, plan) in plans.iter().enumerate() {
            let offset = (j as u64 * self.params_stride) as u32;
            // A field baked every step is baked first: the spawn (Verlet's start) samples it too.
            if let Some((bake, nodes, true)) = &self.bake {
                let (x, y) = self.groups(*nodes)?;
                self.bind(pass, &self.chunks[0], offset);
                pass.set_pipeline(bake);
                pass.dispatch_workgroups(x, y, 1);
            }
            if plan.requested() > 0 {
                self.bind(pass, &self.chunks[0], offset);
                pass.set_pipeline(prepare);
                pass.dispatch_workgroups(1, 1, 1);
                // Every chunk sees every spawn; each writes only the slots it holds.
                let (x, y) = self.groups(u64::from(plan.requested()))?;
                pass.set_pipeline(spawn);
                for chunk in &self.chunks {
                    self.bind(pass, chunk, offset);
                    pass.dispatch_workgroups(x, y, 1);
                }
            }
            if let Some(flock) = &self.flock {
                self.record_flock(pass, flock, offset)?;
            }
            pass.set_pipeline(update);
            for chunk in &self.chunks {
                let (x, y) = self.groups(chunk.len)?;
                self.bind(pass, chunk, offset);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        Ok(())
    }

    /// Records one step's flocking pass (single chunk): snapshot, means, neighbour search.
    fn record_flock(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        flock: &FlockStage,
        offset: u32,
    ) -> Result<(), RuntimeError> {
        let chunk = &self.chunks[0];
        let (x, y) = self.groups(chunk.len)?;
        self.bind(pass, chunk, offset);
        pass.set_pipeline(&flock.snapshot);
        pass.dispatch_workgroups(x, y, 1);
        if let Some(reduce) = &flock.reduce {
            pass.set_pipeline(reduce);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if let Some(grid) = &flock.grid {
            pass.set_pipeline(&grid.bucket);
            pass.dispatch_workgroups(x, y, 1);
            grid.sort.record(pass);
            self.bind(pass, chunk, offset);
            let (bx, by) = self.groups(grid.buckets)?;
            pass.set_pipeline(&grid.clear);
            pass.dispatch_workgroups(bx, by, 1);
            pass.set_pipeline(&grid.ranges);
            pass.dispatch_workgroups(x, y, 1);
        }
        pass.set_pipeline(&flock.neighbours);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    /// Reads a flocking buffer back by its layout name (`boids`, `flock_out`, ...), for tests.
    pub fn read_flock_buffer(&self, name: &str) -> Result<Vec<u8>, RuntimeError> {
        let binding = self
            .effect
            .layout
            .bindings
            .iter()
            .find(|b| b.name == name)
            .map(|b| b.binding);
        let buffer = self
            .flock
            .as_ref()
            .and_then(|f| f.buffers.iter().find(|(b, _)| Some(*b) == binding))
            .map(|(_, buffer)| buffer)
            .ok_or_else(|| RuntimeError::Output(format!("this effect has no buffer {name}")))?;
        read_buffer(self.gpu, buffer)
    }

    /// Whether the effect runs stateless (one `evaluate` per frame read, no state kept).
    pub fn is_stateless(&self) -> bool {
        matches!(self.kernels, Kernels::Stateless(_))
    }

    /// Writes the segment table of the steps done into the frame buffer.
    fn write_frame(&self, stage: &StatelessStage) -> Result<(), RuntimeError> {
        let done = stage.segments.steps_done();
        let count = stage.segments.len() as u64;
        if FRAME_HEADER_BYTES + count * SEGMENT_BYTES > stage.frame.size() {
            return Err(RuntimeError::Gpu(format!(
                "{count} live spawn segments overflow the stateless table (a bug in the compiler's bound)"
            )));
        }
        let mut words: Vec<u32> = vec![0, count as u32, done as u32, 0];
        let mut threads = 0u64;
        let dt = self.effect.ir.dt;
        for seg in stage.segments.iter() {
            let age = done - seg.step;
            let tau = (age as f64 * dt) as f32;
            words.extend([
                threads as u32,
                seg.first_id,
                seg.k_base,
                seg.emitter as u32,
                age.min(u64::from(u32::MAX)) as u32,
                seg.step as u32,
                tau.to_bits(),
                0,
            ]);
            threads += u64::from(seg.count);
        }
        if threads > u64::from(self.effect.ir.capacity) {
            return Err(RuntimeError::Gpu(format!(
                "{threads} stateless particles exceed the capacity {} (a bug in the compiler's bound)",
                self.effect.ir.capacity
            )));
        }
        words[0] = threads as u32;
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        self.gpu.queue.write_buffer(&stage.frame, 0, &bytes);
        Ok(())
    }

    /// Records one evaluation of the whole view into `pass`.
    fn record_evaluate(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        stage: &StatelessStage,
    ) -> Result<(), RuntimeError> {
        pass.set_pipeline(&stage.evaluate);
        for chunk in &self.chunks {
            let (x, y) = self.groups(chunk.len)?;
            self.bind(pass, chunk, 0);
            pass.dispatch_workgroups(x, y, 1);
        }
        Ok(())
    }

    /// A stateless effect: computes the view at the steps done, unless it already holds them.
    /// A stateful effect: nothing to do.
    fn evaluate_view(&self) -> Result<(), RuntimeError> {
        let Kernels::Stateless(stage) = &self.kernels else {
            return Ok(());
        };
        let done = stage.segments.steps_done();
        if stage.evaluated_at.get() == Some(done) {
            return Ok(());
        }
        self.write_frame(stage)?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_evaluate(&mut pass, stage)?;
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        stage.evaluated_at.set(Some(done));
        Ok(())
    }

    /// Runs `steps` (at most [`STEPS_PER_SUBMIT`]) in one timed compute pass; returns seconds.
    /// A stateless effect advances its bookkeeping by `steps` and times as many evaluations of
    /// the view (each one what a frame costs), so the two are compared per step drawn.
    pub fn time_steps(&mut self, timer: &PassTimer<'_>, steps: u32) -> Result<f64, RuntimeError> {
        let steps = steps.min(STEPS_PER_SUBMIT);
        if self.is_stateless() {
            self.run(u64::from(steps), |_| {})?;
            let Kernels::Stateless(stage) = &self.kernels else {
                unreachable!("checked above");
            };
            self.write_frame(stage)?;
            let seconds = timer.time(|pass| {
                for _ in 0..steps {
                    self.record_evaluate(pass, stage)?;
                }
                Ok(())
            })?;
            self.gpu.take_error()?;
            stage.evaluated_at.set(Some(stage.segments.steps_done()));
            return Ok(seconds);
        }
        let plans: Vec<StepPlan> = (0..steps).map(|_| self.schedule.next_plan()).collect();
        self.write_params(&plans);
        let seconds = timer.time(|pass| self.record(pass, &plans))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }

    /// A 2D grid of workgroups covering `threads` (one dimension is capped at 65,535 groups).
    fn groups(&self, threads: u64) -> Result<(u32, u32), RuntimeError> {
        let per_dim = u64::from(self.gpu.limits.max_compute_workgroups_per_dimension);
        let groups = threads.div_ceil(u64::from(WORKGROUP)).max(1);
        let x = groups.min(per_dim);
        let y = groups.div_ceil(x);
        if y > per_dim {
            return Err(RuntimeError::Gpu(format!(
                "{threads} threads need more than {per_dim} x {per_dim} workgroups"
            )));
        }
        Ok((x as u32, y as u32))
    }

    /// Copies a buffer to host memory.
    fn read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RuntimeError> {
        read_buffer(self.gpu, buffer)
    }

    /// Steps done and the GPU's counters: alive, spawned, died, dropped. A stateless effect
    /// drops nothing and counts from its bookkeeping (the kernels' own lifetime draw).
    pub fn totals(&self) -> Result<Totals, RuntimeError> {
        if let Kernels::Stateless(stage) = &self.kernels {
            let spawned = u64::from(self.schedule.ids_requested());
            let alive = stage.segments.alive(&self.effect.ir);
            return Ok(Totals {
                steps: self.schedule.steps_done(),
                alive,
                spawned,
                died: spawned - alive,
                dropped: 0,
            });
        }
        let c = self.read(&self.counters)?;
        let word = |i: usize| {
            u64::from(u32::from_le_bytes([
                c[4 * i],
                c[4 * i + 1],
                c[4 * i + 2],
                c[4 * i + 3],
            ]))
        };
        Ok(Totals {
            steps: self.schedule.steps_done(),
            alive: u64::from(self.effect.ir.capacity) - word(0),
            spawned: word(3),
            dropped: word(4),
            died: word(5),
        })
    }

    /// The live particles in id order, velocity as the integrator knows it (Verlet's derived).
    pub fn records(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let mut out: Vec<ParticleRecord> = self.records_by_slot()?.into_iter().flatten().collect();
        out.sort_by_key(|r| r.id);
        Ok(out)
    }

    /// Every slot's particle (None for a free slot).
    fn records_by_slot(&self) -> Result<Vec<Option<ParticleRecord>>, RuntimeError> {
        self.evaluate_view()?;
        let mut bytes = Vec::new();
        for chunk in &self.chunks {
            bytes.extend(self.read(&chunk.buffer)?);
        }
        let layout = &self.effect.layout;
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
                1.0 / self.effect.ir.h(),
            ),
        };
        let die_at = layout.word_offset(Attribute::DeathStep);
        let mut out = Vec::new();
        for slot in bytes.chunks_exact(stride) {
            let u = |w: usize| {
                u32::from_le_bytes([
                    slot[4 * w],
                    slot[4 * w + 1],
                    slot[4 * w + 2],
                    slot[4 * w + 3],
                ])
            };
            let f = |w: usize| f64::from(f32::from_bits(u(w)));
            let id = u(id_at);
            if id == DEAD {
                out.push(None);
                continue;
            }
            out.push(Some(ParticleRecord {
                id,
                position: DVec3::new(f(pos_at), f(pos_at + 1), f(pos_at + 2)),
                velocity: DVec3::new(f(vel_at), f(vel_at + 1), f(vel_at + 2)) * scale,
                age: self.schedule.age(id),
                lifetime: die_at.and_then(|w| self.schedule.lifetime(id, u(w))),
            }));
        }
        Ok(out)
    }
}

/// Whether the stateless view is written through workgroup memory (`evaluate`, coalesced
/// stores) or by each thread (`evaluate_direct`): staged on GPUs, direct on CPU adapters, where
/// a workgroup barrier costs more than the stores. `PLUME_STATELESS_STORES=staged|direct`
/// overrides the choice, for measuring both.
pub fn stateless_stores_staged(gpu: &Gpu) -> bool {
    match std::env::var("PLUME_STATELESS_STORES").as_deref() {
        Ok("staged") => true,
        Ok("direct") => false,
        _ => gpu.adapter.get_info().device_type != wgpu::DeviceType::Cpu,
    }
}

/// A buffer created mapped and filled by `fill`.
fn filled_buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
    fill: impl FnOnce(&mut [u8]),
) -> wgpu::Buffer {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: true,
    });
    let mut bytes = vec![0u8; size as usize];
    fill(&mut bytes);
    buffer
        .slice(..)
        .get_mapped_range_mut()
        .expect("a buffer created with mapped_at_creation is mapped")
        .copy_from_slice(&bytes);
    buffer.unmap();
    buffer
}

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
        .map_err(|e| RuntimeError::Readback(e.to_string()))?
        .to_vec();
    staging.unmap();
    Ok(data)
}
