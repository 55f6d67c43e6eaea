//! A second image on a textured sprite (`render.texture.second`), as bevy_hanabi's second
//! texture slot: laid out as the texture (its size, its frames, played with it) and sampled at
//! the same place, its texel mapped by its own `sample` and multiplying the colour beside the
//! first's. One image can give a sprite its shape (`OpacityFromRed`), the other its colours
//! (`ModulateRgb`).

use std::path::Path;

use serde::Deserialize;

use super::{Sample, TextureIr};
use crate::base::writer::Writer;

/// The second image (`render.texture.second`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SecondTexture {
    /// The PNG file, relative to the effect file's directory; the same size as the texture.
    pub file: String,
    /// What its texel does to the sprite's colour.
    #[serde(default)]
    pub sample: Sample,
}

/// Binding of the second image in the draw module (read with the texture's sampler).
pub const SECOND_TEXTURE_BINDING: u32 = 29;

impl TextureIr {
    /// Loads `spec`, laid out as `self` (the texture); the error says what is wrong with the
    /// file, for `render.texture.second.file`.
    pub(crate) fn load_second(
        &self,
        spec: &SecondTexture,
        base_dir: Option<&Path>,
    ) -> Result<Self, String> {
        let mut second = Self::load_laid_out_as(&spec.file, self, base_dir, "a second image")?;
        second.sample = spec.sample;
        Ok(second)
    }

    /// The second image `spec` names, standing in for a file that could not be read
    /// (`missing` says why): laid out as `self`, every texel white.
    pub(crate) fn stand_in_second(&self, spec: &SecondTexture, missing: String) -> Self {
        let mut second = Self::stand_in(&self.spec_of(&spec.file), missing);
        second.sample = spec.sample;
        second
    }

    /// Emits the second image's binding (the texture's own are already declared).
    pub(super) fn emit_second_declaration(&self, w: &mut Writer) {
        w.comment(format!(
            "render.texture.second {:?}, laid out as the texture, sampled where it is.",
            self.file
        ));
        w.line(format!(
            "@group(0) @binding({SECOND_TEXTURE_BINDING}) var second_texture: texture_2d<f32>;"
        ));
    }

    /// Emits `frame_texel(cell, quad, gx, gy)` for a texture with a second image: the two
    /// texels at the same place, each mapped by its own `sample`, multiplied.
    pub(super) fn emit_texel_product_fn(&self, second: &TextureIr, w: &mut Writer) {
        Self::emit_texel_fn_of(w, "first_texel", "sprite_texture");
        Self::emit_texel_fn_of(w, "second_texel", "second_texture");
        let mapped = |sample: Sample| sample.mapped_wgsl().unwrap_or("t");
        w.comment(format!(
            "The texture's texel as its sample ({:?}) maps it, times the second image's ({:?}).",
            self.sample, second.sample
        ));
        w.block(
            "fn frame_texel(cell: vec2<f32>, quad: vec2<f32>, gx: vec2<f32>, gy: vec2<f32>) -> vec4<f32>",
            |w| {
                w.line("var t = first_texel(cell, quad, gx, gy);");
                w.line(format!("let a = {};", mapped(self.sample)));
                w.line("t = second_texel(cell, quad, gx, gy);");
                w.line(format!("return a * {};", mapped(second.sample)));
            },
        );
    }
}
