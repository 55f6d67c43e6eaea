//! The plugin in a headless Bevy app on llvmpipe (lavapipe): effects drawn where the scene
//! puts them, a graph effect, hot reload and its errors, local space, restart, instances
//! coming and going, and bursts and params from game code.

use std::time::Duration;

use crate::common::{asset_dir, dots, lit_pixels, project, serial, Harness, WIDTH};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::plume_compiler::reference::{ParticleRecord, Totals};
use bevy_plume::{PlumeBurst, PlumeEffect, PlumeRenderStats, SimulationSpace};

/// Pixels further than this from where the effect's centre projects fail the placement
/// checks: the burst spreads at most 0.13 m (about 1.3 px at 10 m with this camera), so
/// 4 px is that plus sprite size and rounding.
const PLACE_TOLERANCE_PX: f32 = 4.0;

#[test]
fn an_effect_is_drawn_where_its_entity_is() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("place", &dots(300, 100.0, (1.0, 0.2, 0.1)));
    h.app
        .world_mut()
        .spawn((PlumeEffect::new(handle), Transform::from_xyz(2.0, 1.0, 0.0)));
    h.update(10);
    let image = h.capture_running();
    let (n, x, y) = lit_pixels(&image, 40);
    let (ex, ey) = project(2.0, 1.0);
    assert!(n >= 4, "only {n} lit pixels");
    assert!(
        (x - ex).abs() < PLACE_TOLERANCE_PX && (y - ey).abs() < PLACE_TOLERANCE_PX,
        "particles centred at ({x:.1}, {y:.1}), the entity projects to ({ex:.1}, {ey:.1})"
    );
    // Red, as the file says: additive red over black (where many overlap, white).
    let reddest = image.pixels().map(|p| p.0[0]).max().unwrap();
    let greener = image.pixels().filter(|p| p.0[1] > p.0[0]).count();
    assert!(
        reddest > 150 && greener == 0,
        "colour off: max r {reddest}, {greener} greener pixels"
    );
}

#[test]
fn a_graph_effect_runs_its_groups_and_events() {
    let _one = serial();
    // Rockets rise and burst into sparks by events: after a second both groups are drawn.
    let effects = concat!(env!("CARGO_MANIFEST_DIR"), "/../../effects");
    let mut h = Harness::new(std::path::Path::new(effects));
    let handle = h.load("fireworks.ron");
    h.app.world_mut().spawn((
        PlumeEffect::new(handle).with_warm_up(2.5),
        Transform::from_xyz(0.0, -4.0, -8.0),
    ));
    h.update(30);
    let image = h.capture_running();
    let (n, _, y) = lit_pixels(&image, 60);
    assert!(n > 20, "only {n} lit pixels: the fireworks did not draw");
    // Everything drawn is above the launch point (the entity at y = -4 m).
    let (_, launch_y) = project(0.0, -4.0 * 10.0 / 18.0);
    assert!(
        y < launch_y,
        "light centred at y {y:.1}, below the launch point {launch_y:.1}"
    );
}

#[test]
fn a_broken_file_keeps_the_last_good_effect_and_a_fix_reloads() {
    let _one = serial();
    let dir = asset_dir("reload");
    let file = dir.join("dots.plume.ron");
    std::fs::write(&file, dots(300, 100.0, (1.0, 0.2, 0.1))).unwrap();
    let mut h = Harness::with_watching(&dir, true);
    let handle = h.load("dots.plume.ron");
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    h.update(10);
    let red = h.capture_running();
    assert!(
        lit_pixels(&red, 40).0 >= 4,
        "the first version did not draw"
    );

    // A typo in a field name: the loader's error names the file, line and column.
    let broken = dots(300, 100.0, (1.0, 0.2, 0.1)).replace("capacity:", "capacty:");
    std::fs::write(&file, broken).unwrap();
    let reported = h.update_until(200, Duration::from_millis(50), |h| {
        !h.load_errors.lock().unwrap().is_empty()
    });
    assert!(reported, "no load error after the file broke");
    let message = h.load_errors.lock().unwrap().join("\n");
    assert!(
        message.contains("dots.plume.ron:1:") && message.contains("capacty"),
        "the error does not locate the typo: {message}"
    );
    h.update(5);
    let (n, _, _) = lit_pixels(&h.capture(), 40);
    assert!(
        n >= 4,
        "the last good effect stopped drawing after a broken reload"
    );

    // Fixed, and now green: the new version replaces the old one.
    std::fs::write(&file, dots(300, 100.0, (0.1, 1.0, 0.2))).unwrap();
    let green = h.update_until(200, Duration::from_millis(50), |h| {
        let image = h.capture();
        image.pixels().any(|p| p.0[1] > 150 && p.0[0] < 120)
    });
    assert!(green, "the fixed file never replaced the running effect");
}

