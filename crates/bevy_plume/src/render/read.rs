//! Reading an effect entity's particles back, for tests, tools and debugging: from its
//! instance, or from its place in a batch.

use bevy::prelude::*;
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_runtime::RuntimeError;

use crate::render::batches::PlumeBatches;
use crate::render::instances::PlumeInstances;

/// A batched effect has one group.
fn no_group(group: usize) -> RuntimeError {
    RuntimeError::Control(format!("group {group}: a batched effect has one group"))
}

/// Reads back the live particles of group `group` of `entity`'s effect (the main-world
/// entity; group 0 is the top level), in id order, blocking until the GPU has finished: for
/// tests, tools and debugging, not for every frame. None when the entity has no running
/// instance. Call it with the render app's world, between frames:
/// `read_particles(app.sub_app(RenderApp).world(), entity, 0)`.
pub fn read_particles(
    render_world: &World,
    entity: Entity,
    group: usize,
) -> Option<Result<Vec<ParticleRecord>, RuntimeError>> {
    if let Some(batch) = render_world
        .get_resource::<PlumeBatches>()?
        .batch_of(entity)
    {
        let member = &render_world.resource::<PlumeBatches>().members[&entity];
        return Some(match group {
            0 => batch.batch.records(member.instance),
            _ => Err(no_group(group)),
        });
    }
    let instance = render_world
        .get_resource::<PlumeInstances>()?
        .instances
        .get(&entity)?;
    Some(instance.effect.group_records(group))
}

/// Reads back the counts of group `group` of `entity`'s effect (spawned, alive, dropped,
/// died), blocking like [`read_particles`]. None when the entity has no running instance.
pub fn read_totals(
    render_world: &World,
    entity: Entity,
    group: usize,
) -> Option<Result<Totals, RuntimeError>> {
    if let Some(batch) = render_world
        .get_resource::<PlumeBatches>()?
        .batch_of(entity)
    {
        let member = &render_world.resource::<PlumeBatches>().members[&entity];
        return Some(match group {
            0 => batch.batch.totals(member.instance),
            _ => Err(no_group(group)),
        });
    }
    let instance = render_world
        .get_resource::<PlumeInstances>()?
        .instances
        .get(&entity)?;
    Some(instance.effect.group_totals(group))
}
