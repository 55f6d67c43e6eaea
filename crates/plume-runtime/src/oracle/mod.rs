//! Test oracles: what the tests compare the GPU's results against, and the readbacks they
//! compare. The CPU-fed reference drawing ([`ReferenceRenderer`]: particles read back, coloured
//! and sized in f64, drawn by a fixed shader; with [`ribbons`] for trails) is to the GPU draw
//! what the f64 reference simulator (`plume_compiler::reference`) is to the kernels. The
//! readbacks: each slot's particle, the draw order, the trail rings, a flock's buffers, the
//! buffer split.
//!
//! Nothing here serves a command or an embedding application.

pub(crate) mod ribbons;
pub(crate) mod sprites;
pub(crate) mod trails;
