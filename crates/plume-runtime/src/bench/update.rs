//! `plume bench`: fill an effect to N live particles, time its update, and in the same run time
//! a WGSL copy kernel that moves the same bytes (each particle's state read once and written
//! once). A state-preserving update streams particle state, so the copy kernel is its ceiling;
//! the ratio copy time / update time says how close the update gets.

use plume_compiler::passes::layout::Role;
use plume_compiler::schema::State;
use plume_compiler::{CompiledEffect, EffectSpec};

use crate::bench::copy::CopyKernel;
use crate::bench::draw::{time_draws, DrawTimes};
use crate::bench::effect_copy::{compile_bench_as, compile_occupied};
use crate::bench::profile::{profiled, DispatchTime};
use crate::bench::timer::{PassTimer, TimingSource};
use crate::device::gpu::Gpu;
use crate::device::resources::STEPS_PER_SUBMIT;
use crate::error::RuntimeError;
use crate::sim::group::Group;
use crate::sort::radix::SortAlgorithm;

/// What was measured.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchResult {
    /// Adapter description.
    pub adapter: String,
    /// Live particles during the timed steps.
    pub particles: u64,
    /// Timed steps.
    pub steps: u32,
    /// Bytes of state per particle (the layout's struct).
    pub bytes_per_particle: u32,
    /// Particle buffers the state is split into.
    pub chunks: usize,
    /// Seconds per update step.
    pub seconds_per_step: f64,
    /// Seconds per copy of the same bytes.
    pub copy_seconds: f64,
    /// Seconds per in-place copy of the same bytes: each 16-byte word read and written back to
    /// the same buffer, as the update does (the copy kernel reads one buffer and writes another).
    pub copy_in_place_seconds: f64,
    /// Seconds of step 0, which spawns all N particles and updates them once.
    pub spawn_step_seconds: f64,
    /// Seconds for depth keys plus the radix sort of every slot, and the same with the bitonic
    /// baseline, when the effect has `sort: true`.
    pub sort: Option<(f64, f64)>,
    /// The radix depth sort's stages (name, seconds: keys, range, sort), when it sorts.
    pub sort_stages: Vec<(&'static str, f64)>,
    /// The flocking pass's stages (name, seconds) on the timed state, when the effect flocks.
    pub flock_stages: Vec<(&'static str, f64)>,
    /// The draw of all live particles from the GPU buffers, when asked for.
    pub render: Option<DrawTimes>,
    /// Timestamps or wall clock.
    pub timing: TimingSource,
    /// For flocking effects: the mean number of neighbours within the radius per live boid
    /// during the timed steps, and the neighbour search used.
    pub flock: Option<(f64, String)>,
    /// For a baked field: the error of the sampled acceleration against the evaluated one at
    /// the live particles' positions (up to [`FIELD_ERROR_SAMPLES`] of them, f64), as (max, RMS)
    /// over the RMS evaluated acceleration, and the number of particles inside the grid.
    pub field_error: Option<(f64, f64, usize)>,
    /// The stateless comparison: seconds per `evaluate` of the same N particles (what a frame
    /// costs with no state), or why the effect needs state.
    pub stateless: Result<f64, String>,
    /// Seconds per pass of a write-only kernel over the same bytes (the stateless ceiling),
    /// when the effect can be stateless.
    pub fill_seconds: Option<f64>,
    /// With [`BenchOptions::profile`]: each dispatch's time a step (timestamps included).
    pub dispatches: Vec<DispatchTime>,
    /// Wall seconds of building the effect at N (`Effect::new`: its buffers and kernels): the
    /// first time in the process; again, its modules and pipelines taken from the device's
    /// cache; and again on the same device with an empty cache (what every build cost before
    /// the cache, the driver's own caches warm).
    pub build_seconds: [f64; 3],
}

impl BenchResult {
    /// Bytes moved per step: each live particle's state read and written once.
    pub fn bytes_per_step(&self) -> f64 {
        2.0 * self.particles as f64 * f64::from(self.bytes_per_particle)
    }
    /// Effective bandwidth of the update (GB/s).
    pub fn update_gbps(&self) -> f64 {
        self.bytes_per_step() / self.seconds_per_step * 1e-9
    }
    /// Bandwidth of the copy kernel (GB/s).
    pub fn copy_gbps(&self) -> f64 {
        self.bytes_per_step() / self.copy_seconds * 1e-9
    }
    /// Particle-steps per second.
    pub fn particle_steps_per_second(&self) -> f64 {
        self.particles as f64 / self.seconds_per_step
    }
    /// Copy time over update time: 1 means the update runs at the copy kernel's bandwidth.
    pub fn ratio(&self) -> f64 {
        self.copy_seconds / self.seconds_per_step
    }
}

/// What `plume bench` measures.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    /// Particle slots (the capacity N).
    pub particles: u32,
    /// Timed steps (at most 256, one submission).
    pub steps: u32,
    /// Also time the draw at this image size.
    pub render: Option<(u32, u32)>,
    /// The fraction of the slots alive (1: all N). Below 1 the draw's two ways of skipping
    /// free slots, hidden quads and a compacted list, are compared.
    pub occupancy: f64,
    /// Also time each dispatch of a step (`--profile`: [`BenchResult::dispatches`]).
    pub profile: bool,
}

