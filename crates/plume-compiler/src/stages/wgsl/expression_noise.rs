//! The compute module's gradient-noise helpers for expressions (`noise`, `curl`).

use crate::base::writer::Writer;
use crate::ir::EffectIr;
use crate::stages::integrators;

/// The gradient noise's helpers that expressions call (`noise` reads `grad_noise`, `curl`
/// reads `turb_curl`), when some expression of the module reads them; a Turbulence force
/// brings `turb_curl` itself.
pub(super) fn emit(w: &mut Writer, ir: &EffectIr) {
    use crate::expr::typed::Op1;
    let (noise, curl) = (ir.compute_uses(Op1::Noise), ir.compute_uses(Op1::Curl));
    let turbulence = integrators::needs_accel(ir.integrator)
        && ir
            .terms
            .iter()
            .any(|t| matches!(t, crate::features::forces::Term::Turbulence(_)));
    if (noise || curl) && !turbulence {
        crate::base::gradient_noise::emit_curl_helpers(w);
        w.blank();
    }
    if noise {
        crate::base::gradient_noise::emit_noise_helper(w);
        w.blank();
    }
}
