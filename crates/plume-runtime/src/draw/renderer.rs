//! The public draw of an effect: [`EffectRenderer`], every group's draw (ribbons, then sprites)
//! into one kind of target, and the [`Effect`] methods that make one and prepare it each frame.
//! The draw is recorded into the caller's render pass; everything it needs first is recorded
//! into the caller's encoder, outside any pass.

use plume_compiler::reference::ParticleRecord;

use crate::draw::camera::Camera;
use crate::draw::raster::{DrawOptions, GroupDraw};
use crate::draw::splat::HostSplat;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;

/// An effect's draw into render targets like one [`DrawTarget`], trails included, in one of
/// two ways:
/// - raster ([`Effect::renderer`]): each group's draw module on a render pipeline for that
///   target, drawn in the host's render pass;
/// - compute ([`Effect::compute_renderer`]): the compute renderer composites every group into an
///   image of its own, tested against the host's depth, and the host's render pass puts that
///   image over its colour with one full-screen triangle. Faster where raster units are few,
///   as on data-centre GPUs, by far for large effects (docs/performance.md, "The compute
///   renderer").
///
/// Prepared each frame by [`Effect::prepare_draw`], recorded into a render pass by
/// [`Self::draw`].
pub struct EffectRenderer {
    /// (group index, its draw), in group order (raster).
    parts: Vec<(usize, GroupDraw)>,
    /// The compute renderer into the host's images (compute).
    compute: Option<HostSplat>,
    /// The shadow map bound last ([`Self::set_shadow_map`]), so that binding it again is free.
    shadow_map: Option<wgpu::Texture>,
}

