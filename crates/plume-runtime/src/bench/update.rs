//! `plume bench`: fill an effect to N live particles, time its update, and in the same run time
//! a WGSL copy kernel that moves the same bytes (each particle's state read once and written
//! once). A state-preserving update streams particle state, so the copy kernel is its ceiling;
//! the ratio copy time / update time says how close the update gets.

use plume_compiler::schema::State;
use plume_compiler::{compile_effect, CompileError, CompiledEffect, Effect};

use crate::error::RuntimeError;
use crate::device::gpu::Gpu;
use crate::sim::group::EffectInstance;
use crate::outputs::offscreen::Offscreen;
use crate::device::resources::STEPS_PER_SUBMIT;
use crate::sort::radix::SortAlgorithm;
use crate::bench::timer::{PassTimer, TimingSource};

/// The copy kernel: 16 bytes a thread, 2D-indexed like the effect kernels.
const COPY_WGSL: &str = r#"
@group(0) @binding(0) var<storage, read> src: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> dst: array<vec4<u32>>;

@compute @workgroup_size(256)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = src[i];
    }
}

// The same words read and written back in place, as the update does (one buffer, not two).
@compute @workgroup_size(256)
fn copy_in_place(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = dst[i] + vec4<u32>(1u);
    }
}

// Write-only: the ceiling of a kernel that reads no state (the stateless evaluate). It takes
// src's length only, so both kernels share one bind group layout.
@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i < arrayLength(&src)) {
        dst[i] = vec4<u32>(i);
    }
}
"#;

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
}

