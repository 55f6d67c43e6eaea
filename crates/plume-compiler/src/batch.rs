//! Batched instances: one compiled effect stepped for many instances of it at once, as a game
//! runs a thousand small copies of one effect. A batched module's buffers hold every
//! instance side by side: instance n owns the global slots n · `CAPACITY` .. (n + 1) ·
//! `CAPACITY` of one particle buffer (laid out as one effect's of that many slots, so the
//! draw module reads it unchanged), the free list segment of the same range and the n-th
//! counters; each step's parameters are a row per instance, and every kernel takes its
//! instance from its dispatch's z. One dispatch chain then steps every instance, and one draw
//! draws them all.
//!
//! Instances share the batch's step index (the `step` of every row), so the death and spawn
//! steps the draw reckons ages from agree across them; each keeps its own time, ids, spawn
//! counters, placement, live params and bursts. An instance that sits a step out (paused, or
//! slower than the others) has its particles held: their death and spawn steps move on with
//! the batch's, so their ages stay (`update.rs`, `hold_particle`).

use crate::base::layout::{Role, Space};
use crate::base::naga_check;
use crate::compile::{CompileError, CompiledEffect};
use crate::stages::wgsl;

/// Why `compiled` cannot be batched (a feature whose kernels or buffers are the effect's
/// alone), or None when it can.
pub fn unbatchable(compiled: &CompiledEffect) -> Option<&'static str> {
    let ir = &compiled.ir;
    let layout = &compiled.layout;
    if layout.stateless() {
        Some("it is stateless (its particles are computed, not stepped)")
    } else if !ir.events.is_empty() || !ir.event_inputs.is_empty() {
        Some("it fires or takes events")
    } else if ir.render.trail.is_some() {
        Some("it draws trails")
    } else if ir.render.mesh.is_some() {
        Some("it draws meshes (`render.mesh`)")
    } else if ir.render.ribbon.is_some() {
        Some("it draws ribbons (`render.ribbon`)")
    } else if ir.render.light.is_some() {
        Some("its particles give off light (`render.light`)")
    } else if layout.sorts() {
        Some("it is sorted by depth (`sort: true`)")
    } else if ir.flock.is_some() {
        Some("it flocks")
    } else if ir.field.is_some() {
        Some("it bakes a force field")
    } else if layout.half_motion {
        Some("it stores its motion in halves")
    } else if layout.binds(Role::SceneCamera) {
        Some("it collides with a scene's depth")
    } else if layout.batched {
        Some("it is batched already")
    } else {
        None
    }
}

/// `compiled` (an effect of one group) compiled again for batched instances: the same IR and
/// draw module, a compute module whose kernels step every instance of a batch
/// ([`crate::Layout::batched`]). `CAPACITY` is then each instance's.
pub fn compile_batched(compiled: &CompiledEffect) -> Result<CompiledEffect, BatchError> {
    if let Some(why) = unbatchable(compiled) {
        return Err(BatchError::Unbatchable(compiled.ir.name.clone(), why));
    }
    let mut batched = compiled.clone();
    batched.layout.batched = true;
    batched.layout.instance_slots = compiled.ir.capacity;
    batched.layout.bindings.push(crate::base::layout::Binding {
        binding: wgsl::batch::INSTANCE_MODELS_BINDING,
        role: Role::InstanceModels,
        space: Space::Read,
        bytes: 64,
        meaning: "per instance, its transform from its own space to the world, column-major (the draw's; identity for an instance in world space)",
    });
    let params_bytes = batched.layout.params_bytes();
    for binding in &mut batched.layout.bindings {
        match binding.role {
            Role::Params => {
                binding.space = Space::Read;
                binding.bytes = params_bytes;
                binding.meaning = "per step, a row per instance: first id, spawns requested, the instance's time, the batch's step index, per-emitter counts, (active, 0, 0, 0)";
            }
            Role::Counters => {
                binding.meaning = "per instance: free count, this step's spawn base and count, totals spawned, dropped, died";
            }
            Role::FreeList => {
                binding.meaning = "per instance, a stack of its free slots (CAPACITY entries each)";
            }
            _ => {}
        }
    }
    batched.wgsl = wgsl::emit_module(&batched.ir, &batched.layout);
    naga_check::validate(&batched.wgsl).map_err(|e| BatchError::Compile(e.into()))?;
    let shape = wgsl::draw::DrawShape::single(&batched.ir);
    batched.draw_wgsl = wgsl::draw::emit(&batched.ir, &batched.layout, &shape);
    naga_check::validate(&batched.draw_wgsl).map_err(|e| BatchError::Compile(e.into()))?;
    Ok(batched)
}

/// Why an effect was not compiled for batched instances.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The effect has a feature batching does not cover.
    #[error("{0}: cannot be batched: {1}")]
    Unbatchable(String, &'static str),
    /// The batched module failed naga's validation (a bug in Plume).
    #[error(transparent)]
    Compile(CompileError),
}