/// A burst of long-lived dots under a parent at x = -3 m, in `space`; the parent then moves
/// to x = +3 m. Returns (lit pixels, their mean x) before and after the move.
fn move_parent(name: &str, space: SimulationSpace) -> ((u32, f32), (u32, f32)) {
    let dir = asset_dir(name);
    std::fs::write(
        dir.join("dots.plume.ron"),
        dots(300, 100.0, (1.0, 1.0, 1.0)),
    )
    .unwrap();
    let mut h = Harness::new(&dir);
    let handle = h.load("dots.plume.ron");
    let parent = h
        .app
        .world_mut()
        .spawn((Transform::from_xyz(-3.0, 0.0, 0.0), Visibility::default()))
        .with_child(PlumeEffect::new(handle).with_space(space))
        .id();
    h.update(10);
    let (n, before, _) = lit_pixels(&h.capture_running(), 40);
    h.app
        .world_mut()
        .entity_mut(parent)
        .insert(Transform::from_xyz(3.0, 0.0, 0.0));
    h.update(3);
    let (m, after, _) = lit_pixels(&h.capture_running(), 40);
    ((n, before), (m, after))
}

#[test]
fn a_local_space_effect_moves_with_its_parent() {
    let _one = serial();
    let ((n, before), (m, after)) = move_parent("local", SimulationSpace::Local);
    let (left, right) = (project(-3.0, 0.0).0, project(3.0, 0.0).0);
    assert!(n >= 4 && m >= 4, "{n} then {m} lit pixels");
    assert!(
        (before - left).abs() < PLACE_TOLERANCE_PX,
        "at {before:.1}, expected {left:.1}"
    );
    assert!(
        (after - right).abs() < PLACE_TOLERANCE_PX,
        "at {after:.1}, expected {right:.1}"
    );
}

#[test]
fn a_world_space_effect_leaves_its_particles_behind() {
    let _one = serial();
    // One burst at the start, living 100 s: wherever the parent goes, they stay put.
    let ((n, before), (m, after)) = move_parent("world", SimulationSpace::World);
    let left = project(-3.0, 0.0).0;
    assert!(n >= 4 && m >= 4, "{n} then {m} lit pixels");
    assert!(
        (before - left).abs() < PLACE_TOLERANCE_PX,
        "at {before:.1}, expected {left:.1}"
    );
    assert!(
        (after - left).abs() < PLACE_TOLERANCE_PX,
        "moved with the parent to {after:.1}"
    );
}

#[test]
fn restart_and_pause_control_an_instance() {
    let _one = serial();
    // Dots that live 0.5 s: after a second they are gone unless restarted.
    let (mut h, handle) = Harness::with_effect("control", &dots(300, 0.5, (1.0, 1.0, 1.0)));
    let fx = h.app.world_mut().spawn(PlumeEffect::new(handle)).id();
    h.update(70);
    assert_eq!(
        lit_pixels(&h.capture(), 40).0,
        0,
        "the dots outlived their 0.5 s"
    );
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(fx)
        .unwrap()
        .restart();
    h.update(2);
    assert!(
        lit_pixels(&h.capture(), 40).0 >= 4,
        "restart did not burst again"
    );
    // Paused, time stands still: a second later they are still there.
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(fx)
        .unwrap()
        .playing = false;
    h.update(70);
    assert!(
        lit_pixels(&h.capture_running(), 40).0 >= 4,
        "paused dots died"
    );
}

