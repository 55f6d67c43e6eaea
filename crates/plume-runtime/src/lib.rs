//! # plume-runtime
//!
//! Runs compiled Plume effects on wgpu, on a device of its own or inside a host application's
//! renderer. The whole embedding API is at the crate root:
//!
//! - [`Gpu`] (with [`GpuChoice`]): the device, Plume's own ([`Gpu::new`]) or a host's
//!   ([`Gpu::from_device`]);
//! - [`Effect`]: any effect file running on it, a single system or a graph of groups and
//!   events ([`Effect::from_file`], [`Effect::from_source`], [`Effect::new`] from a compiled
//!   effect, [`Effect::from_graph`]); it steps into the host's encoder ([`Effect::advance`]) or
//!   runs on its own ([`Effect::run`]), and reads back ([`Effect::totals`], [`Effect::records`]);
//! - [`EffectRenderer`]: its draw, every group and its trails, into targets like one
//!   [`DrawTarget`] (with an optional [`DepthTest`] against the host's depth buffer), made by
//!   [`Effect::renderer`], prepared each frame by [`Effect::prepare_draw`] from a [`Camera`],
//!   and recorded into the host's render pass by [`EffectRenderer::draw`];
//! - [`RuntimeError`]: what went wrong, and where it can, what to do.
//!
//! Without waiting, for a host that reads every frame: [`Effect::watch_totals`],
//! [`Effect::watch_live_bounds`] and [`Effect::watch_reports`] (an effect's reported events,
//! [`EventReport`]); [`GpuTimer`] times the host's own recorded work the same way.
//!
//! The named module [`outputs`] (headless images, GIF, contact sheets, exports) serves the
//! `plume` command and any host that wants files. With the `tools` feature, two more serve the
//! tools and the tests, not an embedding application: `bench` (benchmarks and measurements)
//! and `oracle` (the CPU reference drawing and the readbacks the tests compare). Everything
//! else is private to the crate, in folders by job: `device`, `sort`, `sim`, `draw` (see
//! docs/ARCHITECTURE.md, "Runtime and outputs").
//!
//! The CPU f64 reference simulator lives in `plume_compiler::reference`.

// An item no path from the crate's root reaches is `pub(crate)`, so the public API reads as
// what it is and the dead-code lint sees the rest. Checked with `tools` on: `bench` and
// `oracle` reach a few items (the sort, the draw's options) that embedders do not.
#![cfg_attr(feature = "tools", warn(unreachable_pub))]

#[cfg(feature = "tools")]
pub mod bench;
mod device;
mod draw;
mod error;
#[cfg(feature = "tools")]
pub mod oracle;
pub mod outputs;
mod sim;
mod sort;

pub use device::gpu::{Gpu, GpuChoice};
pub use device::gpu_timer::GpuTimer;
pub use draw::camera::Camera;
pub use draw::particle_light::ParticleLights;
pub use draw::renderer::EffectRenderer;
pub use draw::target::{DepthTest, DrawTarget};
pub use error::RuntimeError;
/// The glam of [`Camera`]'s matrices (a host on another glam converts through
/// `Mat4::from_cols_array`).
pub use glam;
/// The lights a lit look is drawn with ([`EffectRenderer::set_lights`]).
pub use plume_compiler::lights::{LightSource, Lights};
pub use plume_compiler::shadow::{Shadow, ShadowDepths};
pub use sim::batch::{BatchInstance, EffectBatch};
pub use sim::bounds::{BoundsWatch, LiveBounds};
pub use sim::effect::Effect;
pub use sim::planned::PlannedSteps;
pub use sim::reports::{EventReport, Firing};
/// The wgpu this crate is built against: a host must use the same version.
pub use wgpu;
