//! A crowd of one effect file runs batched: one Plume `EffectBatch` for all its entities,
//! each entity still its own (its particles where it stands, its bursts, its pause), and the
//! batch freed when its last entity goes. Headless on lavapipe.

use crate::common::{dots, lit_pixels, project, serial, Harness};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy_plume::{
    read_particles, read_totals, PlumeBurst, PlumeDraw, PlumeEffect, PlumeRenderStats,
    SimulationSpace, BATCH_FROM,
};

fn stats(h: &Harness) -> PlumeRenderStats {
    *h.app
        .sub_app(RenderApp)
        .world()
        .resource::<PlumeRenderStats>()
}

/// Where entity k of the crowd stands: a row across the view.
fn x_of(k: usize) -> f32 {
    -4.4 + 0.8 * k as f32
}

/// Lit pixels in the columns nearer to where `x` projects than to its neighbours'.
fn lit_near(image: &image::RgbaImage, x: f32) -> usize {
    let (px, _) = project(x, 0.0);
    let half = (project(x + 0.8, 0.0).0 - px).abs() / 2.0;
    image
        .enumerate_pixels()
        .filter(|(col, _, p)| (*col as f32 - px).abs() < half && p.0[1] > 40)
        .count()
}

/// `n` entities of `effect` in a row, entity k at `x_of(k)`.
fn spawn_row(h: &mut Harness, n: usize, effect: impl Fn() -> PlumeEffect) -> Vec<Entity> {
    (0..n)
        .map(|k| {
            let at = Transform::from_xyz(x_of(k), 0.0, 0.0);
            h.app.world_mut().spawn((effect(), at)).id()
        })
        .collect()
}

fn render(h: &Harness) -> &World {
    h.app.sub_app(RenderApp).world()
}

#[test]
fn a_crowd_of_one_file_runs_as_one_batch_each_entity_its_own() {
    let _one = serial();
    // 40 dots each, room for a burst of 17 more.
    let file = dots(40, 100.0, (0.2, 1.0, 0.2)).replace("capacity: 40", "capacity: 64");
    let (mut h, handle) = Harness::with_effect("batches", &file);
    let crowd = 12;
    assert!(crowd >= BATCH_FROM);
    let entities = spawn_row(&mut h, crowd, || {
        PlumeEffect::new(handle.clone()).with_bursts()
    });
    h.update(4);
    let now = stats(&h);
    assert_eq!((now.instances, now.batches), (crowd, 1), "{now:?}");
    assert_eq!(now.draws, 1, "one draw for the whole crowd: {now:?}");
    // One pauses: its particles stop ageing while the others' age on.
    let ages = |h: &Harness, entity| {
        let particles = read_particles(render(h), entity, 0)
            .expect("batched")
            .expect("read");
        particles.iter().map(|p| p.age).sum::<f64>() / particles.len().max(1) as f64
    };
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(entities[3])
        .unwrap()
        .playing = false;
    h.update(1);
    let (paused_before, playing_before) = (ages(&h, entities[3]), ages(&h, entities[4]));
    h.update(3);
    assert_eq!(ages(&h, entities[3]), paused_before, "the paused one aged");
    assert!(
        ages(&h, entities[4]) > playing_before,
        "the playing one did not age"
    );
    // Each entity's 40 particles, where it stands (world space).
    for (k, &entity) in entities.iter().enumerate() {
        let particles = read_particles(render(&h), entity, 0)
            .expect("batched")
            .expect("read");
        assert_eq!(particles.len(), 40, "entity {k}");
        assert!(
            particles
                .iter()
                .all(|p| (p.position.x - f64::from(x_of(k))).abs() < 0.3),
            "entity {k}'s particles are where it stands"
        );
    }
    // A burst from code on one of them: exactly its count, on that one only.
    h.app
        .world_mut()
        .get_mut::<PlumeEffect>(entities[5])
        .unwrap()
        .burst(PlumeBurst::new(17).at(Vec3::new(0.0, 0.5, 0.0)));
    h.update(2);
    for (k, &entity) in entities.iter().enumerate() {
        let totals = read_totals(render(&h), entity, 0)
            .expect("batched")
            .expect("read");
        let expected = if k == 5 { 57 } else { 40 };
        assert_eq!(totals.spawned, expected, "entity {k}");
    }
    // Drawn where each stands.
    let image = h.capture_running();
    for k in 0..crowd {
        assert!(lit_near(&image, x_of(k)) > 0, "entity {k} is drawn");
    }
    // Half go: their particles are drawn no more, the rest still are, in the same batch.
    for &entity in entities.iter().step_by(2) {
        h.app.world_mut().despawn(entity);
    }
    h.update(2);
    let now = stats(&h);
    assert_eq!((now.instances, now.batches), (crowd / 2, 1), "{now:?}");
    let image = h.capture_running();
    for k in 0..crowd {
        let lit = lit_near(&image, x_of(k));
        assert_eq!(lit > 0, k % 2 == 1, "entity {k} ({lit} lit pixels)");
    }
    // The last ones go: the batch is freed.
    for &entity in entities.iter().skip(1).step_by(2) {
        h.app.world_mut().despawn(entity);
    }
    h.update(2);
    let now = stats(&h);
    assert_eq!(
        (now.instances, now.batches, now.particle_bytes),
        (0, 0, 0),
        "{now:?}"
    );
    let (lit, _, _) = lit_pixels(&h.capture(), 40);
    assert_eq!(lit, 0, "nothing is drawn once every entity went");
}