#[test]
fn churn_never_leaks_loses_or_draws_the_gone() {
    let _one = serial();
    let dir = asset_dir("churn");
    // Three files of capacities 64 to 20,000 particles: instances come and go with buffers
    // of very different sizes.
    let files = [
        (64, (1.0, 0.2, 0.2)),
        (2_000, (0.2, 1.0, 0.2)),
        (20_000, (0.2, 0.2, 1.0)),
    ];
    for (i, (count, rgb)) in files.iter().enumerate() {
        std::fs::write(
            dir.join(format!("c{i}.plume.ron")),
            dots(*count, 100.0, *rgb),
        )
        .unwrap();
    }
    let mut h = Harness::new(&dir);
    let handles: Vec<_> = (0..files.len())
        .map(|i| h.load(&format!("c{i}.plume.ron")))
        .collect();
    let stats = |h: &Harness| {
        *h.app
            .sub_app(bevy::render::RenderApp)
            .world()
            .resource::<PlumeRenderStats>()
    };
    h.update(3);
    let empty = stats(&h);
    assert_eq!((empty.instances, empty.particle_bytes), (0, 0));
    // A first round of every file coming and going, so that the one-time pools (wgpu's
    // indirect-draw validation buffers, Bevy's phase buffers) exist before the baseline.
    let warm: Vec<Entity> = (0..30)
        .map(|i| {
            let effect = PlumeEffect::new(handles[i % files.len()].clone());
            h.app.world_mut().spawn(effect).id()
        })
        .collect();
    h.update(3);
    for e in warm {
        h.app.world_mut().despawn(e);
    }
    h.update(3);
    h.capture();
    h.update(2);
    let memory_before = gpu_memory(&h);
    // One survivor that lives through the whole churn, on the right.
    let survivor = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handles[0].clone()),
            Transform::from_xyz(4.0, 0.0, 0.0),
        ))
        .id();
    // A fixed pseudo-random sequence (a 32-bit LCG), so the run is the same every time.
    let mut state = 12_345u32;
    let mut next = move |n: u32| {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) % n
    };
    let mut alive: Vec<Entity> = Vec::new();
    let mut peak = 0;
    for frame in 0..240u32 {
        if frame % 3 == 0 {
            // Churners stand on the left, where nothing else is.
            let x = -2.0 - next(40) as f32 * 0.1;
            let file = next(files.len() as u32) as usize;
            let id = h
                .app
                .world_mut()
                .spawn((
                    PlumeEffect::new(handles[file].clone()),
                    Transform::from_xyz(x, next(20) as f32 * 0.1 - 1.0, 0.0),
                ))
                .id();
            alive.push(id);
        }
        while alive.len() > 12 || (!alive.is_empty() && next(4) == 0) {
            let gone = alive.swap_remove(next(alive.len() as u32) as usize);
            h.app.world_mut().despawn(gone);
        }
        h.update(1);
        let now = stats(&h);
        // Every live effect entity (and no other) has its instance, the frame it exists.
        assert_eq!(now.instances, alive.len() + 1, "frame {frame}: instances");
        peak = peak.max(now.particle_bytes);
    }
    assert!(
        peak > 20_000 * 16,
        "the churn never held a large effect ({peak} bytes)"
    );
    // Then a thousand small instances alive at once: fifty more a frame, a few going at
    // random, two capacities.
    let small: Vec<_> = (0..2)
        .map(|i| {
            let name = format!("s{i}.plume.ron");
            std::fs::write(dir.join(&name), dots(64 << (2 * i), 100.0, (1.0, 0.2, 0.2))).unwrap();
            h.load(&name)
        })
        .collect();
    let mut frame = 0;
    while alive.len() < 1_000 {
        for _ in 0..50 {
            let x = -2.0 - next(40) as f32 * 0.1;
            let effect = PlumeEffect::new(small[next(2) as usize].clone());
            let id = h
                .app
                .world_mut()
                .spawn((effect, Transform::from_xyz(x, 0.0, 0.0)))
                .id();
            alive.push(id);
        }
        for _ in 0..next(4) {
            let gone = alive.swap_remove(next(alive.len() as u32) as usize);
            h.app.world_mut().despawn(gone);
        }
        h.update(1);
        frame += 1;
        assert_eq!(stats(&h).instances, alive.len() + 1, "ramp frame {frame}");
    }
    // Then churn at about a thousand alive, up to frame 1,000 of the whole run: every frame a
    // few of any file go and as many come (the small ones batched, the others alone), so
    // batches fill, empty, are freed and made again.
    let every: Vec<_> = handles.iter().chain(&small).cloned().collect();
    let mut batched_frames = 0;
    for frame in 240 + frame..1_000 {
        for _ in 0..1 + next(6) {
            let gone = alive.swap_remove(next(alive.len() as u32) as usize);
            h.app.world_mut().despawn(gone);
        }
        while alive.len() < 1_000 {
            let x = -2.0 - next(40) as f32 * 0.1;
            // Mostly the small files: the large ones would grow the churn past lavapipe's
            // patience, a few are enough to come and go.
            let file = match next(10) {
                0 => next(3) as usize,
                _ => 3 + next(2) as usize,
            };
            let effect = PlumeEffect::new(every[file].clone());
            let id = h
                .app
                .world_mut()
                .spawn((
                    effect,
                    Transform::from_xyz(x, next(20) as f32 * 0.1 - 1.0, 0.0),
                ))
                .id();
            alive.push(id);
        }
        h.update(1);
        let now = stats(&h);
        assert_eq!(now.instances, alive.len() + 1, "churn frame {frame}");
        batched_frames += usize::from(now.batches > 0);
        peak = peak.max(now.particle_bytes);
    }
    assert!(batched_frames > 0, "the crowd never ran batched");
    for gone in alive.drain(..) {
        h.app.world_mut().despawn(gone);
    }
    h.update(2);
    // The survivor lost none of its 64 particles through it all.
    let survivor_totals = totals(&h, survivor);
    assert_eq!((survivor_totals.spawned, survivor_totals.alive), (64, 64));
    let image = h.capture_running();
    // The survivor is still drawn, where it stands; nothing is left on the left.
    let (n, x, _) = lit_pixels(&image, 40);
    let right = project(4.0, 0.0).0;
    assert!(
        n >= 4 && (x - right).abs() < PLACE_TOLERANCE_PX,
        "{n} lit pixels centred at {x:.1}, the survivor at {right:.1}"
    );
    let leftover = image
        .enumerate_pixels()
        .filter(|(px, _, p)| (*px as f32) < WIDTH as f32 * 0.45 && p.0[..3].iter().any(|&c| c > 40))
        .count();
    assert_eq!(leftover, 0, "despawned effects still drawn");
    h.app.world_mut().despawn(survivor);
    h.update(3);
    h.capture();
    h.update(2);
    assert_eq!(
        stats(&h),
        empty,
        "the plugin holds GPU state after every effect went"
    );
    // And the driver's allocator holds what it held before the churn: as many allocations,
    // and the same bytes within 1 KiB (Bevy's small uniform buffers change size by a few
    // bytes from frame to frame; a leaked instance would add its dozen or so allocations,
    // its steps' parameters alone 256 slots of at least 80 bytes), so every buffer of every
    // instance was freed.
    let memory_after = gpu_memory(&h);
    let (bytes_before, count_before) = memory_totals(&memory_before);
    let (bytes_after, count_after) = memory_totals(&memory_after);
    assert!(
        count_after == count_before && bytes_after.abs_diff(bytes_before) < 1024,
        "GPU memory before the churn ({bytes_before} bytes, {count_before} allocations), \
         after ({bytes_after} bytes, {count_after} allocations); added: {:?}",
        memory_added(&memory_before, &memory_after)
    );
}

