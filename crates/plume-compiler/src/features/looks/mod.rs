//! Looks: how particles are drawn. Each module owns one part of `render` as a force owns its
//! term: its schema, its lowered form, the WGSL the draw modules use and the f64 twin the
//! reference drawing uses.

pub mod by_expression;
pub(crate) mod glow;
pub mod lit;
pub mod mesh_splat;
pub mod orient;
pub mod particle_light;
pub mod particle_mesh;
pub mod ribbon;
pub mod rotation;
pub mod screen_size;
pub mod texture;
pub mod tint;
pub mod trail;

use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::{ColorStop, SizeStop};

/// The brightest colour channel an effect may ask for, in its stops and from `color_by`:
/// above 1 is HDR light, which blooms with glow or on an HDR host. The compute renderer's
/// fixed-point light holds this much from one fragment (`stages/wgsl/draw/splat/light.rs`).
pub(crate) const COLOR_MOST: f64 = 128.0;

/// How sprites combine with what is behind them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub enum Blend {
    /// `over` compositing: order matters, so use `sort: true`.
    #[default]
    Alpha,
    /// Colours add up (fire, sparks); order does not matter.
    Additive,
    /// What lies behind is multiplied by the colour, as far as the opacity goes: behind ·
    /// (1 − a + a · rgb) (soot, shadows, tinted glass); order does not matter.
    Multiply,
    /// Cut-outs: a fragment whose opacity is below the cutoff (0 to 1) is not drawn, the rest
    /// is drawn opaque (leaves, paper, hard-edged sparks). Depth is not written: overlapping
    /// cut-outs need `sort: true` to show the nearest.
    Mask(f64),
    /// Opaque: the colour replaces what lies behind wherever the sprite covers (the round
    /// dot's disc, a texture's whole frame), its opacity unused. Depth is not written:
    /// overlapping opaque sprites need `sort: true` to show the nearest.
    Opaque,
    /// The colour is premultiplied: rgb is added as it is and what lies behind is dimmed by
    /// the opacity, rgb + behind · (1 − a), each times the sprite's coverage; opacity 0 adds
    /// light as `Additive` does, and one sprite can glow at its core and cover at its rim.
    Premultiplied,
}

impl Blend {
    /// Checks a `Mask`'s cutoff, in [0, 1]; `path` names `render.blend`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        if let Blend::Mask(cutoff) = *self {
            c.within(&path.variant("Mask").inner(), cutoff, 0.0, 1.0);
        }
    }

    /// Whether the fragment's colour is changed before blending ([`Self::emit_blend_out`];
    /// `Premultiplied` shades its coverage apart from its opacity instead).
    pub(crate) fn changes_output(self) -> bool {
        matches!(self, Blend::Multiply | Blend::Mask(_) | Blend::Opaque)
    }

    /// Whether a sprite of colour `rgba` draws nothing: alpha 0 but for `Premultiplied`, where
    /// light with no opacity still adds (WGSL, of `s.color`).
    pub(crate) fn hidden_wgsl(self) -> &'static str {
        match self {
            Blend::Premultiplied => {
                "max(max(s.color.r, s.color.g), max(s.color.b, s.color.a)) <= 0.0"
            }
            _ => "s.color.a <= 0.0",
        }
    }

    /// The f64 twin of `hidden_wgsl`: whether a sprite of colour `rgba` draws nothing.
    pub fn hides(self, rgba: [f64; 4]) -> bool {
        match self {
            Blend::Premultiplied => rgba.iter().all(|&c| c <= 0.0),
            _ => rgba[3] <= 0.0,
        }
    }

    /// What a strip's fragment (a trail's, a ribbon's) of colour `in.color` covering `cover`
    /// of the pixel (WGSL) returns: its colour at opacity × coverage through `blend_out`, or
    /// for `Premultiplied` its colour and opacity each times the coverage.
    pub(crate) fn strip_out_wgsl(self, cover: &str) -> String {
        match self {
            Blend::Premultiplied => {
                format!("vec4<f32>(in.color.rgb * {cover}, in.color.a * {cover})")
            }
            _ if self.changes_output() => {
                format!("blend_out(vec4<f32>(in.color.rgb, in.color.a * {cover}))")
            }
            _ => format!("vec4<f32>(in.color.rgb, in.color.a * {cover})"),
        }
    }

    /// Emits `blend_out(c)`, what a fragment of colour `c` (straight alpha) writes for this
    /// blend: for `Multiply` the colour times its opacity (the blend multiplies what lies
    /// behind by it and adds what lies behind times 1 − a); for `Mask` the colour, opaque, or
    /// nothing below the cutoff. Nothing for a blend that needs none.
    pub(crate) fn emit_blend_out(self, w: &mut crate::base::writer::Writer) {
        if !self.changes_output() {
            return;
        }
        w.comment(
            "What the fragment writes for the effect's blend (features/looks/mod.rs, Blend).",
        );
        w.block("fn blend_out(c: vec4<f32>) -> vec4<f32>", |w| match self {
            Blend::Mask(cutoff) => {
                w.block(
                    format!("if (c.a < {})", crate::base::writer::f32_lit(cutoff)),
                    |w| w.line("discard;"),
                );
                w.line("return vec4<f32>(c.rgb, 1.0);");
            }
            Blend::Opaque => w.line("return vec4<f32>(c.rgb, 1.0);"),
            _ => w.line("return vec4<f32>(c.rgb * c.a, c.a);"),
        });
    }
}

