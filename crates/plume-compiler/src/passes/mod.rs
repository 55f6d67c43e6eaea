//! Passes over the IR, run in this order: fold constant terms and merge drags, prune terms that
//! cannot act, resolve the integrator (Auto, and Exact's preconditions), analyse stability,
//! and decide the particle layout.

pub mod fold;
pub mod integrator;
pub mod layout;
pub mod prune;
pub mod stability;

use crate::check::Checker;
use crate::diagnostics::Diagnostic;
use crate::ir::EffectIr;
use layout::Layout;

/// Runs every pass. Errors come back in a [`Checker`] (with lookup paths); on success the
/// layout and the warnings (each with its lookup path) come back.
pub fn run(
    ir: &mut EffectIr,
    force_names: &[&'static str],
) -> Result<(Layout, Vec<(Diagnostic, String)>), Checker> {
    fold::fold(ir);
    prune::prune(ir);
    integrator::resolve(ir, force_names)?;
    let warnings = stability::analyse(ir, force_names);
    let layout = layout::decide(ir);
    Ok((layout, warnings))
}
