//! Batched instances (`EffectBatch`): many instances of one effect in one set of buffers,
//! stepped by one dispatch chain, give each instance exactly the particles the same effect
//! gives alone with the same placement, params, bursts and steps, whether the instance plays,
//! sits steps out (paused) or takes more steps than the others (a faster time scale), and
//! whether it joined at the start or later in a place another instance left; its one draw, by
//! the raster pipeline and by the compute renderer, draws each instance through its transform.

mod common;

use plume::compiler::bursts::Burst;
use plume::compiler::placement::Placement;
use plume::compiler::reference::ParticleRecord;
use plume::runtime::{BatchInstance, Effect, EffectBatch, Gpu};
use plume::{compile_str, CompileOptions, CompiledEffect};

/// Sparks from a small sphere, falling onto a floor, pushed sideways by a live param; some
/// emitter bursts fired from code. A short life, so slots are freed and used again; a small
/// capacity, so spawns are dropped.
const SPARKS: &str = r#"Effect(name: "sparks", capacity: 120, seed: 9, dt: 0.02,
    params: {"push": 1.0},
    emitters: [
        Emitter(rate: 400.0, shape: Sphere(center: (0.0, 0.5, 0.0), radius: 0.2),
            velocity: Radial(speed: (1.0, 3.0)), lifetime: Some((0.2, 0.5))),
    ],
    forces: [Gravity((0.0, -9.81, 0.0)), Drag(k: 0.5), Custom(accel: "vec3(push, 0, 0)")],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.1)],
    integrator: SemiImplicitEuler)"#;

fn compiled() -> CompiledEffect {
    let options = CompileOptions {
        placed: true,
        bursts: true,
        live_params: true,
        ..Default::default()
    };
    compile_str(SPARKS, &options).expect("compiles")
}

/// A move to `(x, 0, z)` turned by `turn` radians about +y, column-major.
fn cols(x: f32, z: f32, turn: f32) -> [f32; 16] {
    let (s, c) = turn.sin_cos();
    [
        c, 0.0, -s, 0.0, 0.0, 1.0, 0.0, 0.0, s, 0.0, c, 0.0, x, 0.0, z, 1.0,
    ]
}

/// [`cols`] as a placement.
fn placed(x: f32, z: f32, turn: f32) -> Placement {
    Placement::from_cols(cols(x, z, turn)).expect("finite")
}

/// One instance's part in the run: where it is, its param, its steps in frame f.
struct Part {
    placement: Placement,
    push: f32,
    steps: fn(u32) -> u64,
    burst_at: Option<u32>,
}

fn parts() -> Vec<Part> {
    vec![
        // Plays at one step a frame.
        Part {
            placement: placed(0.0, 0.0, 0.0),
            push: 1.0,
            steps: |_| 1,
            burst_at: None,
        },
        // Paused for frames 8 to 19, with a burst fired while paused (spawned when it plays on).
        Part {
            placement: placed(4.0, -1.0, 0.7),
            push: -2.0,
            steps: |f| u64::from(!(8..20).contains(&f)),
            burst_at: Some(12),
        },
        // Twice as fast, and a burst.
        Part {
            placement: placed(-3.0, 2.0, 2.0),
            push: 0.0,
            steps: |_| 2,
            burst_at: Some(5),
        },
    ]
}

fn burst() -> Burst {
    Burst::new(0, 30)
        .at([0.0, 1.0, 0.0])
        .with_velocity([0.0, 2.0, 0.0])
}

/// Bitwise the same particles: ids, positions and velocities to the bit, ages and lifetimes.
fn assert_same(what: &str, batched: &[ParticleRecord], alone: &[ParticleRecord]) {
    assert_eq!(batched.len(), alone.len(), "{what}: live particles");
    assert!(
        !alone.is_empty(),
        "{what}: the run has particles to compare"
    );
    for (b, a) in batched.iter().zip(alone) {
        assert_eq!(b.id, a.id, "{what}");
        for (p, q) in [(b.position, a.position), (b.velocity, a.velocity)] {
            assert_eq!(
                p.to_array().map(f64::to_bits),
                q.to_array().map(f64::to_bits),
                "{what}: id {}",
                a.id
            );
        }
        assert_eq!(b.age, a.age, "{what}: id {} age", a.id);
        assert_eq!(b.lifetime, a.lifetime, "{what}: id {} lifetime", a.id);
    }
}

