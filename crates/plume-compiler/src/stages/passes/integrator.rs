//! Integrator resolution: Auto becomes Exact where a closed form exists, else
//! SemiImplicitEuler; an explicit Exact without a closed form is an error naming the cause.

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::ir::EffectIr;
use crate::stages::schema::Integrator;

/// Why the Exact integrator cannot be used, naming the force or feature, or None if it can.
pub fn exact_blocker(ir: &EffectIr, force_names: &[&'static str]) -> Option<(String, ValuePath)> {
    for term in &ir.terms {
        if term.as_dyn().linear().is_some() {
            continue;
        }
        let origin = term.as_dyn().origins()[0];
        let name = force_names.get(origin).copied().unwrap_or("force");
        let what = format!(
            "forces[{origin}] ({name}) {}",
            term.as_dyn().closed_form_blocker()
        );
        let path = ValuePath::root()
            .field("forces")
            .index(origin)
            .variant(name);
        return Some((what, path));
    }
    if let Some(flock) = &ir.flock {
        return Some((
            format!("forces[{}] (Flock) couples particles", flock.origin),
            ValuePath::root()
                .field("forces")
                .index(flock.origin)
                .variant("Flock"),
        ));
    }
    if let Some(c) = ir.colliders.first() {
        let name = c.surface.name();
        return Some((
            format!("collide[0] ({name}) needs collision handling"),
            ValuePath::root().field("collide").index(0).variant(name),
        ));
    }
    if ir.max_speed.is_some() {
        return Some((
            "max_speed clamps the velocity".into(),
            ValuePath::root().field("max_speed"),
        ));
    }
    None
}

/// Resolves `ir.integrator` to a concrete integrator and records why.
pub(crate) fn resolve(ir: &mut EffectIr, force_names: &[&'static str]) -> Result<(), Checker> {
    let blocker = exact_blocker(ir, force_names);
    match (ir.integrator, blocker) {
        (Integrator::Auto, None) => {
            ir.integrator = Integrator::Exact;
            ir.integrator_reason =
                "Auto: only gravity, drag and noiseless wind act, so the closed form is exact"
                    .into();
        }
        (Integrator::Auto, Some((why, _))) => {
            ir.integrator = Integrator::SemiImplicitEuler;
            ir.integrator_reason = format!("Auto: no closed form because {why}");
        }
        (Integrator::Exact, Some((why, _))) => {
            let mut c = Checker::default();
            c.error(
                &ValuePath::root().field("integrator"),
                format!(
                    "Exact is not allowed because {why}; Exact needs only Gravity, Drag and Wind with noise 0, no colliders and no max_speed (use Rk4 or Auto)"
                ),
            );
            return Err(c);
        }
        _ => {}
    }
    Ok(())
}
