//! # plume-runtime
//!
//! Runs compiled Plume effects on wgpu, on a device of its own or inside a host application's
//! renderer. The modules follow the pipeline, data flowing one way:
//!
//! - [`gpu`]: the device (Plume's own adapter choice, or a host's device and queue);
//! - [`resources`]: an effect's buffers and the compute module's bind groups, from its layout;
//! - [`steps`] (with [`flock_pass`]): the simulation passes, many steps per submission with
//!   no CPU round trip, or a stateless effect's bookkeeping;
//! - [`depth_sort`] (with [`depth_quantise`] and the generic [`sort`]): depth keys, quantised
//!   to 16 bits, and their GPU radix sort;
//! - [`draw`] (with [`live_list`]): the effect's generated draw module on a render pipeline,
//!   drawing straight from the particle buffers into the caller's render pass;
//! - [`readback`]: particles and counters back to the CPU (exports, tests, measurements);
//! - [`instance`]: [`EffectInstance`], the public object that ties them together;
//! - outputs: [`offscreen`] (headless images, drawn by the raster pipeline or by [`splat`], a
//!   compute-shader splat of the same image), [`images`], [`export`], [`bench`],
//!   [`accuracy`] and [`plot`]; [`reference_draw`] is the CPU-fed drawing the GPU draw is
//!   tested against.
//!
//! The CPU f64 reference simulator lives in `plume_compiler::reference`.

pub mod accuracy;
pub mod bench;
pub mod camera;
pub mod depth_quantise;
pub mod depth_sort;
pub mod draw;
pub mod draw_pipeline;
pub mod draw_target;
pub mod error;
pub mod event_order;
pub mod export;
pub mod flock_pass;
pub mod glow;
pub mod gpu;
pub mod graph_bench;
pub mod graph_instance;
pub mod images;
pub mod instance;
pub mod live_list;
pub mod offscreen;
pub mod plot;
pub mod readback;
pub mod reference_draw;
pub mod reference_ribbons;
pub mod resources;
pub mod scene_depth;
pub mod sort;
pub mod sort_bench;
pub mod splat;
pub mod sprite_texture;
pub mod steps;
pub mod timer;
pub mod trail_draw;
pub mod trail_readback;

pub use camera::Camera;
pub use draw::{DeadSlots, DepthTest, DrawOptions, DrawTarget, EffectRenderer};
pub use error::RuntimeError;
pub use gpu::{Gpu, GpuChoice};
pub use graph_instance::GraphInstance;
pub use instance::EffectInstance;
pub use resources::STEPS_PER_SUBMIT;
/// The wgpu this crate is built against: a host must use the same version.
pub use wgpu;