/// The draw's figures at one image size, in seconds per frame: each the median of
/// [`DRAW_REPEATS`] frames, timed by GPU timestamps around the render pass alone (the wall
/// clock of the whole submission on adapters without timestamps).
#[derive(Clone, Debug, PartialEq)]
pub struct DrawTimes {
    /// Live particles drawn: the effect's own scene scaled to N ([`draw_scene`]).
    pub particles: u64,
    /// Steps run before drawing.
    pub steps: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The draw as the effect asks for it (its blending, its sizes), one instance per slot
    /// (free slots hidden, for an unsorted stateful effect; see `compacted` for the default).
    pub draw: f64,
    /// The same draw with blending off (each fragment replaces the pixel): blending's share.
    pub opaque: f64,
    /// Every sprite of size 0, hidden by the vertex shader: the vertex work alone, no pixels.
    pub vertex_only: f64,
    /// The compute work a frame records before the draw: depth keys, the radix sort and the
    /// indirect draw's count (sorted effects only).
    pub prepare: Option<f64>,
    /// A stateful, unsorted effect drawn through a compacted list of its live slots instead
    /// of hiding the free ones: (the list's compute passes, its draw).
    pub compacted: Option<(f64, f64)>,
    /// The same draw with one triangle per sprite instead of a quad (3 vertices and 1
    /// primitive instead of 4 and 2; 30% more area).
    pub triangle: f64,
    /// The compute splat of the same image ([`crate::draw::splat`]): its one compute pass (the frame
    /// preparation, a sort when the effect sorts, excluded as for the draw), and the (tile,
    /// sprite) entries it sorted; None for sprites it cannot draw (oriented ones).
    pub splat: Option<(f64, u64)>,
    /// The splat's stages timed one by one (each the median of [`DRAW_REPEATS`]).
    pub splat_stages: Vec<(&'static str, f64)>,
    /// The same N particles of a stateless copy of the effect, drawn from the closed form in
    /// the vertex shader, when the effect can be stateless.
    pub stateless: Option<f64>,
    /// For a glowing effect (`render.glow`): (the same draw into the HDR image instead of
    /// RGBA8, the two blur passes that bloom it).
    pub glow: Option<(f64, f64)>,
}

/// Frames timed per draw figure (the median is reported).
pub const DRAW_REPEATS: usize = 5;

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

/// The benchmark's copy of an effect: capacity N and all N spawned at step 0 (split over the
/// emitters in proportion to their bursts and rates), lifetimes long enough to outlast the run.
/// Forces, integrator, collisions and kills are the effect's own, so the layout is too.
pub fn bench_effect(effect: &Effect, particles: u32) -> Effect {
    bench_effect_occupied(effect, particles, particles)
}

/// Like [`bench_effect`] with capacity `capacity` of which only `live` are spawned (at most
/// the capacity): the rest of the slots stay free.
pub fn bench_effect_occupied(effect: &Effect, capacity: u32, live: u32) -> Effect {
    let mut e = effect.clone();
    let file_count: u32 = e.emitters.iter().map(|em| em.burst).sum();
    e.capacity = capacity.max(1);
    let live = live.min(e.capacity);
    // A flock keeps the file's density: spheres and boxes (and their arrangement) grow with the
    // cube root of the count, so the neighbours per boid (what the search costs) stay those the
    // author chose.
    let flocks = e
        .forces
        .iter()
        .any(|f| matches!(f, plume_compiler::forces::Force::Flock(_)));
    if flocks && file_count > 0 {
        let scale = (f64::from(live.max(1)) / f64::from(file_count)).cbrt();
        let centres: Vec<glam::DVec3> = e
            .emitters
            .iter()
            .map(|em| shape_centre(&em.shape))
            .collect();
        let about = centres.iter().sum::<glam::DVec3>() / centres.len().max(1) as f64;
        for em in &mut e.emitters {
            scale_shape(&mut em.shape, scale, about);
        }
    }
    let weights: Vec<f64> = e
        .emitters
        .iter()
        .map(|em| f64::from(em.burst) + em.rate.max(0.0))
        .collect();
    let total: f64 = weights.iter().sum();
    let mut given = 0u32;
    let n = e.emitters.len();
    for (i, em) in e.emitters.iter_mut().enumerate() {
        let share = if i + 1 == n {
            live - given
        } else if total > 0.0 {
            ((f64::from(live) * weights[i] / total) as u32).min(live - given)
        } else {
            0
        };
        em.burst = share;
        em.rate = 0.0;
        given += share;
        if em.lifetime.is_some() {
            em.lifetime = Some(plume_compiler::schema::Range(1.0e6, 1.0e6));
        }
    }
    e
}

fn shape_centre(shape: &plume_compiler::schema::Shape) -> glam::DVec3 {
    use plume_compiler::schema::Shape;
    match shape {
        Shape::Sphere { center, .. } => center.d(),
        Shape::Box { min, max } => (min.d() + max.d()) * 0.5,
        Shape::Point(p) => p.d(),
        Shape::Disc { center, .. } => center.d(),
        Shape::Grid { min, max, .. } => (min.d() + max.d()) * 0.5,
        Shape::Points(ps) => ps.iter().map(|p| p.d()).sum::<glam::DVec3>() / ps.len().max(1) as f64,
    }
}

/// Scales a spawn shape about `about` (spheres and boxes, centres included, so several shapes
/// keep their arrangement; other shapes are left as they are).
fn scale_shape(shape: &mut plume_compiler::schema::Shape, scale: f64, about: glam::DVec3) {
    use plume_compiler::schema::{Shape, Vec3};
    let map = |p: glam::DVec3| {
        let q = about + (p - about) * scale;
        Vec3(q.x, q.y, q.z)
    };
    match shape {
        Shape::Sphere { center, radius } => {
            *center = map(center.d());
            *radius *= scale;
        }
        Shape::Box { min, max } => {
            *min = map(min.d());
            *max = map(max.d());
        }
        _ => {}
    }
}

/// The draw's scene: the effect as written, its emitters scaled so that about `particles` are
/// alive when it is drawn, and the steps to run before drawing it. The update's copy
/// ([`bench_effect`]) spawns everything at step 0, which suits a bandwidth measurement but draws
/// a fountain as one blob at the nozzle; a draw measurement needs the effect's own picture:
/// - an effect with a stream and lifetimes is drawn at its steady state, after its longest
///   lifetime (alive ≈ Σ rate × mean lifetime + bursts still alive);
/// - an effect of bursts with lifetimes is drawn at half its shortest lifetime;
/// - an effect whose particles never die is drawn after 1.5 s.
///
/// The capacity is `slots`, or a tenth more than `particles` if that is more, so the
/// randomness of lifetimes drops nothing.
pub fn draw_scene(effect: &Effect, particles: u32, slots: u32) -> (Effect, u64) {
    let mut e = effect.clone();
    let mean = |l: &plume_compiler::schema::Range| 0.5 * (l.0 + l.1);
    let streams = e
        .emitters
        .iter()
        .any(|em| em.rate > 0.0 && em.lifetime.is_some());
    let t = if streams {
        e.emitters
            .iter()
            .filter_map(|em| em.lifetime.as_ref().map(|l| l.1))
            .fold(0.0, f64::max)
    } else if e.emitters.iter().any(|em| em.lifetime.is_some()) {
        0.5 * e
            .emitters
            .iter()
            .filter_map(|em| em.lifetime.as_ref().map(|l| l.0))
            .fold(f64::INFINITY, f64::min)
    } else {
        1.5
    };
    let alive: f64 = e
        .emitters
        .iter()
        .map(|em| {
            let burst = match &em.lifetime {
                Some(l) if l.1 < t => 0.0,
                _ => f64::from(em.burst),
            };
            let stream = match &em.lifetime {
                Some(l) => em.rate * mean(l).min(t),
                None => em.rate * t,
            };
            burst + stream
        })
        .sum();
    let scale = f64::from(particles.max(1)) / alive.max(1.0);
    for em in &mut e.emitters {
        em.burst = (f64::from(em.burst) * scale)
            .round()
            .min(f64::from(u32::MAX / 2)) as u32;
        em.rate *= scale;
    }
    e.capacity = (f64::from(particles) * 1.1 + 1024.0)
        .max(f64::from(slots))
        .min(f64::from(u32::MAX / 2)) as u32;
    let steps = (t / e.dt).round().max(1.0) as u64;
    (e, steps)
}

/// Compiles the bench copy of `effect` (with its own `state`).
pub fn compile_bench(effect: &Effect, particles: u32) -> Result<CompiledEffect, RuntimeError> {
    compile_bench_as(effect, particles, effect.state)
}

/// Compiles the bench copy of `effect` with `state` in place of the file's.
fn compile_bench_as(
    effect: &Effect,
    particles: u32,
    state: State,
) -> Result<CompiledEffect, RuntimeError> {
    compile_occupied(effect, particles, particles, state)
}

/// Compiles [`bench_effect_occupied`] with `state` in place of the file's.
fn compile_occupied(
    effect: &Effect,
    capacity: u32,
    live: u32,
    state: State,
) -> Result<CompiledEffect, RuntimeError> {
    let mut e = bench_effect_occupied(effect, capacity, live);
    e.state = state;
    compile_effect(&e, "").map_err(|e| match e {
        CompileError::Invalid(d) => RuntimeError::Output(d.to_string()),
        CompileError::Internal(i) => RuntimeError::Output(i.to_string()),
    })
}

/// What `plume bench` measures.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    /// Particle slots (the capacity N).
    pub particles: u32,
    /// Timed steps (at most [`STEPS_PER_SUBMIT`]).
    pub steps: u32,
    /// Also time the draw at this image size.
    pub render: Option<(u32, u32)>,
    /// The fraction of the slots alive (1: all N). Below 1 the draw's two ways of skipping
    /// free slots, hidden quads and a compacted list, are compared.
    pub occupancy: f64,
}

