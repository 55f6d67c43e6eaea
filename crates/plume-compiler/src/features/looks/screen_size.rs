//! Sizes in the image (`render.size_in: Screen`): the size stops (and `size_y`, and the
//! factor of `size_by`) are fractions of the image's height instead of metres, so a sprite
//! keeps its size in the image however far it is (bevy_hanabi's `screen_space_size`): 0.01 is
//! 1% of the height, 7.2 pixels in a 720-pixel image. The quad stays in the scene: it is made
//! in metres at the particle's depth, `fraction · 2 w / P[1][1]` with P the projection and w the
//! particle's clip-space w (its depth for a perspective camera, 1 for an orthographic one), so
//! both renderers and the reference drawing, which share the quad, draw it alike.

use glam::{DMat4, DVec3, DVec4};
use serde::Deserialize;

use crate::base::writer::Writer;

/// What the size stops measure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum SizeIn {
    /// Metres in the scene (the default): nearer sprites look larger.
    #[default]
    World,
    /// Fractions of the image's height, at any distance.
    Screen,
}

/// Emits, inside `sprite_at` (after the sizes are set, `x` the particle's position), the scaling
/// of `s.size` (and `s.size_y`, when `height` says the sprite has one) from fractions of the
/// image's height to metres at the particle's depth: the WGSL twin of [`metres_per_height`].
pub(crate) fn emit_scale(w: &mut Writer, height: bool) {
    w.comment("render.size_in: Screen: the sizes are fractions of the image's height.");
    w.line("let clip_w = (draw.proj * (draw.view * vec4<f32>(x, 1.0))).w;");
    w.line("let per_height = 2.0 * max(clip_w, 0.0) / draw.proj[1][1];");
    w.line("s.size = s.size * per_height;");
    if height {
        w.line("s.size_y = s.size_y * per_height;");
    }
}

/// Metres at `x` that one image height spans, for a camera of view `view` and projection
/// `proj`: `2 w / P[1][1]` (0 behind a perspective camera, where the sprite is not drawn).
pub fn metres_per_height(view: DMat4, proj: DMat4, x: DVec3) -> f64 {
    let clip: DVec4 = proj * (view * x.extend(1.0));
    2.0 * clip.w.max(0.0) / proj.y_axis.y
}
