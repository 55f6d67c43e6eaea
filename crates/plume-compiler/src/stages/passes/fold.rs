//! Folding: all constant accelerations (gravity, noiseless wind) become one term, and all
//! drags one drag, so the kernel adds one vector and does one multiply for them.

use crate::ir::EffectIr;

/// Folds constants and merges drags (`forces::fold`); other terms keep their order after them.
pub fn fold(ir: &mut EffectIr) {
    ir.terms = crate::features::forces::fold(std::mem::take(&mut ir.terms));
}
