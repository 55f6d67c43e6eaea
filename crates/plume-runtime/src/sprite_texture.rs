//! An effect's sprite texture on the GPU (`render.texture`, loaded by the compiler): the RGBA8
//! image uploaded once, and the linear, clamp-to-edge sampler the draw module samples it with.

use plume_compiler::texture::TextureIr;
use wgpu::util::DeviceExt;

use crate::error::RuntimeError;
use crate::gpu::{texture_2d_descriptor, Gpu};

/// The texture's view and its sampler, ready to bind.
pub struct SpriteTexture {
    /// The whole image, one mip level.
    pub view: wgpu::TextureView,
    /// Linear filtering, clamped to the edge.
    pub sampler: wgpu::Sampler,
}

impl SpriteTexture {
    /// Uploads `texture` (texels stored as they are: `Rgba8Unorm`, no sRGB decoding, as the
    /// effect's colour stops).
    pub fn new(gpu: &Gpu, texture: &TextureIr) -> Result<Self, RuntimeError> {
        Self::from_rgba(gpu, texture.width, texture.height, &texture.rgba)
    }

    /// Uploads `width` x `height` RGBA8 texels, rows top to bottom.
    pub fn from_rgba(
        gpu: &Gpu,
        width: u32,
        height: u32,
        rgba: &[u8],
    ) -> Result<Self, RuntimeError> {
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width > max || height > max {
            return Err(RuntimeError::Unsupported(format!(
                "{}: a {width}x{height} sprite texture is larger than its largest texture, {max} texels on a side",
                gpu.info.name
            )));
        }
        let texture = gpu.device.create_texture_with_data(
            &gpu.queue,
            &texture_2d_descriptor(
                "sprite texture",
                (width, height),
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            wgpu::util::TextureDataOrder::LayerMajor,
            rgba,
        );
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sprite sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        gpu.take_error()?;
        Ok(Self {
            view: texture.create_view(&Default::default()),
            sampler,
        })
    }
}