/// One allocation the driver's allocator reports: its buffer's label and its size in bytes.
type Allocation = (String, u64);

/// The bytes and the number of allocations in a memory report.
fn memory_totals(allocations: &[Allocation]) -> (u64, usize) {
    (allocations.iter().map(|a| a.1).sum(), allocations.len())
}

/// The allocations in `after` that `before` has not (by label and size), to name a leak.
fn memory_added(before: &[Allocation], after: &[Allocation]) -> Vec<Allocation> {
    let mut unmatched = before.to_vec();
    after
        .iter()
        .filter(|a| match unmatched.iter().position(|b| b == *a) {
            Some(i) => {
                unmatched.swap_remove(i);
                false
            }
            None => true,
        })
        .cloned()
        .collect()
}

/// The GPU memory the app holds, from the Vulkan allocator's report, leaving out wgpu's own
/// pools, which neither Plume nor Bevy owns:
/// - the in-flight staging buffers (a few bytes of uploads that come and go every frame);
/// - the indirect-draw validation buffers (1 MiB each), taken per command buffer and kept
///   for reuse once it has run: how many exist depends on how many of the app's command
///   buffers were in flight at once, which is the driver's timing, not the plugin's doing.
fn gpu_memory(h: &Harness) -> Vec<Allocation> {
    let device = h
        .app
        .sub_app(RenderApp)
        .world()
        .resource::<bevy::render::renderer::RenderDevice>();
    let report = device
        .wgpu_device()
        .generate_allocator_report()
        .expect("an allocator report (Vulkan: lavapipe on a machine without a GPU)");
    report
        .allocations
        .iter()
        .filter(|a| {
            a.name != "(wgpu internal) Staging"
                && !a
                    .name
                    .starts_with("(wgpu internal) Indirect draw validation")
        })
        .map(|a| (a.name.clone(), a.size))
        .collect()
}