#[test]
fn a_batched_crowd_in_local_space_moves_with_its_entities() {
    let _one = serial();
    crowd_in_local_space("batches_local", PlumeDraw::Auto);
}

#[test]
fn a_batched_crowd_drawn_by_the_compute_renderer_moves_with_its_entities() {
    let _one = serial();
    crowd_in_local_space("batches_local_compute", PlumeDraw::Compute);
}

/// Ten local-space entities of one file batched, drawn by `draw` (`Auto`: the raster renderer,
/// for so few particles): lifted 1.5 m, their particles are drawn lifted with them, and read
/// back in each entity's own space.
fn crowd_in_local_space(name: &str, draw: PlumeDraw) {
    // Stateful as written (in local space the file is compiled as written, and these dots
    // would be stateless: their particles computed in the draw, nothing to batch).
    let file = dots(40, 100.0, (0.2, 1.0, 0.2)).replace(
        r#"Effect(name: "dots","#,
        r#"Effect(name: "dots", state: Stateful,"#,
    );
    let (mut h, handle) = Harness::with_effect(name, &file);
    let entities = spawn_row(&mut h, 10, || {
        PlumeEffect::new(handle.clone())
            .with_space(SimulationSpace::Local)
            .with_draw(draw)
    });
    h.update(3);
    let now = stats(&h);
    assert_eq!((now.instances, now.batches), (10, 1), "{now:?}");
    let compute_draws = usize::from(draw == PlumeDraw::Compute);
    assert_eq!(
        (now.draws, now.compute_draws),
        (1, compute_draws),
        "one draw for the batch, by the {draw:?} renderer: {now:?}"
    );
    // Every entity goes up 1.5 m: its particles, in its own space, go with it.
    for &entity in &entities {
        h.app
            .world_mut()
            .get_mut::<Transform>(entity)
            .unwrap()
            .translation
            .y = 1.5;
    }
    h.update(2);
    let image = h.capture_running();
    let (lit, x, y) = lit_pixels(&image, 40);
    let (_, up) = project(0.0, 1.5);
    let (_, down) = project(0.0, 0.0);
    assert!(lit > 10, "{lit} lit pixels");
    assert!(
        (y - up).abs() < (up - down).abs() / 4.0,
        "the particles' rows centre at {y:.1}: the entities stand at {up:.1} (they were at {down:.1})"
    );
    let (left, right) = (project(x_of(0), 1.5).0, project(x_of(9), 1.5).0);
    assert!(
        x > left && x < right,
        "centred at column {x:.1}, the row spans {left:.1} to {right:.1}"
    );
    // Read back in each entity's own space: still around its origin.
    for (k, &entity) in entities.iter().enumerate() {
        let particles = read_particles(render(&h), entity, 0)
            .expect("batched")
            .expect("read");
        assert!(
            particles.iter().all(|p| p.position.length() < 0.3),
            "entity {k}'s particles in its own space"
        );
    }
}
