//! Passes over the IR, run in this order: fold constant terms and merge drags, prune terms that
//! cannot act, meet an accuracy budget (Auto's scheme from f64 calibration runs), resolve the
//! integrator (Auto, and Exact's preconditions), analyse stability,
//! decide whether particles need state at all, and decide the particle layout.

pub mod fold;
pub mod integrator;
pub mod layout;
pub(crate) mod prune;
pub mod stability;
pub mod stateless;

use crate::base::check::Checker;
use crate::base::diagnostics::Diagnostic;
use crate::ir::EffectIr;
use layout::Layout;

/// The accuracy pass, which `compile` hands to [`run`] (`calibration::accuracy::choose`): with
/// a budget it picks the scheme for `ir` (the bool: whether the closed form applies) and may
/// warn; errors come back in a `Checker`. Passed in, so that no stage imports the reference
/// simulator it runs.
pub(crate) type AccuracyChooser =
    dyn Fn(&mut EffectIr, bool) -> Result<Option<(Diagnostic, String)>, Checker>;

/// Runs every pass, the accuracy pass by `choose_accuracy`. Errors come back in a `Checker`
/// (with lookup paths); on success the layout and the warnings (each with its lookup path)
/// come back.
pub(crate) fn run(
    ir: &mut EffectIr,
    force_names: &[&'static str],
    choose_accuracy: &AccuracyChooser,
) -> Result<(Layout, Vec<(Diagnostic, String)>), Checker> {
    fold::fold(ir);
    prune::prune(ir);
    // A budget picks the scheme before Auto's default does (and leaves Exact to it).
    let exact_possible = integrator::exact_blocker(ir, force_names).is_none();
    let budget_warning = choose_accuracy(ir, exact_possible)?;
    integrator::resolve(ir, force_names)?;
    let mut warnings = stability::analyse(ir, force_names);
    warnings.extend(budget_warning);
    // A baked field with nothing to hold (no attractor, vortex or noise left) is dropped, so
    // the effect pays for no grid.
    if ir.field.is_some() && !ir.terms.iter().any(|t| t.as_dyn().bakeable()) {
        ir.field = None;
        let path = crate::base::path::ValuePath::root().field("field");
        warnings.push((
            Diagnostic::warning(
                path.display,
                "nothing to bake: no Attractor, Vortex or noisy Wind acts, so forces are evaluated and no grid is made",
            ),
            path.lookup,
        ));
    }
    stateless::decide(ir)?;
    let layout = layout::decide(ir);
    Ok((layout, warnings))
}
