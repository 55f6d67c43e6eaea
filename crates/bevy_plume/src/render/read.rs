//! Reading an effect entity's particles back, for tests, tools and debugging: from its
//! instance, or from its place in a batch.

use bevy::prelude::*;
use plume_compiler::reference::{ParticleRecord, Totals};
use plume_runtime::{BatchInstance, Effect, EffectBatch, RuntimeError};

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
    read(
        render_world,
        entity,
        group,
        EffectBatch::records,
        Effect::group_records,
    )
}

/// Reads back the counts of group `group` of `entity`'s effect (spawned, alive, dropped,
/// died), blocking like [`read_particles`]. None when the entity has no running instance.
pub fn read_totals(
    render_world: &World,
    entity: Entity,
    group: usize,
) -> Option<Result<Totals, RuntimeError>> {
    read(
        render_world,
        entity,
        group,
        EffectBatch::totals,
        Effect::group_totals,
    )
}

/// `entity`'s reading: from its place in a batch (group 0 only), or from its instance.
fn read<T>(
    render_world: &World,
    entity: Entity,
    group: usize,
    batched: impl Fn(&EffectBatch, BatchInstance) -> Result<T, RuntimeError>,
    alone: impl Fn(&Effect, usize) -> Result<T, RuntimeError>,
) -> Option<Result<T, RuntimeError>> {
    let batches = render_world.get_resource::<PlumeBatches>()?;
    if let (Some(batch), Some(member)) = (batches.batch_of(entity), batches.members.get(&entity)) {
        return Some(match group {
            0 => batched(&batch.batch, member.instance),
            _ => Err(no_group(group)),
        });
    }
    let instance = render_world
        .get_resource::<PlumeInstances>()?
        .instances
        .get(&entity)?;
    Some(alone(&instance.effect, group))
}
