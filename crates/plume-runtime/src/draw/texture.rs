//! An effect's sprite texture on the GPU (`render.texture`, loaded by the compiler): the RGBA8
//! image and its mip levels uploaded once, and the trilinear, clamp-to-edge sampler the draw
//! module samples it with. Each level halves the one before with a 2x2 box filter in
//! premultiplied alpha (so transparent texels do not darken the edges of what they border), for
//! as many levels as keep every flipbook frame whole (`TextureIr::mip_levels`).

use plume_compiler::texture::TextureIr;
use wgpu::util::DeviceExt;

use crate::device::gpu::{texture_2d_descriptor, Gpu};
use crate::error::RuntimeError;

/// The texture's view and its sampler, ready to bind.
pub(crate) struct SpriteTexture {
    /// The whole image, with its mip levels.
    pub view: wgpu::TextureView,
    /// Trilinear filtering (linear within and between levels), clamped to the edge.
    pub sampler: wgpu::Sampler,
    /// A lit look's maps (`render.lit.normals`: a normal map, or the six-way lightmaps), laid
    /// out as the texture and read with its sampler, bound at `LIT_MAP_BINDINGS`.
    pub(crate) lit_maps: Vec<wgpu::TextureView>,
    /// The second image (`render.texture.second`), laid out as the texture and read with its
    /// sampler, bound at `SECOND_TEXTURE_BINDING`.
    pub second: Option<wgpu::TextureView>,
}

impl SpriteTexture {
    /// The texture of `render` (None without one), with a lit look's maps.
    pub(crate) fn for_render(
        gpu: &Gpu,
        render: &plume_compiler::ir::RenderIr,
    ) -> Result<Option<Self>, RuntimeError> {
        let Some(texture) = &render.texture else {
            return Ok(None);
        };
        let mut sprite = Self::new(gpu, texture)?;
        for map in &render.lit_maps {
            sprite.lit_maps.push(Self::new(gpu, map)?.view);
        }
        Ok(Some(sprite))
    }

    /// Uploads `texture` (texels stored as they are: `Rgba8Unorm`, no sRGB decoding, as the
    /// effect's colour stops). An error for a texture whose file could not be read when the
    /// effect was compiled to be stepped only (`CompileOptions::step_only`): drawing needs it.
    pub(crate) fn new(gpu: &Gpu, texture: &TextureIr) -> Result<Self, RuntimeError> {
        if let Some(why) = &texture.missing {
            return Err(RuntimeError::Compile(format!(
                "{why} (the effect was compiled to be stepped, not drawn; drawing it needs its texture)"
            )));
        }
        let mut uploaded = Self::from_rgba(
            gpu,
            texture.width,
            texture.height,
            &texture.rgba,
            texture.mip_levels(),
        )?;
        if let Some(second) = &texture.second {
            uploaded.second = Some(Self::new(gpu, second)?.view);
        }
        Ok(uploaded)
    }

    /// Uploads `width` x `height` RGBA8 texels, rows top to bottom, with `levels` mip levels
    /// (each dimension must halve exactly `levels - 1` times).
    pub(crate) fn from_rgba(
        gpu: &Gpu,
        width: u32,
        height: u32,
        rgba: &[u8],
        levels: u32,
    ) -> Result<Self, RuntimeError> {
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width > max || height > max {
            return Err(RuntimeError::Unsupported(format!(
                "{}: a {width}x{height} sprite texture is larger than its largest texture, {max} texels on a side",
                gpu.info.name
            )));
        }
        let descriptor = wgpu::TextureDescriptor {
            mip_level_count: levels,
            ..texture_2d_descriptor(
                "sprite texture",
                (width, height),
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let texture = gpu.device.create_texture_with_data(
            &gpu.queue,
            &descriptor,
            wgpu::util::TextureDataOrder::LayerMajor,
            &mip_chain(width, height, rgba, levels),
        );
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sprite sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        gpu.take_error()?;
        Ok(Self {
            view: texture.create_view(&Default::default()),
            sampler,
            lit_maps: Vec::new(),
            second: None,
        })
    }
}

/// `rgba` (`width` x `height`) followed by `levels - 1` halvings, each texel the 2x2 average of
/// the level above in premultiplied alpha: colour weighted by alpha, then divided by the
/// block's alpha again (a fully transparent block keeps the plain average of its colours).
pub(crate) fn mip_chain(width: u32, height: u32, rgba: &[u8], levels: u32) -> Vec<u8> {
    let mut chain = rgba.to_vec();
    let (mut w, mut h) = (width as usize, height as usize);
    let mut level = rgba.to_vec();
    for _ in 1..levels {
        let (nw, nh) = (w / 2, h / 2);
        let mut next = vec![0u8; nw * nh * 4];
        for y in 0..nh {
            for x in 0..nw {
                let texels = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .map(|(dx, dy)| 4 * ((2 * y + dy) * w + 2 * x + dx));
                let alpha: u32 = texels.iter().map(|&k| u32::from(level[k + 3])).sum();
                let out = 4 * (y * nw + x);
                for c in 0..3 {
                    let weighted: u32 = texels
                        .iter()
                        .map(|&k| u32::from(level[k + c]) * u32::from(level[k + 3]))
                        .sum();
                    let value = match (weighted + alpha / 2).checked_div(alpha) {
                        Some(v) => v,
                        // A fully transparent block: the plain average of its colours.
                        None => {
                            (texels.iter().map(|&k| u32::from(level[k + c])).sum::<u32>() + 2) / 4
                        }
                    };
                    next[out + c] = value as u8;
                }
                next[out + 3] = ((alpha + 2) / 4) as u8;
            }
        }
        chain.extend_from_slice(&next);
        (w, h, level) = (nw, nh, next);
    }
    chain
}

#[cfg(test)]
mod tests {
    use super::mip_chain;

    #[test]
    fn each_level_averages_in_premultiplied_alpha() {
        // 2x2: opaque red, transparent green (its colour must not bleed), opaque white, half
        // blue.
        let rgba = [
            255, 0, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 0, 0, 255, 128,
        ];
        let chain = mip_chain(2, 2, &rgba, 2);
        assert_eq!(&chain[..16], &rgba);
        // alpha sum 638: r = (255·255 + 255·255) / 638, b = (255·255 + 255·128) / 638.
        assert_eq!(&chain[16..], &[204, 102, 153, 160]);
    }

    #[test]
    fn a_transparent_block_keeps_its_plain_colour_and_levels_shrink_to_one_texel() {
        let rgba: Vec<u8> = [10u8, 20, 30, 0].repeat(16);
        let chain = mip_chain(4, 4, &rgba, 3);
        assert_eq!(chain.len(), (16 + 4 + 1) * 4);
        assert_eq!(&chain[chain.len() - 4..], &[10, 20, 30, 0]);
    }
}
