//! # plume
//!
//! The facade of Plume, a compiler from declarative particle effects (RON files) to fused,
//! naga-validated WGSL compute kernels. It re-exports the compiler crate and the runtime
//! (`plume::runtime`: `Effect`, `EffectRenderer`, `Gpu`, ...); the integration tests of the
//! whole project live in this package's `tests/`.
//!
//! ```
//! let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/sparks.ron")).unwrap();
//! let compiled = plume::compile_str(&src, &plume::CompileOptions::default()).unwrap();
//! assert!(compiled.warnings.is_empty());
//! ```

pub use plume_compiler as compiler;
pub use plume_compiler::{
    compile_effect, compile_str, parse, CompileError, CompileOptions, CompiledEffect, Diagnostic,
    Diagnostics, EffectIr, Integrator, Layout, Severity,
};
pub use plume_runtime as runtime;
