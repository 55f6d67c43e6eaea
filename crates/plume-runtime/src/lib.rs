//! # plume-runtime
//!
//! Runs compiled Plume effects on wgpu: picks an adapter ([`gpu`]), allocates only the buffers
//! the compiled layout needs, records many steps of spawn and fused update into one submission
//! with no CPU round trip per step ([`sim`]), reads particles back when asked and writes them out
//! ([`export`]). The CPU f64 reference lives in `plume_compiler::reference`.

pub mod accuracy;
pub mod bench;
pub mod error;
pub mod export;
pub mod gpu;
pub mod images;
pub mod plot;
pub mod render;
pub mod sim;
pub mod sort;
pub mod timer;

pub use error::RuntimeError;
pub use gpu::{Gpu, GpuChoice};
pub use sim::GpuSim;