fn alone(gpu: &Gpu, compiled: &CompiledEffect, part: &Part) -> Effect {
    let mut effect = Effect::new(gpu, compiled.clone()).expect("effect");
    effect.set_placement(part.placement);
    effect.set_param("push", part.push).expect("param");
    effect
}

#[test]
fn each_batched_instance_has_the_particles_of_the_same_effect_alone() {
    let gpu = common::gpu();
    let compiled = compiled();
    let parts = parts();
    // Room for more instances than there are: the dispatches cover only those there are.
    let mut batch = EffectBatch::new(&gpu, &compiled, 8).expect("batch");
    let mut instances = Vec::new();
    let mut effects = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        let instance = batch.add().expect("room");
        batch
            .set_placement(instance, part.placement)
            .expect("placement");
        batch.set_param(instance, "push", part.push).expect("param");
        // Thinned instances thin as alone: the first keeps every spawn, the next fewer.
        let scale = 1.0 - 0.3 * k as f32;
        batch.set_spawn_scale(instance, scale).expect("scale");
        instances.push(instance);
        let mut effect = alone(&gpu, &compiled, part);
        effect.set_spawn_scale(scale);
        effects.push(effect);
    }
    for frame in 0..40u32 {
        for (k, part) in parts.iter().enumerate() {
            if part.burst_at == Some(frame) {
                batch.burst(instances[k], burst()).expect("burst");
                effects[k].burst(0, burst()).expect("burst");
            }
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        batch
            .advance(&mut encoder, |i| (parts[i.0 as usize].steps)(frame))
            .expect("batch steps");
        for (effect, part) in effects.iter_mut().zip(&parts) {
            effect
                .advance(&mut encoder, (part.steps)(frame))
                .expect("steps");
        }
        gpu.queue.submit([encoder.finish()]);
    }
    for (k, effect) in effects.iter().enumerate() {
        let what = format!("instance {k}");
        assert_eq!(
            batch.steps_done(instances[k]).expect("steps"),
            effect.steps_done(),
            "{what}"
        );
        assert_eq!(
            batch.totals(instances[k]).expect("totals"),
            effect.totals().expect("totals"),
            "{what}"
        );
        assert_same(
            &what,
            &batch.records(instances[k]).expect("records"),
            &effect.records().expect("records"),
        );
    }
    let totals = batch.totals(instances[0]).expect("totals");
    assert!(
        totals.died > 0 && totals.dropped > 0,
        "slots were freed and spawns dropped: {totals:?}"
    );
    // The batch as one effect counts every instance.
    let whole = batch.effect().totals().expect("totals");
    let each: Vec<_> = effects
        .iter()
        .map(|e| e.totals().expect("totals"))
        .collect();
    assert_eq!(whole.alive, each.iter().map(|t| t.alive).sum::<u64>());
    assert_eq!(whole.spawned, each.iter().map(|t| t.spawned).sum::<u64>());
    assert_eq!(whole.died, each.iter().map(|t| t.died).sum::<u64>());
}

