//! The preview's frame target: the effect is drawn into an RGBA8 texture, the format
//! `plume render` writes, so the window shows the same colours and a screenshot is exactly the
//! effect's image; a fullscreen triangle then copies it onto the window's surface, pixel for
//! pixel, and the on-screen text goes over that. An effect with `render.glow` is drawn into an
//! HDR texture and bloomed into the frame, as `plume render` does.

use plume_compiler::schema::Glow;
use plume_runtime::outputs::{GlowPasses, FORMAT, HDR_FORMAT};
use plume_runtime::Gpu;

const BLIT_WGSL: &str = r#"
@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target: (-1, -1), (3, -1), (-1, 3).
    let p = vec2<f32>(f32((v << 1u) & 2u), f32(v & 2u)) * 2.0 - 1.0;
    return vec4<f32>(p, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(frame, vec2<i32>(p.xy), 0);
}
"#;

/// The frame texture and the copy onto the surface.
pub struct FrameTarget {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    size: (u32, u32),
    blit: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    /// The loaded effect's glow, and while it has one the HDR texture drawn into and the bloom
    /// passes into the frame.
    glow: Option<Glow>,
    bloom: Option<GlowPasses>,
}

impl FrameTarget {
    /// A `width` x `height` frame copied onto surfaces of `surface_format`.
    pub fn new(
        device: &wgpu::Device,
        surface_format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("blit"),
            source: wgpu::ShaderSource::Wgsl(BLIT_WGSL.into()),
        });
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(surface_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let (texture, view, group) = Self::target(device, &blit, size);
        Self {
            texture,
            view,
            size,
            blit,
            group,
            glow: None,
            bloom: None,
        }
    }

    /// Uses `glow` from now on (a newly loaded effect's); on an error nothing changes.
    pub fn set_glow(&mut self, gpu: &Gpu, glow: Option<Glow>) -> Result<(), String> {
        let old = std::mem::replace(&mut self.glow, glow);
        self.rebuild_bloom(gpu).inspect_err(|_| self.glow = old)
    }

    fn rebuild_bloom(&mut self, gpu: &Gpu) -> Result<(), String> {
        self.bloom = match &self.glow {
            Some(g) => {
                let (width, height) = (self.size.0.max(1), self.size.1.max(1));
                let passes = GlowPasses::new(gpu, g, &self.view, width, height);
                Some(passes.map_err(|e| e.to_string())?)
            }
            None => None,
        };
        Ok(())
    }

    /// The format an effect with `glow` is drawn in: the frame's, or the HDR one.
    pub fn draw_format(glow: Option<&Glow>) -> wgpu::TextureFormat {
        match glow {
            Some(_) => HDR_FORMAT,
            None => FORMAT,
        }
    }

    /// Records what turns the drawn texture into the frame: the bloom, while it glows.
    pub fn finish(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(passes) = &self.bloom {
            passes.record(encoder);
        }
    }

    fn target(
        device: &wgpu::Device,
        blit: &wgpu::RenderPipeline,
        (width, height): (u32, u32),
    ) -> (wgpu::Texture, wgpu::TextureView, wgpu::BindGroup) {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("preview frame"),
            size: wgpu::Extent3d {
                width: width.max(1),
                height: height.max(1),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit"),
            layout: &blit.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            }],
        });
        (texture, view, group)
    }

    /// A new size (the window was resized).
    pub fn resize(&mut self, gpu: &Gpu, size: (u32, u32)) -> Result<(), String> {
        if size != self.size {
            (self.texture, self.view, self.group) = Self::target(&gpu.device, &self.blit, size);
            self.size = size;
            self.rebuild_bloom(gpu)?;
        }
        Ok(())
    }

    /// The texture to draw the effect into: the frame, or the HDR one while it glows (then
    /// [`Self::finish`] blooms it into the frame).
    pub fn view(&self) -> &wgpu::TextureView {
        self.bloom.as_ref().map_or(&self.view, GlowPasses::hdr)
    }

    /// The frame texture, to read a screenshot back.
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// Width and height.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Records the copy of the frame onto `target` (the surface texture) into `pass`.
    pub fn blit(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.blit);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..3, 0..1);
    }
}
