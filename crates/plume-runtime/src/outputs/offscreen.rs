//! Headless drawing: an RGBA8 texture cleared to the effect's background, an effect drawn into
//! it through the same [`EffectRenderer`] a host application uses, and the image read back.
//! `plume render`, `plume bench --render`, the embed example's `--headless` mode and the tests
//! draw this way.

use glam::DVec3;

use crate::device::gpu::Gpu;
use crate::device::readback::read_texture;
use crate::draw::camera::Camera;
use crate::draw::glow::{GlowPasses, HDR_FORMAT};
use crate::draw::renderer::EffectRenderer;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::outputs::scene::Scene;
use crate::sim::effect::Effect;
use plume_compiler::schema::Glow;

/// The image format: 8-bit RGBA, no sRGB conversion (what the images encode as is).
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// An offscreen colour target of one size.
pub struct Offscreen {
    gpu: Gpu,
    width: u32,
    height: u32,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// With glow: the HDR image drawn into and the bloom passes that turn it into `texture`.
    glow: Option<GlowPasses>,
    /// The depth buffer of a draw that writes depth (opaque mesh particles), made on first use.
    depth: std::sync::OnceLock<wgpu::TextureView>,
}

impl Offscreen {
    /// A `width` x `height` target on `gpu`.
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Result<Self, RuntimeError> {
        Self::with_glow(gpu, width, height, None)
    }

