//! Received shadows: a directional light whose light a shadow map blocks. The map is a depth
//! image seen from the light (one layer, or up to [`SHADOW_CASCADES_MOST`] cascades, each
//! with its own projection); a point is lit by that light where it is no farther from the
//! light than the map's surface at its place. `plume render` and `plume preview` draw the map
//! from the scene's meshes, an embedding host passes its own, the Bevy plugin Bevy's
//! cascades. This module owns the map's description in the lights uniform, the WGSL lookup
//! ([`SHADOW_WGSL`]) that every lit shader shares, and its f64 twin ([`Shadow::visibility`]).
//!
//! The lookup filters 2 x 2 texels (percentage-closer filtering, by the GPU's comparison
//! sampler): each of the four texels nearest the point's place says lit (1) or not (0) by
//! comparing its depth with the point's, and the four verdicts are blended bilinearly, so a
//! shadow's edge is a texel wide ramp rather than a staircase.

use glam::{DMat4, DVec3, DVec4};
use serde::Deserialize;

/// Most cascades (layers of the map, each with its projection) a draw reads.
pub const SHADOW_CASCADES_MOST: usize = 4;

/// Bytes of the shadow's part of the lights uniform: (source, cascades, reversed, unused) as
/// u32, then [`SHADOW_CASCADES_MOST`] matrices.
pub(crate) const SHADOW_BYTES: u64 = 16 + 64 * SHADOW_CASCADES_MOST as u64;

/// Binding of the shadow map (`texture_depth_2d_array`) in a lit draw module.
pub const SHADOW_MAP_BINDING: u32 = 52;

/// Bindings of the shadow map's comparison samplers in a lit draw module: standard depth
/// (`LessEqual`), then reversed (`GreaterEqual`).
pub const SHADOW_SAMPLER_BINDINGS: [u32; 2] = [53, 54];

/// A draw module's declarations of the shadow map and its samplers.
pub(crate) fn shadow_declarations_wgsl() -> String {
    let [standard, reversed] = SHADOW_SAMPLER_BINDINGS;
    format!(
        "@group(0) @binding({SHADOW_MAP_BINDING}) var shadow_map: texture_depth_2d_array;\n\
         @group(0) @binding({standard}) var shadow_standard: sampler_comparison;\n\
         @group(0) @binding({reversed}) var shadow_reversed: sampler_comparison;"
    )
}

/// Where a lit look looks its shadow up (`render.lit.shadow_at`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub(crate) enum ShadowAt {
    /// At every pixel's own point: a shadow's edge crosses a sprite as it crosses the scene.
    #[default]
    Pixel,
    /// Once a particle, at its centre, the whole sprite taking that verdict: one lookup a
    /// particle (in the vertex shader, or as the compute renderer loads its record) rather
    /// than one a pixel. For sprites small beside the shadow's features (smoke under a wall).
    Particle,
}

impl ShadowAt {
    /// The WGSL that a light's colour is multiplied by at view-space point `p`: the map's
    /// verdict there, or the particle's own (`particle_shadow`, which each shader that lights
    /// sets from `shadow_visibility` at the particle's centre before it lights a pixel).
    pub(crate) fn visibility_wgsl(self) -> &'static str {
        match self {
            ShadowAt::Pixel => "shadow_visibility(p)",
            ShadowAt::Particle => "particle_shadow",
        }
    }
}

/// The source index in the uniform that no light has: no shadow.
const NO_SOURCE: u32 = u32::MAX;

/// Which light a shadow map blocks and how the map was seen, in the lights' space.
#[derive(Clone, Debug, PartialEq)]
pub struct Shadow {
    /// The index, in [`crate::features::lights::Lights::sources`], of the directional light
    /// the map blocks.
    pub source: usize,
    /// Each cascade's projection from the lights' space into its clip space (wgpu's: x and y
    /// in [-1, 1], depth in [0, 1]), in the order they are tried: a point takes the first
    /// that holds it. Layer k of the map is cascade k. Empty: the map is not drawn yet and
    /// nothing is shadowed.
    pub cascades: Vec<DMat4>,
    /// Whether the map's depth is reversed (1 near the light, as Bevy draws it).
    pub reversed: bool,
    /// The map's depths, for the f64 twin ([`Self::visibility`]); the GPU reads its texture
    /// instead, and without them the f64 light is unshadowed.
    pub depths: Option<ShadowDepths>,
}