impl BenchOptions {
    /// N particles, all alive, `steps` timed steps, no draw.
    pub fn new(particles: u32, steps: u32) -> Self {
        Self {
            particles,
            steps,
            render: None,
            occupancy: 1.0,
        }
    }
}

/// Runs the benchmark: spawn N, warm up, time `steps` update steps and as many copies. The
/// update is always the stateful one (state read and written every step, against the copy
/// kernel); an effect that can be stateless also has its `evaluate` timed on the same N.
pub fn bench(
    gpu: &Gpu,
    effect: &Effect,
    options: &BenchOptions,
) -> Result<BenchResult, RuntimeError> {
    let particles = options.particles;
    let steps = options.steps.clamp(1, STEPS_PER_SUBMIT);
    let live = ((f64::from(particles) * options.occupancy.clamp(0.0, 1.0)).round() as u32).max(1);
    let compiled = compile_occupied(effect, particles, live, State::Stateful)?;
    let bpp = compiled.layout.bytes_per_particle;
    let timer = PassTimer::new(gpu);
    // Warm the pipelines up on a throwaway copy so step 0 of the measured one is not a
    // first dispatch.
    EffectInstance::new(gpu, compile_bench_as(effect, 64, State::Stateful)?)?.run(2, |_| {})?;
    let stateless = time_stateless(gpu, &timer, effect, (particles, live), steps)?;
    let mut sim = EffectInstance::new(gpu, compiled)?;
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
    let sort = if sim.effect().layout.sorts() {
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
    let flock = match &sim.effect().ir.flock {
        Some(f) => {
            let words = sim.read_flock_buffer("flock_out")?;
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
    let field_error = match sim.effect().ir.field {
        Some(_) => {
            let t = sim.schedule().steps_done() as f64 * sim.effect().ir.dt;
            field_error(sim.effect(), &sim.records()?, t)
        }
        None => None,
    };
    let chunks = sim.chunk_count();
    let render = match options.render {
        None => None,
        Some((w, h)) => {
            // The draw is measured on the effect's own picture at N particles (draw_scene),
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
    })
}

/// Times the draws (see [`DrawTimes`]) of the effect's scene with about `particles` alive in
/// `slots` at `width` x `height` from the effect's camera.
fn time_draws(
    gpu: &Gpu,
    timer: &PassTimer<'_>,
    effect: &Effect,
    (particles, slots): (u32, u32),
    (width, height): (u32, u32),
) -> Result<DrawTimes, RuntimeError> {
    let (scene, steps) = draw_scene(effect, particles, slots);
    let compile = |state| {
        let mut e = scene.clone();
        e.state = state;
        compile_effect(&e, "").map_err(|e| RuntimeError::Output(e.to_string()))
    };
    // The stateful copy is measured in full; a stateless one (when the effect allows it) is
    // drawn from its closed form beside it.
    let mut sim = EffectInstance::new(gpu, compile(State::Stateful)?)?;
    sim.run(steps, |_| {})?;
    let sim = &sim;
    let target = Offscreen::new(gpu, width, height)?;
    let camera = target.effect_camera(sim);
    let median = |times: &mut Vec<f64>| {
        times.sort_by(f64::total_cmp);
        times[times.len() / 2]
    };
    // Warms the draw up (pipeline creation, first use of the buffers), then times it.
    let time = |sim: &EffectInstance, renderer: &crate::draw::raster::EffectRenderer| {
        target.render(sim, renderer, &camera)?;
        let mut times = Vec::with_capacity(DRAW_REPEATS);
        for _ in 0..DRAW_REPEATS {
            times.push(timer.time_render(|encoder, timestamps| {
                target.record(encoder, sim, renderer, &camera, timestamps)
            })?);
        }
        Ok::<f64, RuntimeError>(median(&mut times))
    };
    // The draw as a host gets it by default; for an unsorted stateful effect that is the
    // compacted list, and `draw` below is the other way, every slot with free ones hidden.
    let hidden_slots = crate::draw::raster::DrawOptions {
        dead_slots: crate::draw::raster::DeadSlots::Hidden,
        ..Default::default()
    };
    let draw = time(sim, &sim.renderer_with(&target.target(), &hidden_slots)?)?;
    let opaque = time(
        sim,
        &sim.renderer_with(
            &target.target(),
            &crate::draw::raster::DrawOptions {
                blend: Some(wgpu::BlendState::REPLACE),
                ..hidden_slots
            },
        )?,
    )?;
    let mut hidden = sim.renderer_with(&target.target(), &hidden_slots)?;
    hidden.set_size_scale(0.0);
    let vertex_only = time(sim, &hidden)?;
    let triangle = time(
        sim,
        &sim.renderer_with(
            &target.target(),
            &crate::draw::raster::DrawOptions {
                primitive: plume_compiler::wgsl::draw::Primitive::Triangle,
                ..hidden_slots
            },
        )?,
    )?;
    let (splat, splat_stages) = if !crate::draw::splat::Splat::draws(&sim.effect().ir) {
        (None, Vec::new())
    } else {
        let mut splat = crate::draw::splat::Splat::new(sim, width, height)?;
        // Draws once, growing the entry list to what the frame needs, then times the pass.
        splat.render(sim, &camera)?;
        let mut times = Vec::with_capacity(DRAW_REPEATS);
        for _ in 0..DRAW_REPEATS {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            splat.prepare(&mut encoder, sim, &camera)?;
            gpu.queue.submit([encoder.finish()]);
            times.push(timer.time(|pass| splat.record(pass))?);
        }
        // Stage by stage, in order, each in its own timed pass: repeating one stage alone is
        // not the same work (the scan works in place).
        let mut per_stage = vec![Vec::with_capacity(DRAW_REPEATS); crate::draw::splat::STAGES.len()];
        for _ in 0..DRAW_REPEATS {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            splat.prepare(&mut encoder, sim, &camera)?;
            gpu.queue.submit([encoder.finish()]);
            for (times, stage) in per_stage.iter_mut().zip(crate::draw::splat::STAGES) {
                times.push(timer.time(|pass| splat.record_stage(pass, stage))?);
            }
        }
        let stages: Vec<(&'static str, f64)> = crate::draw::splat::STAGES
            .into_iter()
            .zip(per_stage.iter_mut())
            .map(|(stage, times)| (stage, median(times)))
            .collect();
        (Some((median(&mut times), splat.entries())), stages)
    };
    let prepare = match sim.effect().ir.sort {
        true => {
            sim.time_sort(timer, SortAlgorithm::Radix)?;
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| sim.time_sort(timer, SortAlgorithm::Radix))
                .collect::<Result<_, _>>()?;
            Some(median(&mut times))
        }
        false => None,
    };
    // Hidden quads against a compacted list (stateful, unsorted effects): the list's compute
    // passes, then its draw.
    let compacted = match !sim.effect().ir.sort {
        true => {
            let renderer = sim.renderer_with(
                &target.target(),
                &crate::draw::raster::DrawOptions {
                    dead_slots: crate::draw::raster::DeadSlots::Compacted,
                    ..Default::default()
                },
            )?;
            let draw = time(sim, &renderer)?;
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| timer.time(|pass| renderer.record_instance_count(pass)))
                .collect::<Result<_, _>>()?;
            Some((median(&mut times), draw))
        }
        false => None,
    };
    let glow = match &sim.effect().ir.render.glow {
        Some(g) => {
            let glowing = Offscreen::with_glow(gpu, width, height, Some(g))?;
            let renderer = sim.renderer_with(&glowing.target(), &hidden_slots)?;
            glowing.render(sim, &renderer, &camera)?;
            let mut draws = Vec::with_capacity(DRAW_REPEATS);
            let mut blurs = Vec::with_capacity(DRAW_REPEATS);
            let passes = glowing.glow().expect("a glowing target has its passes");
            for _ in 0..DRAW_REPEATS {
                draws.push(timer.time_render(|encoder, timestamps| {
                    glowing.record(encoder, sim, &renderer, &camera, timestamps)
                })?);
                blurs.push(timer.time(|pass| {
                    passes.record_into(pass);
                    Ok(())
                })?);
            }
            Some((median(&mut draws), median(&mut blurs)))
        }
        None => None,
    };
    let stateless = match compile(State::Auto)? {
        c if c.ir.stateless.is_some() => {
            let mut s = EffectInstance::new(gpu, c)?;
            s.run(steps, |_| {})?;
            Some(time(&s, &s.renderer(&target.target())?)?)
        }
        _ => None,
    };
    Ok(DrawTimes {
        particles: sim.totals()?.alive,
        steps,
        width,
        height,
        draw,
        opaque,
        vertex_only,
        prepare,
        compacted,
        triangle,
        splat,
        splat_stages,
        stateless,
        glow,
    })
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
    effect: &Effect,
    (capacity, live): (u32, u32),
    steps: u32,
) -> Result<Result<f64, String>, RuntimeError> {
    let compiled = compile_occupied(effect, capacity, live, State::Auto)?;
    if compiled.ir.stateless.is_none() {
        return Ok(Err(compiled.ir.state_reason));
    }
    let mut sim = EffectInstance::new(gpu, compiled)?;
    sim.run(4, |_| {})?;
    sim.time_steps(timer, 2)?;
    Ok(Ok(sim.time_steps(timer, steps)? / f64::from(steps)))
}

/// Rounds in which `plume bench` times the update and the copy kernels in turn, keeping each
/// one's fastest: on the lent H100 the memory bandwidth every kernel gets switches between two
/// levels (about 3.0 and 1.7 TB/s for the copy) for seconds at a time, whatever the buffers
/// (docs/performance.md, "The update at large sizes"), so a single timing of each can compare
/// kernels measured at different levels.
pub const ROUNDS: u32 = 5;

/// A pass of `entry` (`copy`: read and write `bytes`, rounded up to 16; `copy_in_place`: the
/// same, reading and writing one buffer; `fill`: write them only) over buffers of its own,
/// split into buffers of at most one binding each.
struct CopyKernel {
    pipeline: wgpu::ComputePipeline,
    /// Per buffer: its bind group, the dispatch size, and the buffers it binds.
    parts: Vec<(wgpu::BindGroup, u32, u32, wgpu::Buffer, wgpu::Buffer)>,
    gpu: Gpu,
}

impl CopyKernel {
    fn new(gpu: &Gpu, bytes: u64, entry: &str) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size)
            / 16
            * 16;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("copy"),
            source: wgpu::ShaderSource::Wgsl(COPY_WGSL.into()),
        });
        let pipeline = gpu.compute_pipeline(&module, entry, None);
        let layout = pipeline.get_bind_group_layout(0);
        let mut parts = Vec::new();
        let mut left = bytes.next_multiple_of(16).max(16);
        while left > 0 {
            let size = left.min(limit);
            left -= size;
            let make = |label| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            };
            let (src, dst) = (make("copy src"), make("copy dst"));
            let group = gpu.bind_buffers("copy", &layout, &[(0, &src), (1, &dst)]);
            let (x, y) = gpu.grid(size / 16, 256)?;
            parts.push((group, x, y, src, dst));
        }
        let kernel = Self {
            pipeline,
            parts,
            gpu: gpu.clone(),
        };
        gpu.take_error()?;
        Ok(kernel)
    }

    /// Seconds for `repeats` passes, in one compute pass (after one untimed pass).
    fn time(&self, timer: &PassTimer<'_>, repeats: u32) -> Result<f64, RuntimeError> {
        let record = |pass: &mut wgpu::ComputePass<'_>, n: u32| {
            pass.set_pipeline(&self.pipeline);
            for _ in 0..n {
                for (group, x, y, _, _) in &self.parts {
                    pass.set_bind_group(0, group, &[]);
                    pass.dispatch_workgroups(*x, *y, 1);
                }
            }
            Ok(())
        };
        timer.time(|pass| record(pass, 1))?;
        let seconds = timer.time(|pass| record(pass, repeats))?;
        self.gpu.take_error()?;
        Ok(seconds)
    }
}
