//! Reported events in a Bevy app (docs/bevy.md, "Events to game code"), on llvmpipe
//! (lavapipe): a file's `Event(.., report: N)` firings reach game systems as
//! `PlumeEventFired` messages with the entity, in world space, a few frames after the step;
//! firings past the bound arrive as a `PlumeEventsMissed` count.

use crate::common::{serial, Harness};
use bevy::prelude::*;
use bevy_plume::{PlumeEffect, PlumeEventFired, PlumeEventsMissed, SimulationSpace};

/// Eight drops that fall 1 m onto the floor of the effect's space (y = 0) and bounce, every
/// bounce reported, at most `BOUND` a readback. One step a frame (the harness's 1/60 s).
const DROPS: &str = r#"Effect(name: "drops", capacity: 8, seed: 5,
    emitters: [Emitter(burst: 8, shape: Point((0.0, 1.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.0)],
    events: [Event(on: Collide, report: BOUND)])
"#;

/// The step at whose end the drops first touch the floor: on the default integrator
/// (semi-implicit Euler) they have fallen g dt² n (n + 1) / 2 after n steps, 0.957 m after 26
/// and 1.030 m after 27: the 27th step, step 26 counted from 0.
const FIRST_BOUNCE_STEP: u64 = 26;

/// Frames from the one a step runs in to the one whose `Update` hears its firings: the
/// readback's 3 (docs/effect-format.md, "Reported events") and the next frame's `PreUpdate`,
/// which sends what the render world read back after the main world's `Update` had run.
const MOST_FRAMES_PAST_STEP: u64 = 4;

/// What the game heard, with the frame each message came in.
#[derive(Resource, Default)]
struct Heard {
    frame: u64,
    fired: Vec<(u64, PlumeEventFired)>,
    missed: Vec<PlumeEventsMissed>,
}

fn listen(
    mut heard: ResMut<Heard>,
    mut fired: MessageReader<PlumeEventFired>,
    mut missed: MessageReader<PlumeEventsMissed>,
) {
    heard.frame += 1;
    let frame = heard.frame;
    heard.fired.extend(fired.read().map(|m| (frame, m.clone())));
    heard.missed.extend(missed.read().copied());
}

fn app(bound: u32) -> (Harness, Handle<bevy_plume::PlumeEffectAsset>) {
    let (mut h, handle) = Harness::with_effect(
        &format!("reports-{bound}"),
        &DROPS.replace("BOUND", &bound.to_string()),
    );
    h.app.init_resource::<Heard>().add_systems(Update, listen);
    (h, handle)
}

#[test]
fn bounces_reach_game_code_in_world_space() {
    let _one = serial();
    let (mut h, handle) = app(64);
    // A world-space effect: its floor is the world's (y = 0), its drops start 1 m above the
    // entity. A local-space one: its floor and drops move with the entity.
    let world = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle.clone()),
            Transform::from_xyz(5.0, 0.0, 0.0),
        ))
        .id();
    let local = h
        .app
        .world_mut()
        .spawn((
            PlumeEffect::new(handle).with_space(SimulationSpace::Local),
            Transform::from_xyz(-5.0, 2.0, 1.0),
        ))
        .id();
    // The frame (1 for the first update) each step ran in, as the render world counts steps.
    // Until both entities' first bounces are heard and the frames they may take have passed
    // (at most 600: an instance starts once its variant is compiled, later on a busy machine).
    let mut ran_in = std::collections::HashMap::new();
    let mut heard_by = None;
    for frame in 1..=600 {
        h.update(1);
        let render = h.app.sub_app(bevy::render::RenderApp).world();
        let steps = bevy_plume::read_totals(render, world, 0).map_or(0, |t| t.unwrap().steps);
        for step in ran_in.len() as u64..steps {
            ran_in.insert(step, frame);
        }
        let heard = h.app.world().resource::<Heard>();
        let bounced = |e: Entity| {
            heard
                .fired
                .iter()
                .any(|(_, m)| m.entity == e && m.step == FIRST_BOUNCE_STEP)
        };
        if heard_by.is_none() && bounced(world) && bounced(local) {
            heard_by = Some(frame);
        }
        if heard_by.is_some_and(|by| frame > by + MOST_FRAMES_PAST_STEP) {
            break;
        }
    }
    assert!(heard_by.is_some(), "no bounce heard in 600 frames");
    let heard = h.app.world().resource::<Heard>();
    assert!(heard.missed.is_empty());
    for (entity, at) in [
        (world, Vec3::new(5.0, 0.0, 0.0)),
        (local, Vec3::new(-5.0, 2.0, 1.0)),
    ] {
        let bounces: Vec<&(u64, PlumeEventFired)> = heard
            .fired
            .iter()
            .filter(|(_, m)| m.entity == entity)
            .collect();
        let first: Vec<_> = bounces
            .iter()
            .filter(|(_, m)| m.step == FIRST_BOUNCE_STEP)
            .collect();
        assert_eq!(
            first.len(),
            8,
            "{entity}: the eight drops' first bounce, once each: {bounces:?}"
        );
        let mut ids: Vec<u32> = first.iter().map(|(_, m)| m.id).collect();
        ids.sort();
        assert_eq!(ids, (0..8).collect::<Vec<_>>());
        for (frame, m) in &first {
            // On the floor (the step's end leaves it within a step's rise of it), going up at
            // half the 27 g dt = 4.41 m/s it hit with.
            assert!(
                (m.position - at).length() < 0.05,
                "{entity}: bounced at {} (the floor under the entity is at {at})",
                m.position
            );
            assert!(m.velocity.y > 2.1 && m.velocity.y < 2.3, "{}", m.velocity);
            if entity == world {
                let ran = ran_in[&m.step];
                assert!(
                    *frame <= ran + MOST_FRAMES_PAST_STEP,
                    "step {} ran in frame {ran}, its firing came in frame {frame}",
                    m.step
                );
            }
        }
    }
}

#[test]
fn firings_past_the_bound_are_counted() {
    let _one = serial();
    let (mut h, handle) = app(4);
    let entity = h.app.world_mut().spawn(PlumeEffect::new(handle)).id();
    let heard_all = h.update_until(600, std::time::Duration::ZERO, |h| {
        let heard = h.app.world().resource::<Heard>();
        heard.fired.iter().any(|(_, m)| m.step == FIRST_BOUNCE_STEP)
    });
    assert!(heard_all, "no bounce heard in 600 frames");
    // A readback holds the whole step: its misses come with it.
    h.update(MOST_FRAMES_PAST_STEP as u32);
    let heard = h.app.world().resource::<Heard>();
    let first: Vec<_> = heard
        .fired
        .iter()
        .filter(|(_, m)| m.step == FIRST_BOUNCE_STEP)
        .collect();
    assert_eq!(first.len(), 4, "the bound: four of the eight");
    assert_eq!(
        heard.missed,
        [PlumeEventsMissed {
            entity,
            group: 0,
            event: 0,
            fired: 8,
            kept: 4
        }]
    );
}
