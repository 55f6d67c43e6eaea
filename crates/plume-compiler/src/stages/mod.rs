//! The stages that gather features: the effect schema, the checks, lowering to the IR, the
//! passes, the integrators, the WGSL kernel assembly and the step schedule.
//!
//! Architecture invariant: a stage imports features, the IR and `base`, never a driver
//! (`compile`, `graph`); of the reference simulator, only the accuracy pass imports its
//! calibration runs (`reference/calibrate.rs`), to choose a budget's scheme; features never
//! import a stage.

pub(crate) mod integrators;
pub(crate) mod lower;
pub mod passes;
pub mod schedule;
pub mod schema;
pub mod validate;
pub mod wgsl;