/// Checks a curve's stop times: at least one, each in 0 to 1, in increasing order.
pub(crate) fn check_stop_times(c: &mut Checker, path: &ValuePath, times: &[f64]) {
    if times.is_empty() {
        c.error(path, "must list at least one stop");
    }
    for (i, &t) in times.iter().enumerate() {
        c.within(&path.index(i).component(0, "t"), t, 0.0, 1.0);
        if i > 0 && t < times[i - 1] {
            c.error(
                &path.index(i).component(0, "t"),
                format!(
                    "stops must be in increasing t, got {t} after {}",
                    times[i - 1]
                ),
            );
        }
    }
}

/// Checks a colour curve: its stop times, each channel from 0 (colour up to `COLOR_MOST`, HDR
/// light; opacity up to 1).
pub(crate) fn check_colors(c: &mut Checker, colors: &ValuePath, stops: &[ColorStop]) {
    check_stop_times(c, colors, &stops.iter().map(|s| s.0).collect::<Vec<_>>());
    for (i, s) in stops.iter().enumerate() {
        let p = colors.index(i).component(1, "color");
        // Colour above 1 is HDR light; opacity is a fraction.
        let most = COLOR_MOST;
        for (j, (name, x, hi)) in [
            ("r", s.1 .0, most),
            ("g", s.1 .1, most),
            ("b", s.1 .2, most),
            ("a", s.1 .3, 1.0),
        ]
        .into_iter()
        .enumerate()
        {
            c.within(&p.component(j, name), x, 0.0, hi);
        }
    }
}

/// Checks an opacity curve: its stop times, each opacity in [0, 1].
pub(crate) fn check_alphas(c: &mut Checker, alphas: &ValuePath, stops: &[SizeStop]) {
    check_stop_times(c, alphas, &stops.iter().map(|s| s.0).collect::<Vec<_>>());
    for (i, s) in stops.iter().enumerate() {
        c.within(&alphas.index(i).component(1, "alpha"), s.1, 0.0, 1.0);
    }
}

/// Checks a size curve: its stop times, each size (called `name` in errors) at least 0.
pub(crate) fn check_sizes(c: &mut Checker, sizes: &ValuePath, stops: &[SizeStop], name: &str) {
    check_stop_times(c, sizes, &stops.iter().map(|s| s.0).collect::<Vec<_>>());
    for (i, s) in stops.iter().enumerate() {
        c.non_negative(&sizes.index(i).component(1, name), s.1);
    }
}
