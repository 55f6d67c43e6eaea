//! Pruning: terms that are zero everywhere (zero gravity, k = 0 drag, strength-0 attractors,
//! a vortex with no spin, pull or down, gravity cancelled by wind) are dropped.

use crate::ir::EffectIr;

/// Drops every term that cannot act.
pub(crate) fn prune(ir: &mut EffectIr) {
    ir.terms.retain(|t| t.as_dyn().can_act());
}
