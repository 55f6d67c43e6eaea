//! The compute module's gradient-noise helpers for expressions (`noise`, `curl`).

use crate::features::forces::{WgslHelpers, CURL_HELPERS, GRADIENT_NOISE_HELPERS};
use crate::ir::EffectIr;

/// The helper sets that the module's expressions call: `curl` reads `turb_curl`, `noise` reads
/// `grad_noise` (and the curl's `turb_gradient`). The module writes them with the terms' own,
/// each set once, so a Turbulence force and a `curl` share one copy.
pub(super) fn helpers(ir: &EffectIr) -> Vec<WgslHelpers> {
    use crate::expr::typed::Op1;
    let (noise, curl) = (ir.compute_uses(Op1::Noise), ir.compute_uses(Op1::Curl));
    let mut sets = Vec::new();
    if noise || curl {
        sets.push(CURL_HELPERS);
    }
    if noise {
        sets.push(GRADIENT_NOISE_HELPERS);
    }
    sets
}