#[test]
fn an_instance_added_in_a_freed_place_starts_afresh_and_a_restart_starts_again() {
    let gpu = common::gpu();
    let compiled = compiled();
    let parts = parts();
    let mut batch = EffectBatch::new(&gpu, &compiled, 2).expect("batch");
    let first = batch.add().expect("room");
    let second = batch.add().expect("room");
    assert!(batch.add().is_none(), "a batch of 2 is full with 2");
    let step = |batch: &mut EffectBatch, frames: u32| {
        for _ in 0..frames {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            batch.advance(&mut encoder, |_| 1).expect("steps");
            gpu.queue.submit([encoder.finish()]);
        }
    };
    step(&mut batch, 15);
    // The first leaves; a new one takes its place, 15 steps into the batch, elsewhere.
    batch.remove(first).expect("remove");
    assert!(batch.records(first).is_err(), "a removed instance is gone");
    let third = batch.add().expect("a freed place");
    assert_eq!(third, first, "the freed place is given again");
    batch
        .set_placement(third, parts[1].placement)
        .expect("placement");
    batch
        .set_param(third, "push", parts[1].push)
        .expect("param");
    step(&mut batch, 20);
    let mut fresh = alone(&gpu, &compiled, &parts[1]);
    fresh.run(20, |_| {}).expect("run");
    assert_same(
        "the new instance",
        &batch.records(third).expect("records"),
        &fresh.records().expect("records"),
    );
    assert_eq!(
        batch.totals(third).expect("totals"),
        fresh.totals().expect("totals")
    );
    // The second never left: 35 steps as one effect alone.
    let unmoved = Part {
        placement: Placement::IDENTITY,
        push: 1.0,
        steps: |_| 1,
        burst_at: None,
    };
    let mut long = alone(&gpu, &compiled, &unmoved);
    long.run(35, |_| {}).expect("run");
    assert_same(
        "the instance that stayed",
        &batch.records(second).expect("records"),
        &long.records().expect("records"),
    );
    // A restart: its particles gone at once, then as a fresh effect.
    batch.restart(second).expect("restart");
    step(&mut batch, 10);
    let mut again = alone(&gpu, &compiled, &unmoved);
    again.run(10, |_| {}).expect("run");
    assert_same(
        "the restarted instance",
        &batch.records(second).expect("records"),
        &again.records().expect("records"),
    );
}

#[test]
fn what_a_batch_cannot_take_is_refused_with_the_reason() {
    let gpu = common::gpu();
    let sorted = compile_str(
        &SPARKS.replace(
            "integrator: SemiImplicitEuler",
            "integrator: SemiImplicitEuler, sort: true",
        ),
        &CompileOptions::default(),
    )
    .expect("compiles");
    let refused = EffectBatch::new(&gpu, &sorted, 4)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        refused.contains("sparks: cannot be batched: it is sorted by depth"),
        "{refused}"
    );
    let mut batch = EffectBatch::new(&gpu, &compiled(), 2).expect("batch");
    let one = batch.add().expect("room");
    let unknown = batch.set_param(one, "pull", 1.0).unwrap_err().to_string();
    assert!(
        unknown.contains("unknown param `pull`") && unknown.contains("push"),
        "{unknown}"
    );
    let gone = batch
        .set_param(BatchInstance(1), "push", 1.0)
        .unwrap_err()
        .to_string();
    assert!(gone.contains("no instance 1"), "{gone}");
}

#[test]
fn one_draw_draws_every_instance_as_the_reference_draws_their_particles() {
    const SIDE: u32 = 128;
    // Life-faded colours and sizes (the draw reckons ages from the batch's step index).
    let source = seen_from_above(
        "Render(color: [(0.0, (1.0, 0.9, 0.5, 1.0)), (1.0, (0.6, 0.1, 0.0, 0.2))],
            size: [(0.0, 0.25), (1.0, 0.1)], blend: Additive)",
    );
    let options = CompileOptions {
        placed: true,
        bursts: true,
        live_params: true,
        ..Default::default()
    };
    let compiled = compile_str(&source, &options).expect("compiles");
    let gpu = common::gpu();
    let parts = parts();
    let mut batch = EffectBatch::new(&gpu, &compiled, 4).expect("batch");
    let instances: Vec<BatchInstance> = parts
        .iter()
        .map(|part| {
            let instance = batch.add().expect("room");
            batch
                .set_placement(instance, part.placement)
                .expect("placement");
            batch.set_param(instance, "push", part.push).expect("param");
            instance
        })
        .collect();
    for frame in 0..25u32 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        batch
            .advance(&mut encoder, |i| (parts[i.0 as usize].steps)(frame))
            .expect("steps");
        gpu.queue.submit([encoder.finish()]);
    }
    let mut records = Vec::new();
    for instance in &instances {
        records.extend(batch.records(*instance).expect("records"));
    }
    let (drawn, expected) = draw_and_reference(&gpu, &batch, &records, SIDE);
    // Every instance is in the image: the bright pixels span the three places (4 m apart
    // and more: over 30 pixels in this view), not one.
    let bright: Vec<u32> = (0..SIDE * SIDE)
        .filter(|&k| drawn[4 * k as usize] > 60)
        .map(|k| k % SIDE)
        .collect();
    let spread = bright
        .iter()
        .max()
        .zip(bright.iter().min())
        .map_or(0, |(a, b)| a - b);
    assert!(
        bright.len() > 30 && spread > 30,
        "{} bright pixels over {spread} columns",
        bright.len()
    );
    let (mean, max, over) = common::differences(&drawn, &expected, 8);
    // The same sprites rasterised from the same positions: only edge pixels may differ.
    assert!(
        mean < 0.5 && over < 60,
        "batch draw vs reference: mean {mean:.3}, largest {max}, {over} over 8"
    );
    assert_compute_draws_as_raster(&batch, &drawn, SIDE);
}