impl BenchOptions {
    /// N particles, all alive, `steps` timed steps, no draw.
    pub fn new(particles: u32, steps: u32) -> Self {
        Self {
            particles,
            steps,
            render: None,
            occupancy: 1.0,
            profile: false,
        }
    }
}

/// Runs the benchmark: spawn N, warm up, time `steps` update steps and as many copies. The
/// update is always the stateful one (state read and written every step, against the copy
/// kernel); an effect that can be stateless also has its `evaluate` timed on the same N.
pub fn bench(
    gpu: &Gpu,
    effect: &EffectSpec,
    options: &BenchOptions,
) -> Result<BenchResult, RuntimeError> {
    let particles = options.particles;
    let steps = options.steps.clamp(1, STEPS_PER_SUBMIT);
    let live = ((f64::from(particles) * options.occupancy.clamp(0.0, 1.0)).round() as u32).max(1);
    let compiled = compile_occupied(effect, particles, live, State::Stateful)?;
    let bpp = compiled.layout.bytes_per_particle;
    let build_seconds = time_builds(gpu, &compiled)?;
    let timer = PassTimer::new(gpu);
    // Warm the pipelines up on a throwaway copy so step 0 of the measured one is not a
    // first dispatch.
    Group::new(
        gpu,
        compile_bench_as(effect, 64, State::Stateful)?,
        None,
        &[],
    )?
    .run(2, |_| {})?;
    let stateless = time_stateless(gpu, &timer, effect, (particles, live), steps)?;
    let mut sim = Group::new(gpu, compiled, None, &[])?;
    let _scene = bind_scene_depth(gpu, &mut sim, options.render.unwrap_or((1280, 720)))?;
    // Step 0 spawns everything (timed), then a few steps settle the caches.
    let spawn_step = sim.time_steps(&timer, 1)?;
    sim.run(3, |_| {})?;
    let live = sim.totals()?.alive;
    let bytes = u64::from(particles) * u64::from(bpp);
    let copy_kernel = CopyKernel::new(gpu, bytes, "copy")?;
    let copy_in_place_kernel = CopyKernel::new(gpu, bytes, "copy_in_place")?;
    // The update and the copies in turn, the steps split into ROUNDS rounds (so the effect
    // advances by `steps` in all, as a flock's neighbours, which its cost follows, are taken
    // over them); each kernel keeps its fastest round.
    let per_round = (steps / ROUNDS).max(1);
    let (mut update, mut copy, mut copy_in_place) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..ROUNDS.min(steps) {
        update = update.min(sim.time_steps(&timer, per_round)? / f64::from(per_round));
        copy = copy.min(copy_kernel.time(&timer, per_round)? / f64::from(per_round));
        copy_in_place =
            copy_in_place.min(copy_in_place_kernel.time(&timer, per_round)? / f64::from(per_round));
    }
    drop((copy_kernel, copy_in_place_kernel));
    let dispatches = match options.profile {
        true => profiled(gpu, per_round, |n| sim.time_steps(&timer, n))?,
        false => Vec::new(),
    };
    let sort_stages = if sim.effect.layout.sorts() {
        sim.time_sort_stages(&timer, 9)?
    } else {
        Vec::new()
    };
    let sort = if sim.effect.layout.sorts() {
        // Warm up both, then time them.
        sim.time_sort(&timer, SortAlgorithm::Radix)?;
        sim.time_sort(&timer, SortAlgorithm::Bitonic)?;
        Some((
            sim.time_sort(&timer, SortAlgorithm::Radix)?,
            sim.time_sort(&timer, SortAlgorithm::Bitonic)?,
        ))
    } else {
        None
    };
    let flock = match &sim.effect.ir.flock {
        Some(f) => {
            let words = sim.read_extra_buffer(Role::FlockOut)?;
            // Word 7 of every 12 is the slot's neighbour count (0 for free slots).
            let total: f64 = words
                .chunks_exact(48)
                .map(|c| f64::from(f32::from_le_bytes([c[28], c[29], c[30], c[31]])))
                .sum();
            let search = match f.neighbors {
                plume_compiler::forces::flock::Neighbors::AllPairs => "all pairs".to_string(),
                plume_compiler::forces::flock::Neighbors::Grid { cell } => {
                    format!("grid, cell {cell} m")
                }
            };
            Some((total / live.max(1) as f64, search))
        }
        None => None,
    };
    let flock_stages = sim.time_flock_stages(&timer, 9)?;
    let field_error = match sim.effect.ir.field {
        Some(_) => {
            let t = sim.steps_done() as f64 * sim.effect.ir.dt;
            field_error(&sim.effect, &sim.records()?, t)
        }
        None => None,
    };
    let chunks = sim.chunk_count();
    let render = match options.render {
        None => None,
        Some((w, h)) => {
            // The draw is measured on the effect's own picture at N particles (draw_copy),
            // after the update's copy is gone.
            drop(sim);
            Some(time_draws(
                gpu,
                &timer,
                effect,
                (live as u32, particles),
                (w, h),
            )?)
        }
    };
    Ok(BenchResult {
        chunks,
        sort,
        sort_stages,
        flock_stages,
        render,
        adapter: gpu.describe(),
        particles: live,
        steps,
        bytes_per_particle: bpp,
        seconds_per_step: update,
        copy_seconds: copy,
        copy_in_place_seconds: copy_in_place,
        spawn_step_seconds: spawn_step,
        timing: timer.source(),
        flock,
        field_error,
        fill_seconds: match stateless {
            Ok(_) => Some(
                CopyKernel::new(gpu, u64::from(particles) * u64::from(bpp), "fill")?
                    .time(&timer, steps)?
                    / f64::from(steps),
            ),
            Err(_) => None,
        },
        stateless,
        dispatches,
        build_seconds,
    })
}

