//! The readbacks and views the tests compare: state the public [`Effect`] keeps to itself
//! (slot order, the GPU's draw order, a flock's buffers, how its state is split), and a
//! renderer of one group alone.

use plume_compiler::reference::ParticleRecord;

use crate::draw::renderer::EffectRenderer;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use crate::sort::radix::SortAlgorithm;

/// Every slot's particle of the top-level group, in slot order (None for a free slot): the
/// order an unsorted draw follows.
pub fn records_by_slot(effect: &Effect) -> Result<Vec<Option<ParticleRecord>>, RuntimeError> {
    effect.groups()[0].records_by_slot()
}

/// Sorts every slot of the top-level group by depth along the effect camera's axis on the GPU
/// with `algorithm` (farthest first, free slots last) and returns the live slots in draw
/// order, each with its 16-bit key. An error for `sort: false`.
pub fn draw_order(
    effect: &Effect,
    algorithm: SortAlgorithm,
) -> Result<Vec<(u32, u32)>, RuntimeError> {
    effect.groups()[0].draw_order(algorithm)
}

/// Reads a flocking buffer of the top-level group back by its role (`Role::Boids`,
/// `Role::FlockOut`, ...).
pub fn read_flock_buffer(
    effect: &Effect,
    role: plume_compiler::passes::layout::Role,
) -> Result<Vec<u8>, RuntimeError> {
    effect.groups()[0].read_extra_buffer(role)
}

/// Number of particle buffers group `g`'s state is split into.
pub fn chunk_count(effect: &Effect, g: usize) -> Result<usize, RuntimeError> {
    Ok(effect.group(g)?.chunk_count())
}

/// Bytes of particle buffers allocated now, every group: the state (stateful), or the view a
/// readback made (stateless; 0 for an effect that has only been drawn).
pub fn particle_buffer_bytes(effect: &Effect) -> u64 {
    effect
        .groups()
        .iter()
        .map(|g| g.particle_buffer_bytes())
        .sum()
}

/// A renderer that draws group `g` of `effect` alone into targets like `target` (prepared
/// and drawn as any [`EffectRenderer`]).
pub fn group_renderer(
    effect: &Effect,
    g: usize,
    target: &DrawTarget,
) -> Result<EffectRenderer, RuntimeError> {
    effect.group_renderer(g, target)
}
