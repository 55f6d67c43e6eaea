//! # plume-compiler
//!
//! Compiles Plume particle effects, written in RON, into one WGSL compute module per effect: a
//! fused `update` kernel and `spawn` kernels (or, for a stateless effect, one `evaluate`
//! kernel), and one draw module (a vertex shader that reads the particles from the GPU buffers
//! and a fragment shader for the sprites), both validated by naga. The pipeline, one module per stage:
//! parse ([`schema`], located [`Diagnostics`]) → check ([`validate`]) → lower to the [`ir`] →
//! [`passes`] (fold, prune, accuracy ([`calibration`]), integrator, stability, the unused field
//! dropped, state, layout) → [`wgsl`] writer → naga's validation. This crate does not depend on wgpu.
//!
//! ```
//! let source = r#"Effect(
//!     name: "drop",
//!     capacity: 1000,
//!     emitters: [Emitter(burst: 100, shape: Point((0.0, 1.0, 0.0)),
//!                        velocity: Constant((0.0, 0.0, 0.0)))],
//!     forces: [Gravity((0.0, -9.81, 0.0))],
//! )"#;
//! let effect = plume_compiler::compile_str(source, &Default::default()).unwrap();
//! assert_eq!(effect.ir.integrator, plume_compiler::Integrator::Exact); // picked by Auto
//! // Nothing else needs state, so each particle is computed from its id and age:
//! assert!(effect.ir.stateless.is_some() && effect.wgsl.contains("fn evaluate"));
//! assert_eq!(effect.layout.state_bytes_per_particle(), 0);
//!
//! // Kept stateful, it has spawn and update kernels and 32 bytes of state per particle
//! // (position, velocity, id: 28 bytes, padded to 16).
//! let options = plume_compiler::CompileOptions {
//!     state: Some(plume_compiler::schema::State::Stateful),
//!     ..Default::default()
//! };
//! let stateful = plume_compiler::compile_str(source, &options).unwrap();
//! assert!(stateful.wgsl.contains("fn update"));
//! assert_eq!(stateful.layout.state_bytes_per_particle(), 32);
//! ```

//!
//! The crate is layered, every import pointing down (docs/ARCHITECTURE.md draws it):
//! `base` (leaves) → `expr` → `features` → `ir` → `stages` → `reference` → `calibration` →
//! `compile` and `batch` → `graph`. The public API: compiling a file or a string
//! ([`compile_str`], [`compile_effect`], [`graph`]), the diagnostics, the IR and layout to
//! inspect, and the modules the runtime, the Bevy plugin and the tests share with the compiler
//! (the step [`schedule`], the f64 [`reference`](mod@reference), the WGSL contract in [`wgsl`], the features'
//! IR types), re-exported under their short names. Everything else is `pub(crate)`.

// An item no path from the crate's root reaches is `pub(crate)`, so the public API reads as
// what it is and the dead-code lint sees the rest.
#![warn(unreachable_pub)]

mod base;
pub mod batch;
pub mod calibration;
mod compile;
pub mod expr;
mod features;
pub mod graph;
pub mod ir;
pub mod reference;
mod stages;

pub use base::diagnostics::{Diagnostic, Diagnostics, Severity, Span};
pub use base::{files, lifetime, rng};
pub use compile::{
    compile_effect, compile_str, parse, parse_with, CompileError, CompileOptions, CompiledEffect,
};
pub use features::looks::{
    by_expression, lit, mesh_splat, orient, particle_light, particle_mesh, ribbon, rotation,
    screen_size, texture, tint, trail,
};
pub use features::{
    accuracy, attributes, bursts, colliders, emitter, event_report, events, field, forces, inherit,
    lights, placement, shadow,
};
pub use ir::EffectIr;
pub use stages::passes::layout::Layout;
pub use stages::schema::{EffectSpec, Integrator};
pub use stages::{passes, schedule, schema, validate, wgsl};