/// Wall seconds of building `compiled` (`Effect::new`) three times in a row, each build
/// dropped once made: first, again, and again with an empty cache
/// ([`BenchResult::build_seconds`]).
fn time_builds(gpu: &Gpu, compiled: &CompiledEffect) -> Result<[f64; 3], RuntimeError> {
    let build = |gpu: &Gpu| {
        let start = std::time::Instant::now();
        drop(crate::sim::effect::Effect::new(gpu, compiled.clone())?);
        Ok::<_, RuntimeError>(start.elapsed().as_secs_f64())
    };
    Ok([build(gpu)?, build(gpu)?, build(&gpu.with_empty_cache())?])
}

/// Particles whose baked-field error `plume bench` measures (the first by id).
pub const FIELD_ERROR_SAMPLES: usize = 4096;

/// The baked field's error at `records`' positions (see [`BenchResult::field_error`]): the
/// reference's bake at time `t`, sampled, against every bakeable term evaluated (f64). Only
/// particles inside the grid count; outside it the forces are evaluated anyway.
fn field_error(
    c: &CompiledEffect,
    records: &[plume_compiler::reference::ParticleRecord],
    t: f64,
) -> Option<(f64, f64, usize)> {
    let field = c.ir.field.as_ref()?;
    let t = match field.refresh {
        plume_compiler::field::Refresh::Once => 0.0,
        plume_compiler::field::Refresh::EveryStep => t,
    };
    let nodes = field.bake(&c.ir.terms, t);
    let (mut max, mut sum_err2, mut sum_ref2, mut n) = (0.0f64, 0.0, 0.0, 0usize);
    for r in records.iter().take(FIELD_ERROR_SAMPLES) {
        if let Some(baked) = field.sample(&nodes, r.position) {
            let exact = plume_compiler::field::baked_sum(&c.ir.terms, r.position, t);
            let err = (baked - exact).length();
            max = max.max(err);
            sum_err2 += err * err;
            sum_ref2 += exact.length_squared();
            n += 1;
        }
    }
    if n == 0 {
        return Some((0.0, 0.0, 0));
    }
    let scale = (sum_ref2 / n as f64).sqrt().max(1e-300);
    Some((max / scale, (sum_err2 / n as f64).sqrt() / scale, n))
}