impl EffectRenderer {
    /// Records the draw of every group, in group order, into the caller's render pass (after
    /// [`Effect::prepare_draw`] in the same or an earlier submission). Sets its own pipelines
    /// and bind group 0.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(compute) = &self.compute {
            compute.draw(pass);
        }
        for (_, part) in &self.parts {
            part.draw(pass);
        }
    }

    /// Whether this draw fades sprites near the scene's depth (a group has `render.soft` and
    /// the target a depth buffer): then bind the host's depth with [`Self::set_scene_depth`].
    pub fn is_soft(&self) -> bool {
        self.compute.as_ref().is_some_and(HostSplat::is_soft)
            || self.parts.iter().any(|(_, part)| part.is_soft())
    }

    /// Whether a group writes depth: opaque or cut-out mesh particles drawn into a target made
    /// [`DrawTarget::with_depth_writes`], whose pass then needs a writable depth attachment.
    pub fn writes_depth(&self) -> bool {
        self.parts.iter().any(|(_, part)| part.writes_depth())
    }

    /// Whether this is the compute renderer ([`Effect::compute_renderer`]).
    pub fn is_compute(&self) -> bool {
        self.compute.is_some()
    }

    /// The target size a compute renderer was made for (a target of another size needs a new
    /// one); None for the raster renderer, which draws into any size.
    pub fn size(&self) -> Option<(u32, u32)> {
        self.compute.as_ref().map(HostSplat::size)
    }

    /// Binds the host's depth buffer for soft particles: a depth-only view (of a texture
    /// created with `TEXTURE_BINDING`, single-sampled, of a depth format) holding the scene's
    /// depth, read as an unfilterable float texture. It may be the very texture the render pass
    /// tests against if that pass keeps its depth attachment read-only (`depth_ops: None`) and
    /// the adapter offers `DownlevelFlags::READ_ONLY_DEPTH_STENCIL` (Vulkan does; GL does not:
    /// there, write the scene's depth into a second texture as well and bind that one).
    /// Call it again when the texture changes (a resize); until the first call sprites are not
    /// faded. Does nothing for a draw that is not soft.
    ///
    /// The compute renderer reads the host's depth for every sprite, soft or not: it copies
    /// `depth`'s texture (any depth format and sample count, multisampled ones by sample 0,
    /// with `TEXTURE_BINDING`, of the renderer's size) in each [`Effect::prepare_draw`], so
    /// record that after the host has drawn its depth; until the first call nothing hides
    /// the particles.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{DrawTarget, Effect, Gpu};
    /// let source = r#"Effect(name: "mist", capacity: 8,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     render: Render(soft: Some(0.5)))"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mist = Effect::from_source(&gpu, source, &Default::default())?;
    /// let depth_format = wgpu::TextureFormat::Depth32Float;
    /// let target = DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm).with_depth(depth_format);
    /// let mut particles = mist.renderer(&target)?;
    /// assert!(particles.is_soft());
    /// // The host's depth buffer, made bindable.
    /// let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    /// let depth = gpu.texture_2d("host depth", (640, 360), depth_format, usage);
    /// particles.set_scene_depth(&depth.create_view(&Default::default()));
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_scene_depth(&mut self, depth: &wgpu::TextureView) {
        if let Some(compute) = &self.compute {
            compute.set_scene_depth(depth);
        }
        for (_, part) in &mut self.parts {
            part.set_scene_depth(depth);
        }
    }

    /// For the compute renderer over a host whose depth it cannot read: puts its image over
    /// the host's at NDC depth `depth` (the effect's place, say its origin's depth), tested
    /// against the pass's depth attachment by the target's compare function, so that what the
    /// host drew in front of that depth hides the effect. None (the default): everywhere, each
    /// pixel tested against the host's depth bound with [`Self::set_scene_depth`]. Nothing for
    /// the raster renderer, whose fragments test their own depths.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{glam, DrawTarget, Effect, Gpu};
    /// let source = r#"Effect(name: "dots", capacity: 8,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let dots = Effect::from_source(&gpu, source, &Default::default())?;
    /// // A host with reversed depth (Greater) whose depth texture is not bindable.
    /// let target = DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm)
    ///     .with_depth_compare(wgpu::TextureFormat::Depth32Float, wgpu::CompareFunction::Greater);
    /// let mut particles = dots.compute_renderer(&target, 320, 180)?;
    /// // The effect's origin, 5 m in front of the host's camera, in NDC depth.
    /// let proj = glam::Mat4::perspective_infinite_reverse_rh(1.0, 16.0 / 9.0, 0.1);
    /// let clip = proj * glam::Vec4::new(0.0, 0.0, -5.0, 1.0);
    /// particles.set_composite_depth(Some(clip.z / clip.w));
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_composite_depth(&mut self, depth: Option<f32>) {
        if let Some(compute) = &self.compute {
            compute.set_composite_depth(depth);
        }
    }

    /// Scales every sprite's size (1: the effect's own sizes).
    pub fn set_size_scale(&mut self, scale: f32) {
        if let Some(compute) = &self.compute {
            compute.set_size_scale(scale);
        }
        for (_, part) in &mut self.parts {
            part.set_size_scale(scale);
        }
    }

    /// Lights the sprites of every group whose look is lit (`render.lit`) with `lights`, in
    /// world space, from the next frame on: a host's own lights (the Bevy plugin passes
    /// Bevy's). Until the first call they are the effect file's `lights` (or, where it names
    /// none, the default sun and ambient light). Does nothing for unlit groups.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{glam, DrawTarget, Effect, Gpu, LightSource, Lights};
    /// let source = r#"Effect(name: "puffs", capacity: 8,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     render: Render(lit: Some(Lit(normals: Sphere))))"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let puffs = Effect::from_source(&gpu, source, &Default::default())?;
    /// let mut particles = puffs.renderer(&DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm))?;
    /// // A red lamp 2 m above, and a little grey ambient light.
    /// particles.set_lights(&Lights {
    ///     ambient: glam::DVec3::splat(0.1),
    ///     sources: vec![LightSource::Point {
    ///         position: glam::DVec3::new(0.0, 2.0, 0.0),
    ///         color: glam::DVec3::new(4.0, 0.5, 0.5),
    ///         range: 10.0,
    ///     }],
    ///     shadow: None,
    /// });
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_lights(&mut self, lights: &plume_compiler::lights::Lights) {
        if let Some(compute) = &self.compute {
            compute.set_lights(lights);
        }
        for (_, part) in &self.parts {
            part.set_lights(lights);
        }
    }

    /// Reads `map` as the shadow map of the lights' shadow ([`plume_compiler::shadow`]):
    /// the directional light that [`Lights::shadow`](plume_compiler::lights::Lights) names
    /// gives a lit sprite or mesh only as much light as the map lets through. `map` is a
    /// single-sampled 2D depth texture with `TEXTURE_BINDING`, layer k holding cascade k of
    /// the shadow's `cascades` (one layer for a single map); its depths are read as they are
    /// when the frame is drawn. Call it again when the texture changes; until the first call,
    /// or while the lights name no shadow, nothing is shadowed. Does nothing for unlit
    /// groups; an error for a texture that cannot be read so, and for a lit effect compiled
    /// without the lookup (compile it with `CompileOptions::receive_shadows`, or give a light
    /// of its file `shadow: true`). Giving the texture bound already costs nothing, so a host
    /// may give it every frame.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{glam, DrawTarget, Effect, Gpu, LightSource, Lights, Shadow};
    /// let source = r#"Effect(name: "puffs", capacity: 8,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     render: Render(lit: Some(Lit(normals: Sphere))))"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// // Its file casts no shadow: compiled to read the host's map.
    /// let options = plume_compiler::CompileOptions { receive_shadows: true, ..Default::default() };
    /// let puffs = Effect::from_source(&gpu, source, &options)?;
    /// let mut particles = puffs.renderer(&DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm))?;
    /// // The host's shadow map of the sun, drawn by the host from the sun's view.
    /// let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    /// let map = gpu.texture_2d("sun shadow", (1024, 1024), wgpu::TextureFormat::Depth32Float, usage);
    /// let sun_view = glam::DMat4::look_at_rh(glam::DVec3::new(0.0, 10.0, 0.0), glam::DVec3::ZERO, glam::DVec3::Z);
    /// let sun_clip = glam::DMat4::orthographic_rh(-5.0, 5.0, -5.0, 5.0, 0.0, 20.0) * sun_view;
    /// particles.set_lights(&Lights {
    ///     ambient: glam::DVec3::splat(0.2),
    ///     sources: vec![LightSource::Directional { direction: -glam::DVec3::Y, color: glam::DVec3::ONE }],
    ///     shadow: Some(Shadow { cascades: vec![sun_clip], ..Shadow::of_source(0) }),
    /// });
    /// particles.set_shadow_map(&map)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_shadow_map(&mut self, map: &wgpu::Texture) -> Result<(), RuntimeError> {
        if self.shadow_map.as_ref() == Some(map) {
            return Ok(());
        }
        let view = crate::draw::lights::shadow_map_view(map)?;
        let parts = self.parts.iter().map(|(_, p)| p.lit_and_shadowed());
        let compute = self.compute.as_ref().map(HostSplat::lit_and_shadowed);
        crate::draw::lights::check_reads_shadows(parts.chain(compute))?;
        self.shadow_map = Some(map.clone());
        if let Some(compute) = &self.compute {
            compute.set_shadow_map(&view);
        }
        for (_, part) in &mut self.parts {
            part.set_shadow_map(&view);
        }
        Ok(())
    }

    /// The first group this renderer draws (the top-level one, unless it draws one group
    /// alone): whose background a headless image is cleared to.
    pub(crate) fn first_group(&self) -> usize {
        self.parts.first().map_or(0, |(g, _)| *g)
    }

    /// Records what decides every part's instances on the GPU (the live count, or the
    /// compacted list), as [`Effect::prepare_draw`] does (the benchmark times it alone).
    #[cfg(feature = "tools")]
    pub(crate) fn record_instance_counts(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
    ) -> Result<(), RuntimeError> {
        for (_, part) in &self.parts {
            part.record_instance_count(pass)?;
        }
        Ok(())
    }
}

