//! Folding: all constant accelerations (gravity, noiseless wind) become one term, and all
//! drags one drag, so the kernel adds one vector and does one multiply for them.

use crate::features::forces::constant::ConstantTerm;
use crate::features::forces::Term;
use crate::ir::EffectIr;

/// Folds constants and merges drags; other terms keep their order after them.
pub fn fold(ir: &mut EffectIr) {
    let mut constant: Option<ConstantTerm> = None;
    let mut drag: Option<crate::features::forces::drag::DragTerm> = None;
    let mut rest = Vec::new();
    for term in ir.terms.drain(..) {
        match term {
            Term::Constant(c) => {
                constant = Some(match constant {
                    None => c,
                    Some(acc) => {
                        let mut origins = acc.origins;
                        origins.extend(c.origins);
                        ConstantTerm {
                            accel: acc.accel + c.accel,
                            origins,
                        }
                    }
                });
            }
            Term::Drag(d) => {
                drag = Some(match drag {
                    None => d,
                    Some(acc) => acc.merge(&d),
                });
            }
            other => rest.push(other),
        }
    }
    ir.terms = constant
        .map(Term::Constant)
        .into_iter()
        .chain(drag.map(Term::Drag))
        .chain(rest)
        .collect();
}