/// A shadow map's depths read back: `layers[k]` holds cascade k's, row by row from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowDepths {
    /// Texels a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Each layer's depths, `width * height` of them.
    pub layers: Vec<Vec<f32>>,
}

impl Shadow {
    /// The shadow of source `source` before any map is drawn (nothing shadowed yet).
    pub fn of_source(source: usize) -> Self {
        Self {
            source,
            cascades: Vec::new(),
            reversed: false,
            depths: None,
        }
    }

    /// The same shadow for lights moved by `m` (their space to another): each cascade's
    /// projection then starts from the other space.
    pub fn transformed(&self, m: DMat4) -> Self {
        let back = m.inverse();
        Self {
            cascades: self.cascades.iter().map(|c| *c * back).collect(),
            ..self.clone()
        }
    }

    /// How much of its light the shadowed source gives point `p` (in the lights' space): 1
    /// lit, 0 in shadow, between at an edge. The first cascade whose box holds `p` (x and y
    /// in [-1, 1], depth in [0, 1]) decides; a point in none is lit. The f64 twin of the WGSL
    /// `shadow_visibility`; 1 without `depths`.
    pub fn visibility(&self, p: DVec3) -> f64 {
        let Some(depths) = &self.depths else {
            return 1.0;
        };
        for (layer, clip_from) in depths
            .layers
            .iter()
            .zip(&self.cascades)
            .take(SHADOW_CASCADES_MOST)
        {
            let q = *clip_from * DVec4::new(p.x, p.y, p.z, 1.0);
            if q.w <= 0.0 {
                continue;
            }
            let ndc = q.truncate() / q.w;
            if ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 || !(0.0..=1.0).contains(&ndc.z) {
                continue;
            }
            let z = ndc.z;
            let (w, h) = (i64::from(depths.width), i64::from(depths.height));
            let tx = (ndc.x * 0.5 + 0.5) * w as f64 - 0.5;
            let ty = (0.5 - ndc.y * 0.5) * h as f64 - 0.5;
            let (x0, y0) = (tx.floor(), ty.floor());
            let (fx, fy) = (tx - x0, ty - y0);
            let verdict = |dx: i64, dy: i64| {
                let x = (x0 as i64 + dx).clamp(0, w - 1);
                let y = (y0 as i64 + dy).clamp(0, h - 1);
                let d = f64::from(layer[(y * w + x) as usize]);
                let lit = match self.reversed {
                    true => z >= d,
                    false => z <= d,
                };
                f64::from(u8::from(lit))
            };
            let top = verdict(0, 0) * (1.0 - fx) + verdict(1, 0) * fx;
            let bottom = verdict(0, 1) * (1.0 - fx) + verdict(1, 1) * fx;
            return top * (1.0 - fy) + bottom * fy;
        }
        1.0
    }

    /// The shadow's words in the lights uniform ([`SHADOW_BYTES`]): (source, cascade count,
    /// reversed, 0) as u32 bits, then the cascades' matrices column by column (unused ones
    /// zero). `None`: no shadow.
    pub(crate) fn uniform_words(shadow: Option<&Shadow>) -> Vec<f32> {
        let mut words = vec![0.0f32; SHADOW_BYTES as usize / 4];
        let (source, count, reversed) = match shadow {
            Some(s) => (
                u32::try_from(s.source).unwrap_or(NO_SOURCE),
                s.cascades.len().min(SHADOW_CASCADES_MOST) as u32,
                u32::from(s.reversed),
            ),
            None => (NO_SOURCE, 0, 0),
        };
        words[0] = f32::from_bits(source);
        words[1] = f32::from_bits(count);
        words[2] = f32::from_bits(reversed);
        if let Some(s) = shadow {
            for (k, m) in s.cascades.iter().take(SHADOW_CASCADES_MOST).enumerate() {
                for (j, x) in m.to_cols_array().iter().enumerate() {
                    words[4 + 16 * k + j] = *x as f32;
                }
            }
        }
        words
    }
}

/// The lights uniform's shadow fields, as the struct `Lights` ends in every lit shader.
pub(crate) const SHADOW_FIELDS_WGSL: &str =
    "    shadow: vec4<u32>,\n    cascades: array<mat4x4<f32>, 4>,";