/// The compute renderer draws `batch` as its raster draw did (`raster`), each instance
/// through its own transform: the same sprites from the same f32 positions, each pixel's sum
/// rounded to 8 bits once in the compute renderer and after each additive blend in the raster
/// target, so a channel may land a step or two apart (llvmpipe: mean 0.002, at most 2). An
/// instance drawn without its transform moves its sprites by metres (tens of pixels here),
/// changing hundreds of pixels by tens of steps.
fn assert_compute_draws_as_raster(batch: &EffectBatch, raster: &[u8], side: u32) {
    let camera = plume::runtime::Camera::from_effect(&batch.compiled().ir.camera, 1.0);
    let mut compute = plume::runtime::outputs::ComputeOffscreen::new(batch.effect(), side, side)
        .expect("the compute renderer draws a batch");
    let drawn = compute
        .render(batch.effect(), &camera)
        .expect("compute draw");
    let bright = drawn.chunks(4).filter(|p| p[0] > 60).count();
    assert!(bright > 30, "{bright} bright pixels");
    let (mean, max, over) = common::differences(&drawn, raster, 2);
    assert!(
        mean < 0.01 && over == 0,
        "compute renderer vs raster draw of a batch: mean {mean:.4}, largest {max}, {over} over 2"
    );
}

#[test]
fn steps_in_parts_spawn_at_each_part_s_placement_as_an_effect_placed_between_advances() {
    let gpu = common::gpu();
    let compiled = compiled();
    let parts = parts();
    let mut batch = EffectBatch::new(&gpu, &compiled, 2).expect("batch");
    let moving = batch.add().expect("room");
    let mut effect = alone(&gpu, &compiled, &parts[0]);
    for frame in 0..6 {
        // Four steps a frame, in parts: one at each of two places, then three at a third.
        let at = |k: u32| placed(frame as f32 + k as f32, 0.5 * k as f32, 0.3 * k as f32);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        batch
            .advance_along(&mut encoder, &[vec![(1, Some(at(1))), (3, Some(at(2)))]])
            .expect("steps");
        for (n, k) in [(1, 1), (3, 2)] {
            effect.set_placement(at(k));
            effect.advance(&mut encoder, n).expect("steps");
        }
        gpu.queue.submit([encoder.finish()]);
    }
    assert_same(
        "in parts",
        &batch.records(moving).expect("records"),
        &effect.records().expect("records"),
    );
}

#[test]
fn a_long_run_remembers_only_the_steps_whose_particles_may_live() {
    // 3,000 steps of 400 sparks a second living 0.2 to 0.5 s: every step spawns, no spark
    // lives past 25 steps. The schedule keeps the steps whose sparks may live, not all 3,000,
    // and still gives every live spark its age: as the f64 reference does.
    let compiled = compile_str(SPARKS, &CompileOptions::default()).expect("compiles");
    let mut schedule = plume::compiler::schedule::Schedule::new(&compiled.ir);
    for _ in 0..3_000 {
        schedule.next_plan();
    }
    assert!(
        schedule.steps_remembered() <= 30,
        "{} steps remembered",
        schedule.steps_remembered()
    );
    let (gpu_totals, gpu) = common::run_gpu(&compiled, 3_000);
    let (cpu_totals, cpu) = common::run_cpu(&compiled, 3_000);
    assert_eq!(gpu_totals.spawned, cpu_totals.spawned);
    assert!(!gpu.is_empty());
    let ages = |records: &[ParticleRecord]| -> Vec<(u32, f64, Option<f64>)> {
        records.iter().map(|r| (r.id, r.age, r.lifetime)).collect()
    };
    assert_eq!(
        ages(&gpu),
        ages(&cpu),
        "ages and lifetimes of the live sparks"
    );
}

