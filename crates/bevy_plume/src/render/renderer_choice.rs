//! Which of Plume's renderers draws an effect, instance or batch alike, and making it: the
//! compute renderer where `PlumeDraw` picks it and it can be made, else the raster one.

use bevy::prelude::*;
use plume_runtime::{DrawTarget, Effect, EffectRenderer, RuntimeError};

use crate::effect::PlumeDraw;

/// The renderer of `effect` into `target`: the compute renderer at `size` where one is given,
/// else the raster renderer; a compute renderer that cannot be made is said, marked in
/// `compute_refused` (so the caller asks no more), and replaced by the raster one. With the
/// size it draws at (None: the raster renderer).
pub(crate) fn renderer_or_raster(
    effect: &Effect,
    target: &DrawTarget,
    size: Option<(u32, u32)>,
    compute_refused: &mut bool,
) -> (Option<(u32, u32)>, Result<EffectRenderer, RuntimeError>) {
    if let Some((w, h)) = size {
        match effect.compute_renderer(target, w, h) {
            Ok(renderer) => return (size, Ok(renderer)),
            Err(err) => {
                let name = &effect.compiled().ir.name;
                warn!("{name}: the compute renderer cannot draw it ({err}): the raster one does");
                *compute_refused = true;
            }
        }
    }
    (None, effect.renderer(target))
}

/// Whether an effect drawn by `draw` is drawn by the compute renderer: `Compute` always,
/// `Auto` on a GPU adapter (`gpu_adapter`) when the effect is `large` and the compute renderer
/// draws all it shows (`compute_draws`, asked only then).
pub(crate) fn draws_by_compute(
    draw: PlumeDraw,
    gpu_adapter: bool,
    large: bool,
    compute_draws: impl FnOnce() -> bool,
) -> bool {
    match draw {
        PlumeDraw::Raster => false,
        PlumeDraw::Compute => true,
        PlumeDraw::Auto => gpu_adapter && large && compute_draws(),
    }
}
