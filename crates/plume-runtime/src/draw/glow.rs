//! Bloom for `plume render`'s images (`render.glow`): the effect is drawn into an HDR image
//! ([`HDR_FORMAT`]); two compute passes ([`glow.wgsl`](glow.wgsl)) blur the light above the
//! threshold (at most the glow's clamp) with a separable Gaussian and add it back, clamped,
//! into the RGBA8 image that is read back. The embedding API leaves post-processing to the host: this is
//! [`crate::outputs::Offscreen`]'s alone.

use plume_compiler::schema::Glow;

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// The format the effect is drawn into when it glows: additive sprites can add up past 1.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The HDR image to draw into and the bloom passes into an RGBA8 image, for one image size.
pub struct GlowPasses {
    hdr: wgpu::TextureView,
    /// The HDR image itself (the compute renderer copies its image into it).
    hdr_texture: wgpu::Texture,
    blur_x: (wgpu::ComputePipeline, wgpu::BindGroup),
    blur_y: (wgpu::ComputePipeline, wgpu::BindGroup),
    groups: (u32, u32),
}

/// The blur's taps on each side of the centre and its exponent factor −1 / (2 σ²), for a
/// standard deviation of `radius` × `height` texels (at least half a texel): taps reach 3 σ.
pub(crate) fn kernel(radius: f64, height: u32) -> (i32, f32) {
    let sigma = (radius * f64::from(height)).max(0.5);
    (
        (3.0 * sigma).ceil() as i32,
        (-1.0 / (2.0 * sigma * sigma)) as f32,
    )
}

impl GlowPasses {
    /// A [`HDR_FORMAT`] image of `width` x `height` (see [`Self::hdr`]) and the passes that
    /// bloom it into `image` (RGBA8, the same size, with `STORAGE_BINDING`).
    pub fn new(
        gpu: &Gpu,
        glow: &Glow,
        image: &wgpu::TextureView,
        width: u32,
        height: u32,
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let (taps, falloff) = kernel(glow.radius, height);
        // `Params` is five words; the buffer is a whole number of 16-byte rows.
        let mut bytes = Vec::with_capacity(32);
        bytes.extend_from_slice(&(glow.threshold as f32).to_le_bytes());
        bytes.extend_from_slice(&(glow.strength as f32).to_le_bytes());
        bytes.extend_from_slice(&taps.to_le_bytes());
        bytes.extend_from_slice(&falloff.to_le_bytes());
        bytes.extend_from_slice(&(glow.clamp as f32).to_le_bytes());
        bytes.resize(32, 0);
        let params = crate::device::buffers::filled_buffer(
            gpu,
            "glow params",
            32,
            wgpu::BufferUsages::UNIFORM,
            |b| b.copy_from_slice(&bytes),
        )?;
        let hdr_image = |label, usage| {
            gpu.texture_2d(
                label,
                (width, height),
                HDR_FORMAT,
                usage | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let hdr_texture = hdr_image(
            "frame, HDR",
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST,
        );
        let hdr = hdr_texture.create_view(&Default::default());
        let blurred = hdr_image("glow blurred along x", wgpu::TextureUsages::STORAGE_BINDING)
            .create_view(&Default::default());
        let module = gpu.shader_module("glow", include_str!("glow.wgsl"));
        let pass = |entry: &str, views: &[(u32, &wgpu::TextureView)]| {
            let pipeline = gpu.compute_pipeline(&module, entry, None);
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            }];
            entries.extend(views.iter().map(|(binding, view)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: wgpu::BindingResource::TextureView(view),
            }));
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            (pipeline, group)
        };
        let blur_x = pass("blur_x", &[(1, &hdr), (2, &blurred)]);
        let blur_y = pass("blur_y_and_add", &[(1, &blurred), (3, &hdr), (4, image)]);
        gpu.take_error()?;
        Ok(Self {
            hdr,
            hdr_texture,
            blur_x,
            blur_y,
            groups: (width.div_ceil(8), height.div_ceil(8)),
        })
    }

    /// The HDR image to draw the effect into (a colour attachment of [`HDR_FORMAT`]).
    pub fn hdr(&self) -> &wgpu::TextureView {
        &self.hdr
    }

    /// The HDR image as a texture (a copy destination).
    pub(crate) fn hdr_texture(&self) -> &wgpu::Texture {
        &self.hdr_texture
    }

    /// Records both passes (after the effect's draw into the HDR image).
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("glow"),
            timestamp_writes: None,
        });
        self.record_into(&mut pass);
    }

    /// Records both passes' dispatches into the caller's compute pass (the benchmark times
    /// them so).
    pub(crate) fn record_into(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (pipeline, group) in [&self.blur_x, &self.blur_y] {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_reaches_three_sigma() {
        // 1% of 1080 rows: sigma 10.8 texels, 33 taps each side.
        let (taps, falloff) = kernel(0.01, 1080);
        assert_eq!(taps, 33);
        assert!((falloff - (-1.0 / (2.0 * 10.8 * 10.8)) as f32).abs() < 1e-9);
        // Tiny images still blur over half a texel.
        assert_eq!(kernel(0.01, 10).0, 2);
    }
}
