//! Validation of every emitted module with naga (parse + full validation). A failure here is an
//! internal compiler error: the compiler produced WGSL it should not have.

use naga::valid::{Capabilities, ValidationFlags, Validator};

/// Why naga rejected a module: its message and the offending WGSL.
#[derive(Debug, thiserror::Error)]
#[error("internal compiler error: naga rejected the generated WGSL: {message}\n--- generated WGSL ---\n{wgsl}")]
pub struct NagaRejection {
    /// naga's message, with its own source excerpt.
    pub message: String,
    /// The module that failed.
    pub wgsl: String,
}

/// Parses and validates `wgsl`; returns the naga module on success.
pub(crate) fn validate(wgsl: &str) -> Result<naga::Module, NagaRejection> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| NagaRejection {
        message: e.emit_to_string(wgsl),
        wgsl: wgsl.to_string(),
    })?;
    Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .map_err(|e| NagaRejection {
            message: e.emit_to_string(wgsl),
            wgsl: wgsl.to_string(),
        })?;
    Ok(module)
}
