//! # plume-runtime
//!
//! Runs compiled Plume effects on wgpu, on a device of its own or inside a host application's
//! renderer.

pub mod bench;
pub(crate) mod device;
pub(crate) mod draw;
mod error;
pub mod oracle;
pub mod outputs;
pub(crate) mod sim;
pub(crate) mod sort;

pub use device::gpu::{Gpu, GpuChoice};
pub use draw::camera::Camera;
pub use draw::raster::{DeadSlots, DrawOptions, EffectRenderer};
pub use draw::target::{DepthTest, DrawTarget};
pub use error::RuntimeError;
pub use sim::graph::GraphInstance;
pub use sim::group::EffectInstance;
/// The wgpu this crate is built against: a host must use the same version.
pub use wgpu;