impl Effect {
    /// A draw of this effect, every group, into render targets like `target`. Create one per
    /// kind of target; reuse it every frame.
    pub fn renderer(&self, target: &DrawTarget) -> Result<EffectRenderer, RuntimeError> {
        self.renderer_with(target, &DrawOptions::default())
    }

    /// Like [`Self::renderer`] with other choices ([`DrawOptions`]: the benchmarks' and the
    /// tests').
    pub(crate) fn renderer_with(
        &self,
        target: &DrawTarget,
        options: &DrawOptions,
    ) -> Result<EffectRenderer, RuntimeError> {
        let parts = (0..self.groups().len())
            .map(|g| Ok((g, self.group_draw(g, target, options)?)))
            .collect::<Result<_, RuntimeError>>()?;
        Ok(EffectRenderer {
            parts,
            compute: None,
            shadow_map: None,
        })
    }

    /// The compute renderer of this effect, every group, into `width` x `height` targets like
    /// `target` ([`EffectRenderer`] says how it draws). Its image is the raster draw's, as
    /// `plume render --draw compute` draws it: every sprite look, ribbons, solid meshes, the depth test (`Less`,
    /// `LessEqual`, `Greater`, `GreaterEqual` or `Always`) and soft particles. The host records
    /// [`Effect::prepare_draw`] after its depth is drawn (the compute renderer reads it in a compute
    /// pass), then [`EffectRenderer::draw`] in a pass over its colour (any format and sample
    /// count). A glowing effect puts its light into the host's target as it is (an HDR target
    /// keeps it, for the host's bloom), as the raster renderer does. Make a new one when the
    /// target's size changes. An error for what the compute renderer cannot draw over a host
    /// ([`crate::outputs::ComputeOffscreen::why_not`]).
    pub fn compute_renderer(
        &self,
        target: &DrawTarget,
        width: u32,
        height: u32,
    ) -> Result<EffectRenderer, RuntimeError> {
        Ok(EffectRenderer {
            parts: Vec::new(),
            compute: Some(HostSplat::new(self, target, width, height)?),
            shadow_map: None,
        })
    }

