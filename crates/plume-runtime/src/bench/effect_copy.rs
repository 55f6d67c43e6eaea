//! The benchmarks' copies of an effect: the file's own forces, integrator, collisions, kills
//! and look, at N particles spawned at step 0 with lifetimes that outlast the run (or some of
//! the slots left free), and its picture scaled to N particles for the draw.

use plume_compiler::emitter::Amount;
use plume_compiler::schema::State;
use plume_compiler::{compile_effect, CompileError, CompiledEffect, EffectSpec};

use crate::error::RuntimeError;

/// The benchmark's copy of an effect: capacity N and all N spawned at step 0 (split over the
/// emitters in proportion to their bursts and rates), lifetimes long enough to outlast the run.
/// Forces, integrator, collisions and kills are the effect's own, so the layout is too.
pub fn bench_effect(effect: &EffectSpec, particles: u32) -> EffectSpec {
    bench_effect_occupied(effect, particles, particles)
}

/// Like [`bench_effect`] with capacity `capacity` of which only `live` are spawned (at most
/// the capacity): the rest of the slots stay free.
pub fn bench_effect_occupied(effect: &EffectSpec, capacity: u32, live: u32) -> EffectSpec {
    let mut e = effect.clone();
    let params = e.params.clone();
    let file_count: u32 = e.emitters.iter().map(|em| em.burst.value(&params)).sum();
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
        .map(|em| f64::from(em.burst.value(&params)) + em.rate.value(&params).max(0.0))
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
        em.burst = Amount::Value(share);
        em.rate = Amount::Value(0.0);
        // All of it at step 0, once.
        (em.start, em.duration, em.every, em.cycles) = (0.0, None, None, None);
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
        Shape::Box { min, max, .. } => (min.d() + max.d()) * 0.5,
        Shape::Point(p) => p.d(),
        Shape::Disc { center, .. } | Shape::Circle { center, .. } | Shape::Torus { center, .. } => {
            center.d()
        }
        Shape::Cone {
            base, axis, height, ..
        } => base.d() + axis.d().normalize_or_zero() * (0.5 * height),
        Shape::Grid { min, max, .. } => (min.d() + max.d()) * 0.5,
        Shape::Points(ps) => ps.iter().map(|p| p.d()).sum::<glam::DVec3>() / ps.len().max(1) as f64,
        Shape::Mesh { offset, .. } => offset.d(),
        Shape::Custom(_) => glam::DVec3::ZERO,
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
        Shape::Sphere { center, radius, .. } => {
            *center = map(center.d());
            *radius *= scale;
        }
        Shape::Box { min, max, .. } => {
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
pub fn draw_copy(effect: &EffectSpec, particles: u32, slots: u32) -> (EffectSpec, u64) {
    let mut e = effect.clone();
    let params = e.params.clone();
    let mean = |l: &plume_compiler::schema::Range| 0.5 * (l.0 + l.1);
    let streams = e
        .emitters
        .iter()
        .any(|em| em.rate.value(&params) > 0.0 && em.lifetime.is_some());
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
                _ => f64::from(em.burst.value(&params)),
            };
            let rate = em.rate.value(&params);
            let stream = match &em.lifetime {
                Some(l) => rate * mean(l).min(t),
                None => rate * t,
            };
            burst + stream
        })
        .sum();
    let scale = f64::from(particles.max(1)) / alive.max(1.0);
    for em in &mut e.emitters {
        let burst = (f64::from(em.burst.value(&params)) * scale)
            .round()
            .min(f64::from(u32::MAX / 2)) as u32;
        em.burst = Amount::Value(burst);
        em.rate = Amount::Value(em.rate.value(&params) * scale);
    }
    e.capacity = (f64::from(particles) * 1.1 + 1024.0)
        .max(f64::from(slots))
        .min(f64::from(u32::MAX / 2)) as u32;
    let steps = (t / e.dt).round().max(1.0) as u64;
    (e, steps)
}

/// Compiles the bench copy of `effect` (with its own `state`).
pub fn compile_bench(effect: &EffectSpec, particles: u32) -> Result<CompiledEffect, RuntimeError> {
    compile_bench_as(effect, particles, effect.state)
}

/// Compiles the bench copy of `effect` with `state` in place of the file's.
pub(crate) fn compile_bench_as(
    effect: &EffectSpec,
    particles: u32,
    state: State,
) -> Result<CompiledEffect, RuntimeError> {
    compile_occupied(effect, particles, particles, state)
}

/// Compiles [`bench_effect_occupied`] with `state` in place of the file's.
pub(crate) fn compile_occupied(
    effect: &EffectSpec,
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