#[test]
fn instances_in_their_own_spaces_are_drawn_through_their_transforms() {
    const SIDE: u32 = 128;
    // Not placed: each instance simulates in its own space, and the draw turns its particles
    // by its transform (an entity that carries an effect in local space), here a move and a
    // quarter turn about +y. Velocity-aligned streaks check that the turn reaches the
    // sprites' axes too.
    let source = seen_from_above(
        "Render(color: [(0.0, (1.0, 0.9, 0.5, 1.0)), (1.0, (0.6, 0.1, 0.0, 0.2))],
            size: [(0.0, 0.2), (1.0, 0.1)], blend: Additive,
            orient: Velocity(stretch: 0.1, max_length: 0.6))",
    );
    let compiled = compile_str(&source, &CompileOptions::default()).expect("compiles");
    let gpu = common::gpu();
    let mut batch = EffectBatch::new(&gpu, &compiled, 4).expect("batch");
    let moves = [(-3.0, 1.0, 0.0), (3.5, -1.0, std::f32::consts::FRAC_PI_2)];
    let places: Vec<Placement> = moves.iter().map(|&(x, z, t)| placed(x, z, t)).collect();
    let instances: Vec<BatchInstance> = moves
        .iter()
        .map(|&(x, z, t)| {
            let instance = batch.add().expect("room");
            batch
                .set_transform(instance, cols(x, z, t))
                .expect("transform");
            instance
        })
        .collect();
    for _ in 0..20 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        batch.advance(&mut encoder, |_| 1).expect("steps");
        gpu.queue.submit([encoder.finish()]);
    }
    // The reference draws each instance's particles moved into the world by its transform.
    let mut records = Vec::new();
    for (instance, place) in instances.iter().zip(&places) {
        for mut r in batch.records(*instance).expect("records") {
            r.position = place.point(r.position);
            r.velocity = place.vector(r.velocity);
            records.push(r);
        }
    }
    let (drawn, expected) = draw_and_reference(&gpu, &batch, &records, SIDE);
    let bright = drawn.chunks(4).filter(|p| p[0] > 60).count();
    assert!(bright > 30, "{bright} bright pixels");
    let (mean, max, over) = common::differences(&drawn, &expected, 8);
    assert!(
        mean < 0.5 && over < 60,
        "batch draw vs reference: mean {mean:.3}, largest {max}, {over} over 8"
    );
    assert_compute_draws_as_raster(&batch, &drawn, SIDE);
}

/// SPARKS seen from above, with `render` (additive, so the order of the sprites does not
/// matter).
fn seen_from_above(render: &str) -> String {
    SPARKS.replace(
        "integrator: SemiImplicitEuler)",
        &format!(
            "integrator: SemiImplicitEuler,
        camera: Camera(eye: (0.5, 14.0, 6.0), target: (0.5, 0.0, 0.5), fov_y: 60.0),
        render: {render})"
        ),
    )
}

/// The batch drawn from its camera by its one draw, and the reference drawing of `records`
/// (in the world) from the same camera, `side` pixels square.
fn draw_and_reference(
    gpu: &Gpu,
    batch: &EffectBatch,
    records: &[ParticleRecord],
    side: u32,
) -> (Vec<u8>, Vec<u8>) {
    use plume::runtime::oracle::{sprites, ReferenceRenderer};
    use plume::runtime::outputs::Offscreen;
    let ir = &batch.compiled().ir;
    let camera = plume::runtime::Camera::from_effect(&ir.camera, 1.0);
    let target = Offscreen::new(gpu, side, side).expect("target");
    let renderer = batch.effect().renderer(&target.target()).expect("renderer");
    let drawn = target
        .render(batch.effect(), &renderer, &camera)
        .expect("draw");
    let reference = ReferenceRenderer::new(gpu, side, side, ir).expect("reference");
    let expected = reference
        .draw(&sprites(records, ir, &camera, false), &camera)
        .expect("reference draw");
    (drawn, expected)
}