    /// A `width` x `height` target on `gpu` that, given a `glow`, draws into an HDR image and
    /// blooms it into the RGBA8 one ([`crate::outputs::GlowPasses`]).
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::outputs::{Offscreen, HDR_FORMAT};
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "spark", capacity: 8,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     render: Render(color: [(0.0, (1.0, 0.8, 0.4, 0.5))], size: [(0.0, 1.0)], blend: Additive,
    ///                    glow: Some(Glow(threshold: 0.5, strength: 2.0, radius: 0.05))))"#;
    /// let effect = plume_compiler::compile_str(source, &Default::default())?;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let target = Offscreen::with_glow(&gpu, 64, 64, effect.ir.render.glow.as_ref())?;
    /// assert_eq!(target.target().color_format, HDR_FORMAT); // the effect draws into HDR
    /// let mut spark = Effect::new(&gpu, effect)?;
    /// spark.run(1, |_| {})?;
    /// let image = target.render(&spark, &spark.renderer(&target.target())?, &target.effect_camera(&spark))?;
    /// assert_eq!(image.len(), 64 * 64 * 4); // bloomed, clamped, RGBA8
    /// # Ok(())
    /// # }
    /// ```
    pub fn with_glow(
        gpu: &Gpu,
        width: u32,
        height: u32,
        glow: Option<&Glow>,
    ) -> Result<Self, RuntimeError> {
        let max = gpu.limits.max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RuntimeError::Output(format!(
                "image size {width}x{height} must be between 1x1 and {max}x{max} on this adapter"
            )));
        }
        // The bloom passes write the image when it glows.
        let storage = match glow {
            Some(_) => wgpu::TextureUsages::STORAGE_BINDING,
            None => wgpu::TextureUsages::empty(),
        };
        let texture = gpu.texture_2d(
            "frame",
            (width, height),
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | storage,
        );
        let view = texture.create_view(&Default::default());
        let glow = match glow {
            Some(g) => Some(GlowPasses::new(gpu, g, &view, width, height)?),
            None => None,
        };
        gpu.take_error()?;
        Ok(Self {
            gpu: gpu.clone(),
            width,
            height,
            texture,
            view,
            glow,
            depth: std::sync::OnceLock::new(),
        })
    }

    /// What a renderer for this target must match: the RGBA8 image, or the HDR one when it
    /// glows.
    pub fn target(&self) -> DrawTarget {
        DrawTarget::new(match self.glow {
            Some(_) => HDR_FORMAT,
            None => FORMAT,
        })
    }

    /// [`Self::target`] for `effect`: with a depth buffer its opaque and cut-out mesh particles
    /// write ([`DrawTarget::with_depth_writes`]), so that the nearest shows where they overlap,
    /// when any group draws them; the plain target otherwise.
    pub fn target_for(&self, effect: &Effect) -> DrawTarget {
        match draws_solid_meshes(effect) {
            true => self
                .target()
                .with_depth(crate::outputs::scene::DEPTH_FORMAT)
                .with_depth_writes(true),
            false => self.target(),
        }
    }

    /// The depth attachment of a draw that writes depth, cleared to the far plane.
    fn depth_attachment(&self) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        let view = self.depth.get_or_init(|| {
            self.gpu
                .texture_2d(
                    "frame depth",
                    (self.width, self.height),
                    crate::outputs::scene::DEPTH_FORMAT,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                )
                .create_view(&Default::default())
        });
        wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }
    }

    /// The bloom passes, when the target glows.
    pub fn glow(&self) -> Option<&GlowPasses> {
        self.glow.as_ref()
    }

    /// The image's width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The effect's own camera at this image's aspect.
    pub fn effect_camera(&self, effect: &Effect) -> Camera {
        effect.camera(self.width as f32 / self.height as f32)
    }

    /// The colour attachment, cleared to `background`, for a render pass of the caller's (one
    /// with its own depth attachment, say).
    /// With glow this is the HDR image, bloomed into the RGBA8 one by [`Self::finish`].
    pub fn attachment(&self, background: DVec3) -> wgpu::RenderPassColorAttachment<'_> {
        wgpu::RenderPassColorAttachment {
            view: self.glow.as_ref().map_or(&self.view, GlowPasses::hdr),
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: background.x,
                    g: background.y,
                    b: background.z,
                    a: 1.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        }
    }

    /// Records the draw of `effect` (every group `renderer` draws) from `camera` over the
    /// background of the first group it draws (the top-level one's) into `encoder`, with the render pass's time written to `timestamps` when
    /// given.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        effect: &Effect,
        renderer: &EffectRenderer,
        camera: &Camera,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> Result<(), RuntimeError> {
        effect.prepare_draw(encoder, renderer, camera)?;
        let background = effect
            .group_compiled(renderer.first_group())?
            .ir
            .render
            .background;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("particles"),
            color_attachments: &[Some(self.attachment(background))],
            depth_stencil_attachment: renderer.writes_depth().then(|| self.depth_attachment()),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        renderer.draw(&mut pass);
        drop(pass);
        self.finish(encoder);
        Ok(())
    }

    /// As [`Self::record`], over `scene`: the scene's pass clears the image to the background
    /// and draws its meshes with depth, then the particles are drawn tested against that depth
    /// (`renderer`, raster or compute, must be made for [`Scene::target`] of this target's; the
    /// draw is prepared after the meshes, whose depth a compute renderer reads).
    pub fn record_over_scene(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        effect: &Effect,
        renderer: &EffectRenderer,
        camera: &Camera,
        scene: &Scene,
    ) -> Result<(), RuntimeError> {
        let background = effect
            .group_compiled(renderer.first_group())?
            .ir
            .render
            .background;
        scene.record(encoder, self.attachment(background), camera);
        effect.prepare_draw(encoder, renderer, camera)?;
        let mut color = self.attachment(background);
        color.ops.load = wgpu::LoadOp::Load;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("particles over the scene"),
            color_attachments: &[Some(color)],
            depth_stencil_attachment: Some(scene.particle_depth()),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        renderer.draw(&mut pass);
        drop(pass);
        self.finish(encoder);
        Ok(())
    }

    /// Draws `effect` over `scene` ([`Self::record_over_scene`]) and returns the image.
    pub fn render_over_scene(
        &self,
        effect: &Effect,
        renderer: &EffectRenderer,
        camera: &Camera,
        scene: &Scene,
    ) -> Result<Vec<u8>, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.record_over_scene(&mut encoder, effect, renderer, camera, scene)?;
        self.submit_and_read(encoder)
    }

    /// Records what turns the drawn attachment into the image read back: the bloom passes
    /// when it glows, nothing otherwise (after a render pass of the caller's into
    /// [`Self::attachment`]).
    pub fn finish(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(passes) = &self.glow {
            passes.record(encoder);
        }
    }

    /// Draws `effect` (every group `renderer` draws, in group order, over the first one's
    /// background) from `camera` and returns the image as RGBA8 rows, top row first.
    pub fn render(
        &self,
        effect: &Effect,
        renderer: &EffectRenderer,
        camera: &Camera,
    ) -> Result<Vec<u8>, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.record(&mut encoder, effect, renderer, camera, None)?;
        self.submit_and_read(encoder)
    }

    /// Submits `encoder`, then reads the target back.
    fn submit_and_read(&self, encoder: wgpu::CommandEncoder) -> Result<Vec<u8>, RuntimeError> {
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        self.read()
    }

    /// Reads the target back as RGBA8 rows (waits for the GPU).
    pub fn read(&self) -> Result<Vec<u8>, RuntimeError> {
        read_texture(&self.gpu, &self.texture, self.width, self.height)
    }
}

/// Whether a group of `effect` draws opaque or cut-out mesh particles.
fn draws_solid_meshes(effect: &Effect) -> bool {
    (0..effect.group_names().len()).any(|g| {
        effect.group_compiled(g).is_ok_and(|c| {
            c.ir.render.mesh.is_some()
                && matches!(
                    c.ir.render.blend,
                    plume_compiler::schema::Blend::Opaque | plume_compiler::schema::Blend::Mask(_)
                )
        })
    })
}
