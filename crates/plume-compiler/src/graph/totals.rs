//! What a compiled graph holds over all its groups together.

use crate::graph::CompiledGraph;

impl CompiledGraph {
    /// About how many particles every group keeps alive unthinned, together
    /// ([`EffectIr::expected_alive`](crate::ir::EffectIr::expected_alive)).
    pub fn expected_alive(&self) -> u64 {
        self.groups
            .iter()
            .map(|g| g.effect.ir.expected_alive())
            .sum()
    }

    /// Particle slots of every group together (their capacities).
    pub fn capacity(&self) -> u64 {
        self.groups
            .iter()
            .map(|g| u64::from(g.effect.ir.capacity))
            .sum()
    }
}