    /// A renderer that draws group `g` alone (the tests compare each group's draw).
    #[cfg(feature = "tools")]
    pub(crate) fn group_renderer(
        &self,
        g: usize,
        target: &DrawTarget,
    ) -> Result<EffectRenderer, RuntimeError> {
        let part = self.group_draw(g, target, &DrawOptions::default())?;
        Ok(EffectRenderer {
            parts: vec![(g, part)],
            compute: None,
            shadow_map: None,
        })
    }

    fn group_draw(
        &self,
        g: usize,
        target: &DrawTarget,
        options: &DrawOptions,
    ) -> Result<GroupDraw, RuntimeError> {
        let group = self.group(g)?;
        GroupDraw::new(&group.gpu, &group.effect, &group.res, target, options)
    }

    /// Records what a draw from `camera` needs this frame into the caller's `encoder`, outside
    /// any render pass, for every group `renderer` draws: the camera and the steps done; for a
    /// stateless group its segment table; for `sort: true` the depth keys and their sort along
    /// the camera's axis, and the live count of the indirect draw. Then call
    /// [`EffectRenderer::draw`] in a render pass. An unsorted stateless effect records no
    /// compute pass at all. For the compute renderer it records the whole splat (the host's
    /// depth copied, every group composited), so record it after the host's depth is drawn;
    /// its image is only read by the draw.
    pub fn prepare_draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        renderer: &EffectRenderer,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        if let Some(compute) = &renderer.compute {
            compute.prepare(encoder, self, camera)?;
        }
        for (g, part) in &renderer.parts {
            let frame = self.group(*g)?.prepare_frame(encoder, camera)?;
            part.write_view(encoder, camera, frame.steps)?;
            part.set_frame_instances(frame.threads);
            if part.counts_on_gpu() {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("draw count"),
                    timestamp_writes: None,
                });
                part.record_instance_count(&mut pass)?;
            }
        }
        Ok(())
    }

    /// The effect's own camera (the top-level group's `camera`) for an image of `aspect` =
    /// width / height. A host may draw from any [`Camera`] of its own instead.
    pub fn camera(&self, aspect: f32) -> Camera {
        Camera::from_effect(&self.compiled().ir.camera, aspect)
    }

    /// The live particles of every group in draw order, group by group: each sorted by its
    /// 16-bit depth keys on the GPU from the effect's camera, farthest first; equal keys by
    /// id, so the order is the same run after run. An error for a group with `sort: false`.
    pub fn records_in_draw_order(&self) -> Result<Vec<ParticleRecord>, RuntimeError> {
        let mut out = Vec::new();
        for group in self.groups() {
            out.extend(group.records_in_draw_order()?);
        }
        Ok(out)
    }
}