/// Times `steps` evaluations of the stateless kernel at N particles (after a warm-up), or says
/// why the effect needs state. The sim is dropped before the stateful one is made.
fn time_stateless(
    gpu: &Gpu,
    timer: &PassTimer<'_>,
    effect: &EffectSpec,
    (capacity, live): (u32, u32),
    steps: u32,
) -> Result<Result<f64, String>, RuntimeError> {
    let compiled = compile_occupied(effect, capacity, live, State::Auto)?;
    if compiled.ir.stateless.is_none() {
        return Ok(Err(compiled.ir.state_reason));
    }
    let mut sim = Group::new(gpu, compiled, None, &[])?;
    sim.run(4, |_| {})?;
    sim.time_steps(timer, 2)?;
    Ok(Ok(sim.time_steps(timer, steps)? / f64::from(steps)))
}

/// Rounds in which `plume bench` times the update and the copy kernels in turn, keeping each
/// one's fastest: on the lent H100 the memory bandwidth every kernel gets switches between two
/// levels for seconds at a time, whatever the buffers (docs/performance.md, "The update at
/// large sizes"), so a single timing of each can compare kernels measured at different levels.
pub const ROUNDS: u32 = 5;

/// For an effect with a `SceneDepth` collider, its scene drawn from its camera at `size` and
/// bound to `sim` (the scene is returned to keep alive); the benchmark then measures the
/// collider against the depth the effect's own scene leaves.
fn bind_scene_depth(
    gpu: &Gpu,
    sim: &mut Group,
    size: (u32, u32),
) -> Result<Option<crate::outputs::Scene>, RuntimeError> {
    if !sim.effect.ir.collides_with_scene_depth() {
        return Ok(None);
    }
    let camera = crate::draw::camera::Camera::from_effect(
        &sim.effect.ir.camera,
        size.0 as f32 / size.1.max(1) as f32,
    );
    let triangles = sim.effect.ir.scene_triangles();
    let Some(scene) = crate::outputs::Scene::depth_only(gpu, &triangles, &camera, size)? else {
        return Ok(None);
    };
    let words = crate::sim::scene_depth::camera(camera.view, camera.proj)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    crate::sim::scene_depth::record(
        sim,
        &mut Default::default(),
        &mut encoder,
        scene.depth_texture(),
        &words,
    )?;
    gpu.queue.submit([encoder.finish()]);
    Ok(Some(scene))
}
