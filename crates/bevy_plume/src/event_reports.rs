//! Reported events in a Bevy game (`Event(.., report: N)` in an effect file): each firing an
//! effect reports becomes a [`PlumeEventFired`] message, which game systems read with a
//! `MessageReader`. The render world reads the reports back after each frame's steps
//! (`Effect::watch_reports`, without waiting) and puts their firings, in world space, into
//! [`FiredEvents`], a queue both worlds hold; the main world writes them as messages here, in
//! `PreUpdate` ([`crate::PlumeSystems::Reports`]), so that `Update` sees them.

use std::sync::{Arc, Mutex};

use bevy::prelude::*;

/// One firing of a reported event: a particle of `entity`'s effect died, hit a collider or
/// reached its period where the file marks the event `report`. It reaches the game at most 3
/// frames after the step it fired in (docs/bevy.md, "Events to game code").
#[derive(Message, Clone, Debug, PartialEq)]
pub struct PlumeEventFired {
    /// The effect entity whose particle fired.
    pub entity: Entity,
    /// The firing group's index (0: the top level; `groups[i]` is i + 1).
    pub group: usize,
    /// The event's index among the group's `events`.
    pub event: usize,
    /// The firing particle's id in its group.
    pub id: u32,
    /// The step it fired at the end of, counted from the instance's start.
    pub step: u64,
    /// Where it fired, in world space.
    pub position: Vec3,
    /// Its velocity then, in world space (m/s).
    pub velocity: Vec3,
}

/// Firings a reported event counted but did not keep in one readback, past its `report`
/// bound: the game heard `kept` of `fired`.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlumeEventsMissed {
    /// The effect entity.
    pub entity: Entity,
    /// The firing group's index.
    pub group: usize,
    /// The event's index among the group's `events`.
    pub event: usize,
    /// Firings counted in the readback.
    pub fired: u64,
    /// Firings kept (each a [`PlumeEventFired`]).
    pub kept: u64,
}

/// What the render world read back, for the main world to send: written by the render world,
/// drained by the main world.
#[derive(Resource, Clone, Default)]
pub(crate) struct FiredEvents(pub Arc<Mutex<Reported>>);

/// The firings and the misses read back since the main world last took them.
#[derive(Default)]
pub(crate) struct Reported {
    pub fired: Vec<PlumeEventFired>,
    pub missed: Vec<PlumeEventsMissed>,
}

impl FiredEvents {
    /// The queue, even if a panicking thread left it poisoned.
    pub(crate) fn lock(&self) -> std::sync::MutexGuard<'_, Reported> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues the reports of `entity`'s effect, whose simulation space maps to the world by
    /// `to_world`.
    pub(crate) fn push(
        &self,
        entity: Entity,
        reports: Vec<plume_runtime::EventReport>,
        to_world: Mat4,
    ) {
        let mut queue = self.lock();
        for report in reports {
            if report.missed() > 0 {
                queue.missed.push(PlumeEventsMissed {
                    entity,
                    group: report.group,
                    event: report.event,
                    fired: report.fired,
                    kept: report.firings.len() as u64,
                });
            }
            queue
                .fired
                .extend(report.firings.iter().map(|f| PlumeEventFired {
                    entity,
                    group: report.group,
                    event: report.event,
                    id: f.id,
                    step: f.step,
                    position: to_world.transform_point3(Vec3::from(f.position)),
                    velocity: to_world.transform_vector3(Vec3::from(f.velocity)),
                }));
        }
    }
}

/// Writes the firings the render world read back as messages.
pub(crate) fn send_fired_events(
    queue: Res<FiredEvents>,
    mut fired: MessageWriter<PlumeEventFired>,
    mut missed: MessageWriter<PlumeEventsMissed>,
) {
    let taken = std::mem::take(&mut *queue.lock());
    fired.write_batch(taken.fired);
    missed.write_batch(taken.missed);
}