#[test]
fn a_fast_world_space_emitter_spawns_along_its_way_within_a_frame() {
    let _one = serial();
    let dir = asset_dir("streak");
    // Four steps a frame (dt = 1/240 s at 60 frames a second), ten particles a step, still.
    let source = r#"Effect(name: "streak", capacity: 4000, seed: 3, dt: 0.004166666666666667,
    emitters: [Emitter(rate: 2400.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)),
        lifetime: Some((100.0, 100.0)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.15)], blend: Additive))"#;
    std::fs::write(dir.join("streak.plume.ron"), source).unwrap();
    let mut h = Harness::new(&dir);
    let handle = h.load("streak.plume.ron");
    let fx = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle),
            Transform::from_xyz(-3.0, 0.0, 0.0),
        ))
        .id();
    h.update(3);
    // One frame's jump of 6 m: its four steps spawn at -1.5, 0, 1.5 and 3 m.
    h.app
        .world_mut()
        .entity_mut(fx)
        .insert(Transform::from_xyz(3.0, 0.0, 0.0));
    h.update(1);
    let image = h.capture_running();
    let lit_near = |x: f32| {
        let (cx, cy) = project(x, 0.0);
        image
            .enumerate_pixels()
            .filter(|(px, py, p)| {
                (*px as f32 + 0.5 - cx).abs() < 2.0
                    && (*py as f32 + 0.5 - cy).abs() < 2.0
                    && p.0[..3].iter().any(|&c| c > 40)
            })
            .count()
    };
    for x in [-3.0, -1.5, 0.0, 1.5, 3.0] {
        assert!(lit_near(x) > 0, "nothing spawned at x = {x} m");
    }
    // Between the steps' places, nothing: the parts are where the motion puts them.
    assert_eq!(
        lit_near(-0.75) + lit_near(0.75),
        0,
        "particles between the steps' places"
    );
}

/// Dots that only bursts from code spawn (the emitter has no rate nor burst of its own),
/// pushed along +x by the param `push` (m/s², read at run time).
const PUSHED_DOTS: &str = r#"Effect(name: "pushed", capacity: 2000, seed: 3,
    params: {"push": 0.0},
    emitters: [Emitter(shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.05),
        velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((100.0, 100.0)))],
    forces: [Custom(accel: "vec3(push, 0, 0) - 2.0 * v")],
    integrator: SemiImplicitEuler,
    render: Render(color: [(0.0, (0.2, 1.0, 0.2, 1.0)), (1.0, (0.2, 1.0, 0.2, 1.0))],
        size: [(0.0, 0.15), (1.0, 0.15)], blend: Additive))
"#;

/// A fresh harness (assets in a folder named `name`) with the pushed dots loaded and one
/// effect of them spawned, as `effect` makes it.
fn pushed_dots(name: &str, effect: impl FnOnce(PlumeEffect) -> PlumeEffect) -> (Harness, Entity) {
    let dir = asset_dir(name);
    std::fs::write(dir.join("pushed.plume.ron"), PUSHED_DOTS).unwrap();
    let mut h = Harness::new(&dir);
    let handle = h.load("pushed.plume.ron");
    let entity = h
        .app
        .world_mut()
        .spawn(effect(PlumeEffect::new(handle)))
        .id();
    (h, entity)
}