/// `shadow_visibility(p)`, the WGSL twin of [`Shadow::visibility`], shared by the generated
/// draw modules (in the view) and the scene's meshes' shader (in the world). It reads
/// `lights.shadow`, `lights.cascades`, `shadow_map` (a `texture_depth_2d_array`) and the
/// comparison samplers `shadow_standard` (`LessEqual`) and `shadow_reversed`
/// (`GreaterEqual`), both linear and clamped to the edge, which each shader declares at its
/// own bindings (`shadow_declarations_wgsl` in a draw module). The sampler's bilinear
/// weights are the hardware's, a step of 1/256 of a texel on most GPUs.
pub const SHADOW_WGSL: &str = r#"// How much of the shadowed source's light reaches point p (in the lights' space): the first
// cascade whose box holds p decides, by the comparison sampler of the map's depth convention
// (its four nearest texels' verdicts blended bilinearly); 1 in none.
fn shadow_visibility(p: vec3<f32>) -> f32 {
    for (var c = 0u; c < min(lights.shadow.y, 4u); c++) {
        let q = lights.cascades[c] * vec4<f32>(p, 1.0);
        if (q.w <= 0.0) {
            continue;
        }
        let ndc = q.xyz / q.w;
        if (abs(ndc.x) > 1.0 || abs(ndc.y) > 1.0 || ndc.z < 0.0 || ndc.z > 1.0) {
            continue;
        }
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        if (lights.shadow.z == 1u) {
            return textureSampleCompareLevel(shadow_map, shadow_reversed, uv, c, ndc.z);
        }
        return textureSampleCompareLevel(shadow_map, shadow_standard, uv, c, ndc.z);
    }
    return 1.0;
}
"#;

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 4 map, the left half at depth 0.25 and the right at 1, seen straight down -z
    /// by an orthographic projection of the square [-1, 1]² and depth z = -p.z.
    fn half_map(reversed: bool) -> Shadow {
        let d = |x: usize| match (x < 2, reversed) {
            (true, false) => 0.25,
            (true, true) => 0.75,
            (false, false) => 1.0,
            (false, true) => 0.0,
        };
        let layer: Vec<f32> = (0..16).map(|i| d(i % 4)).collect();
        let z = match reversed {
            false => DMat4::from_cols_array(&[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ]),
            true => DMat4::from_cols_array(&[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0,
            ]),
        };
        Shadow {
            source: 0,
            cascades: vec![z],
            reversed,
            depths: Some(ShadowDepths {
                width: 4,
                height: 4,
                layers: vec![layer],
            }),
        }
    }

    #[test]
    fn a_point_behind_the_near_half_is_shadowed_and_the_edge_ramps() {
        for reversed in [false, true] {
            let s = half_map(reversed);
            // Texel centres at x = -0.75, -0.25, 0.25, 0.75; depth 0.5 is behind 0.25.
            assert_eq!(s.visibility(DVec3::new(-0.75, 0.0, -0.5)), 0.0);
            assert_eq!(s.visibility(DVec3::new(0.75, 0.0, -0.5)), 1.0);
            // In front of the near half: lit; beyond the map's depths, in no cascade: lit.
            assert_eq!(s.visibility(DVec3::new(-0.75, 0.0, -0.1)), 1.0);
            assert_eq!(s.visibility(DVec3::new(-0.75, 0.0, -1.5)), 1.0);
            // Halfway between the last shadowing and the first lit texel centre: half lit.
            assert!((s.visibility(DVec3::new(0.0, 0.0, -0.5)) - 0.5).abs() < 1e-12);
            // Outside the map: lit.
            assert_eq!(s.visibility(DVec3::new(-1.5, 0.0, -0.5)), 1.0);
        }
    }

    #[test]
    fn moving_the_lights_moves_the_map_with_them() {
        let s = half_map(false);
        let m = DMat4::from_translation(DVec3::new(3.0, 0.0, 0.0));
        let moved = s.transformed(m);
        for p in [DVec3::new(-0.75, 0.1, -0.5), DVec3::new(0.1, -0.3, -0.7)] {
            assert_eq!(s.visibility(p), moved.visibility(m.transform_point3(p)));
        }
    }

    #[test]
    fn without_depths_or_cascades_nothing_is_shadowed() {
        let mut s = half_map(false);
        s.depths = None;
        assert_eq!(s.visibility(DVec3::new(-0.75, 0.0, -0.5)), 1.0);
        let none = Shadow::of_source(0);
        assert_eq!(none.visibility(DVec3::ZERO), 1.0);
        let words = Shadow::uniform_words(None);
        assert_eq!(words[0].to_bits(), NO_SOURCE);
        assert_eq!(words.len() as u64 * 4, SHADOW_BYTES);
    }
}
