//! Looks: how particles are drawn. Each module owns one part of `render` as a force owns its
//! term: its schema, its lowered form, the WGSL the draw modules use and the f64 twin the
//! reference drawing uses.

pub mod by_expression;
pub mod glow;
pub mod lit;
pub mod orient;
pub mod particle_light;
pub mod ribbon;
pub mod rotation;
pub mod screen_size;
pub mod texture;
pub mod tint;
pub mod trail;

use serde::Deserialize;

/// The brightest colour channel an effect may ask for, in its stops and from `color_by`:
/// above 1 is HDR light, which blooms with glow or on an HDR host. The compute renderer's
/// fixed-point light holds this much from one fragment (`stages/wgsl/draw/splat/light.rs`).
pub const COLOR_MOST: f64 = 128.0;

/// How sprites combine with what is behind them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Blend {
    /// `over` compositing: order matters, so use `sort: true`.
    #[default]
    Alpha,
    /// Colours add up (fire, sparks); order does not matter.
    Additive,
}