/// The counts of `entity`'s effect (top-level group), read back from the GPU.
fn totals(h: &Harness, entity: Entity) -> Totals {
    bevy_plume::read_totals(h.app.sub_app(RenderApp).world(), entity, 0)
        .expect("an instance")
        .expect("a readback")
}

/// The live particles of `entity`'s effect (top-level group), read back from the GPU.
fn particles(h: &Harness, entity: Entity) -> Vec<ParticleRecord> {
    bevy_plume::read_particles(h.app.sub_app(RenderApp).world(), entity, 0)
        .expect("an instance")
        .expect("a readback")
}

#[test]
fn a_burst_from_code_emits_exactly_its_count_where_it_is_fired() {
    let _one = serial();
    let (mut h, entity) = pushed_dots("burst", PlumeEffect::with_bursts);
    h.update(3);
    assert_eq!(totals(&h, entity).spawned, 0, "nothing before a burst");
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(entity)
        .unwrap()
        .burst(PlumeBurst::new(137).at(Vec3::new(-2.0, 1.0, 0.0)));
    h.update(1);
    let after = totals(&h, entity);
    assert_eq!((after.spawned, after.alive, after.dropped), (137, 137, 0));
    // Fired once: the next frames spawn nothing more.
    h.update(3);
    assert_eq!(totals(&h, entity).spawned, 137);
    let fired = particles(&h, entity);
    let far = fired
        .iter()
        .filter(|r| {
            (r.position - bevy_plume::plume_runtime::glam::DVec3::new(-2.0, 1.0, 0.0)).length()
                > 0.06
        })
        .count();
    assert_eq!((fired.len(), far), (137, 0));
    // Drawn where they were fired.
    let (n, x, y) = lit_pixels(&h.capture_running(), 40);
    let (ex, ey) = project(-2.0, 1.0);
    assert!(
        n >= 4 && (x - ex).abs() < PLACE_TOLERANCE_PX && (y - ey).abs() < PLACE_TOLERANCE_PX,
        "{n} lit pixels centred at ({x:.1}, {y:.1}), the burst at ({ex:.1}, {ey:.1})"
    );
}

#[test]
fn a_param_changed_from_code_acts_on_the_next_frame() {
    let _one = serial();
    let (mut h, entity) = pushed_dots("param", |e| e.with_bursts().with_param("push", 0.0));
    h.update(2);
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(entity)
        .unwrap()
        .burst(PlumeBurst::new(50));
    h.update(5);
    let speeds =
        |h: &Harness| -> Vec<f64> { particles(h, entity).iter().map(|r| r.velocity.x).collect() };
    assert!(speeds(&h).iter().all(|&v| v == 0.0), "no push yet");
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(entity)
        .unwrap()
        .set_param("push", 30.0);
    h.update(1);
    // One step of 1/60 s under 30 m/s² from rest: v = 0.5 m/s (semi-implicit Euler, the
    // drag reading v before the step).
    let pushed = speeds(&h);
    assert_eq!(pushed.len(), 50);
    assert!(
        pushed.iter().all(|&v| (v - 0.5).abs() < 1e-4),
        "after one frame: {:?}",
        &pushed[..3]
    );
    // Still the same instance (no rebuild): the particles were not spawned again.
    assert_eq!(totals(&h, entity).spawned, 50);
}

