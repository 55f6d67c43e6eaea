//! Looks: how particles are drawn. Each module owns one part of `render` as a force owns its
//! term: its schema, its lowered form, the WGSL the draw modules use and the f64 twin the
//! reference drawing uses.

pub mod glow;
pub mod orient;
pub mod rotation;
pub mod texture;
pub mod tint;
pub mod trail;

use serde::Deserialize;

/// How sprites combine with what is behind them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Blend {
    /// `over` compositing: order matters, so use `sort: true`.
    #[default]
    Alpha,
    /// Colours add up (fire, sparks); order does not matter.
    Additive,
}
