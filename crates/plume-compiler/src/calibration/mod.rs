//! The accuracy pass and what it remembers: with a budget (`features::accuracy`), the scheme
//! (integrator, substeps, motion in halves) chosen from f64 runs of sample particles on the
//! reference simulator ([`accuracy`]), and the choices kept on disk between processes
//! ([`cache`]).
//!
//! A layer of its own above `reference`, which it runs, and `stages`, whose passes call it only
//! through the chooser `compile` hands them (`passes::AccuracyChooser`): so no stage imports the
//! reference simulator, and the reference (which shares the stages' step contract, integrators
//! and schema) imports no stage that imports it back.

pub mod accuracy;
pub mod cache;