#[test]
fn declared_bounds_cull_an_effect_out_of_view() {
    let _one = serial();
    let dir = asset_dir("bounds");
    let dots_file = dots(300, 100.0, (1.0, 1.0, 1.0));
    let with_bounds = |min: &str, max: &str| {
        let close = dots_file
            .rfind(')')
            .expect("the effect's closing parenthesis");
        format!(
            "{}, bounds: Some(Bounds(min: {min}, max: {max})))\n",
            &dots_file[..close]
        )
    };
    // Bounds that hold the dots (in view), and bounds that the author got wrong, 100 m to
    // the side (out of view): Bevy culls by the box, not by the particles.
    std::fs::write(
        dir.join("held.plume.ron"),
        with_bounds("(-0.5, -0.5, -0.5)", "(0.5, 0.5, 0.5)"),
    )
    .unwrap();
    std::fs::write(
        dir.join("aside.plume.ron"),
        with_bounds("(100.0, 0.0, 0.0)", "(101.0, 1.0, 1.0)"),
    )
    .unwrap();
    let mut h = Harness::new(&dir);
    let held = h.load("held.plume.ron");
    let aside = h.load("aside.plume.ron");
    let entity = h.app.world_mut().spawn(PlumeEffect::new(held)).id();
    h.update(5);
    let aabb = *h
        .app
        .world()
        .get::<bevy::camera::primitives::Aabb>(entity)
        .expect("the file's bounds became the entity's Aabb");
    assert_eq!(aabb.half_extents, Vec3::splat(0.5).into());
    assert!(
        lit_pixels(&h.capture_running(), 40).0 >= 4,
        "in view: drawn"
    );
    h.app.world_mut().despawn(entity);
    let entity = h.app.world_mut().spawn(PlumeEffect::new(aside)).id();
    h.update(5);
    let image = h.capture();
    assert_eq!(
        lit_pixels(&image, 40).0,
        0,
        "the box is out of view: culled"
    );
    // It still runs, and it is the culling that hid it: without culling it is drawn.
    assert_eq!(totals(&h, entity).alive, 300);
    h.app
        .world_mut()
        .entity_mut(entity)
        .insert(bevy::camera::visibility::NoFrustumCulling);
    h.update(2);
    assert!(
        lit_pixels(&h.capture_running(), 40).0 >= 4,
        "unculled: drawn"
    );
}

/// Two opaque discs 1 m apart on the z axis, drawn with `sort: true` and alpha blending: the
/// one nearer a camera must cover the other there. The front disc (z = +0.5) lives long and
/// stays red; the back one (z = −0.5) lives 2 s and turns green after 0.2 s.
const TWO_DISCS: &str = r#"Effect(name: "two discs", capacity: 2, sort: true,
    emitters: [
        Emitter(burst: 1, shape: Point((0.0, 0.0, 0.5)), velocity: Constant((0.0, 0.0, 0.0)),
            lifetime: Some((1000.0, 1000.0))),
        Emitter(burst: 1, shape: Point((0.0, 0.0, -0.5)), velocity: Constant((0.0, 0.0, 0.0)),
            lifetime: Some((2.0, 2.0))),
    ],
    render: Render(
        color: [(0.0, (1.0, 0.0, 0.0, 1.0)), (0.05, (1.0, 0.0, 0.0, 1.0)), (0.1, (0.0, 1.0, 0.0, 1.0)), (1.0, (0.0, 1.0, 0.0, 1.0))],
        size: [(0.0, 1.5), (1.0, 1.5)],
        blend: Alpha))
"#;

#[test]
fn each_camera_sees_a_sorted_effect_in_its_own_depth_order() {
    let _one = serial();
    let dir = asset_dir("sort");
    std::fs::write(dir.join("discs.plume.ron"), TWO_DISCS).unwrap();
    let mut h = Harness::new(&dir);
    // The harness's camera looks from +z; a second one looks from −z.
    let behind = h.add_camera(
        Transform::from_xyz(0.0, 0.0, -crate::common::CAMERA_DISTANCE)
            .looking_at(Vec3::ZERO, Vec3::Y),
    );
    let handle = h.load("discs.plume.ron");
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    // 0.3 s: the back disc has turned green (its life at 0.15 of 2 s).
    h.update(18);
    let centre = |image: &image::RgbaImage| image.get_pixel(WIDTH / 2, crate::common::HEIGHT / 2).0;
    let front = centre(&h.capture_running());
    let back = centre(&h.capture_of(behind));
    // From +z the red disc is nearer; from −z the green one.
    assert!(
        front[0] > 200 && front[1] < 50,
        "from +z the centre should be the near red disc: {front:?}"
    );
    assert!(
        back[1] > 200 && back[0] < 50,
        "from −z the centre should be the near green disc: {back:?}"
    );
}

/// Dots flying away from the camera at 5 m/s into the view's depth (a `SceneDepth` collider).
const FLYING_DOTS: &str = r#"Effect(name: "flying", capacity: 25, seed: 5,
    emitters: [Emitter(burst: 25, shape: Grid(min: (-1.0, -1.0, 0.0), max: (1.0, 1.0, 0.0), counts: (5, 5, 1)),
        velocity: Constant((0.0, 0.0, -5.0)), lifetime: Some((100.0, 100.0)))],
    collide: [SceneDepth(thickness: 0.5, restitution: 0.0, friction: 1.0)],
    render: Render(color: [(0.0, (0.2, 1.0, 0.2, 1.0)), (1.0, (0.2, 1.0, 0.2, 1.0))],
        size: [(0.0, 0.15), (1.0, 0.15)], blend: Additive))
"#;

#[test]
fn a_scene_depth_collider_meets_what_the_camera_s_depth_prepass_drew() {
    let _one = serial();
    // A wall 2 m in front of the origin (12 m from the camera), drawn by Bevy; the dots fly at
    // it from the origin. With the camera's depth prepass, single-sampled or with MSAA (a
    // multisampled prepass, read by its sample 0), they stop on it; without one they fly on.
    for (msaa, prepass) in [(Msaa::Off, true), (Msaa::Sample4, true), (Msaa::Off, false)] {
        let dir = asset_dir("scene_depth");
        std::fs::write(dir.join("flying.plume.ron"), FLYING_DOTS).unwrap();
        let mut h = Harness::new(&dir);
        let camera = h.camera();
        let mut camera = h.app.world_mut().entity_mut(camera);
        camera.insert(msaa);
        if prepass {
            camera.insert(bevy::core_pipeline::prepass::DepthPrepass);
        }
        h.spawn_wall(20.0, Color::WHITE, Vec3::new(0.0, 0.0, -2.1));
        // Until the wall's pipelines are ready there is no depth to meet, and dots launched
        // now would be past the wall before it appears.
        h.wait_for_pipelines();
        h.update(5);
        let handle = h.load("flying.plume.ron");
        let entity = h.app.world_mut().spawn(PlumeEffect::new(handle)).id();
        h.update(60);
        let dots = particles(&h, entity);
        assert_eq!(dots.len(), 25);
        for d in &dots {
            let z = d.position.z;
            if prepass {
                // On the wall's face at z = -2, in front of it by the depth's rounding and the
                // contact margin (Bevy's reversed-Z depth is fine-grained there: 1e-2 is loose).
                assert!(
                    z > -2.0 && z < -2.0 + 1e-2,
                    "{msaa:?}: a dot at z = {z}, not on the wall at -2"
                );
            } else {
                assert!(z < -4.0, "without a depth prepass a dot stopped at z = {z}");
            }
        }
    }
}

#[test]
fn an_effect_is_reflected_and_edited_by_path_as_an_inspector_does() {
    let _one = serial();
    let (mut h, entity) = pushed_dots("reflect", PlumeEffect::with_bursts);
    h.update(3);
    let steps = totals(&h, entity).steps;
    assert!(steps > 0, "no steps ran");
    // What bevy-inspector-egui does: find the component through the type registry and set
    // a field by its path.
    let registry = h.app.world().resource::<AppTypeRegistry>().clone();
    {
        let registry = registry.read();
        let component = registry
            .get_type_data::<ReflectComponent>(std::any::TypeId::of::<PlumeEffect>())
            .expect("PlumeEffect is registered with ReflectComponent");
        let mut e = h.app.world_mut().entity_mut(entity);
        let mut reflected = component.reflect_mut(&mut e).expect("the entity has one");
        *reflected
            .reflect_path_mut("time_scale")
            .unwrap()
            .try_downcast_mut::<f32>()
            .unwrap() = 0.0;
    }
    // Its time stands still: no more steps.
    h.update(5);
    let frozen = totals(&h, entity).steps;
    h.update(5);
    assert_eq!(
        totals(&h, entity).steps,
        frozen,
        "time_scale 0 set by path did not hold time"
    );
    // A burst fired by a game system ordered before the plugin's set spawns at once.
    h.app.add_systems(
        PostUpdate,
        (move |mut effects: Query<&mut PlumeEffect>| {
            if let Ok(mut e) = effects.get_mut(entity) {
                e.time_scale = 1.0;
                e.burst(PlumeBurst::new(7));
            }
        })
        .before(bevy_plume::PlumeSystems::Bursts),
    );
    let before = totals(&h, entity).spawned;
    h.update(1);
    assert_eq!(totals(&h, entity).spawned, before + 7);
}
