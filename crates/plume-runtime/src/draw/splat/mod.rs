//! The compute renderer (its modules are named `splat` for what it does: it splats each particle
//! into the screen tiles it covers): another way to draw images, in compute shaders only, for
//! GPUs whose raster units are few (an H100 has graphics units in only a small part of the chip,
//! and the raster draw of 10M sprites is bound by their vertex and primitive rate; see
//! docs/performance.md). It gives the raster draw's image: the same sprites (the draw module's
//! `sprite_at`, through its `project` kernel), coverage tested at pixel centres, the same
//! shading and blend, composited in f32 and rounded once (as the raster draw into a float
//! target is).
//!
//! Sprites are discs (round and camera-facing: a 16-byte record, the fixed `raster` kernel of
//! `splat.wgsl`) or quads (textured, oriented, rotated, of their own height or glowing: a
//! 64-byte record holding the quad's projective map, composited by the effect's generated
//! `composite`, which shades each pixel as the fragment shader does, textures sampled with
//! the same mip levels); see the compiler's `wgsl::draw::splat`.
//!
//! Per group, one compute pass: `project` (each sprite's record and tile count), an exclusive
//! scan of the counts, one (tile, sprite) entry per tile touched, a stable radix sort of the
//! entries by tile (so each tile's sprites stay in draw order), each tile's run, then a
//! workgroup per 16x16 tile composites its sprites front to back ([`group`]). Additive light
//! (discs, quads and ribbons) is summed in fixed point, in any order, so its lists are counted
//! and placed by tile without a sort ([`additive_lists`]), and each tile's list is split over
//! several workgroups whose sums a merge adds up. The groups of an
//! effect share one image, in group order, each over what the ones before drew. Entries are
//! sized from the sprites' count and grown when a frame needs more (the frame is then drawn
//! again). A glowing effect composites into an HDR image and blooms with the raster draw's
//! passes. The embedding API's compute renderer ([`host`]) draws the same splat into a host's
//! images: an HDR image that keeps each pixel's coverage, every pixel tested against a copy of
//! the host's depth, put over the host's colour by one full-screen triangle.
//!
//! A group of solid mesh particles is a part of another kind ([`meshes`]): its meshes covered
//! into a visibility buffer and each pixel shaded once, into the same image.

mod additive_lists;
mod binding;
mod group;
mod host;
mod meshes;
mod quad_raster;

use plume_compiler::wgsl::draw::{splat_hdr_pitch, splat_light_ceiling};
use plume_compiler::EffectIr;

use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::glow::GlowPasses;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use group::SplatImage;
#[cfg(feature = "tools")]
pub(crate) use group::STAGES;
pub(crate) use host::HostSplat;
use meshes::SplatPart;
use plume_compiler::wgsl::draw::SplatHost;

/// A glowing effect's bloom: the compute renderer's HDR image is copied into the glow's HDR texture, and
/// the same two blur passes as the raster draw's write `output` (RGBA8).
struct SplatGlow {
    passes: GlowPasses,
    output: wgpu::Texture,
}

/// A compute renderer of an effect (every group, in group order) into `width` x `height` images.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::outputs::ComputeOffscreen;
/// use plume_runtime::{Effect, Gpu};
/// let source = r#"Effect(name: "streaks", capacity: 64,
///     emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.5),
///                        velocity: Constant((1.0, 0.0, 0.0)))],
///     render: Render(color: [(0.0, (1.0, 0.6, 0.2, 1.0))], size: [(0.0, 0.2)], blend: Additive,
///                    orient: Velocity(stretch: 0.2, max_length: 1.0)))"#;
/// let effect = plume_compiler::compile_str(source, &Default::default())?;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut streaks = Effect::new(&gpu, effect)?;
/// streaks.run(10, |_| {})?;
/// let mut splat = ComputeOffscreen::new(&streaks, 64, 48)?;
/// let image = splat.render(&streaks, &streaks.camera(64.0 / 48.0))?;
/// assert_eq!(image.len(), 64 * 48 * 4); // RGBA8 rows, top row first
/// # Ok(())
/// # }
/// ```
pub struct ComputeOffscreen {
    gpu: Gpu,
    width: u32,
    height: u32,
    /// Per group, its ribbons (if it has a trail) then its sprites, with the group's index;
    /// the first part owns the image the others draw over.
    parts: Vec<(usize, SplatPart)>,
    /// Set when the effect glows (its groups composite into an HDR image).
    glow: Option<SplatGlow>,
    /// The buffer a host's depth is copied into (a host splat whose draw tests depth).
    host_depth: Option<wgpu::Buffer>,
    /// The sprites' size scale (the embedding API's `set_size_scale`).
    size_scale: f32,
}

impl ComputeOffscreen {
    /// Whether the compute renderer can draw `ir`: any sprite (textured or round, any orientation,
    /// rotation and height, glowing or not, lit or not), alpha or additive, trails of a
    /// stateful effect, and solid mesh particles (`render.mesh` with `Opaque` or `Mask`
    /// blending); not ribbons joining
    /// particles (`render.ribbon`), other meshes, nor `Multiply`, `Mask`, `Premultiplied` or
    /// `Opaque` sprites, which the raster draw draws.
    pub fn draws(ir: &EffectIr) -> bool {
        use plume_compiler::schema::Blend;
        use plume_compiler::wgsl::draw::splat_mesh_refusal;
        let look = match ir.render.mesh {
            Some(_) => splat_mesh_refusal(ir).is_none(),
            None => matches!(ir.render.blend, Blend::Alpha | Blend::Additive),
        };
        (ir.render.trail.is_none() || ir.stateless.is_none()) && ir.render.ribbon.is_none() && look
    }

    /// Why the compute renderer cannot draw an effect whose groups are `groups`, or `None` when
    /// it can: a group it does not draw ([`Self::draws`]), or a group after mesh particles (the
    /// raster pipeline tests it against their depth).
    pub fn why_not(groups: &[&EffectIr]) -> Option<&'static str> {
        if groups.iter().any(|ir| !Self::draws(ir)) {
            return Some("the compute renderer draws no ribbons joining particles (render.ribbon), no mesh particles but solid ones (blend: Opaque or Mask), no sprites blended by Multiply, Mask, Premultiplied or Opaque, and no trails of stateless effects");
        }
        let first_mesh = groups.iter().position(|ir| ir.render.mesh.is_some())?;
        groups[first_mesh..]
            .iter()
            .any(|ir| ir.render.mesh.is_none())
            .then_some("the compute renderer draws no sprites after mesh particles, which the raster pipeline tests against the meshes' depth")
    }

    /// A splat of `effect` into `width` x `height` images; an error for sprites it cannot
    /// draw (see [`Self::why_not`]).
    pub fn new(effect: &Effect, width: u32, height: u32) -> Result<Self, RuntimeError> {
        Self::with_host(effect, width, height, None)
    }

    /// [`Self::new`], or for a host's image (`host`: the embedding API's compute draw) an HDR
    /// image that keeps each pixel's coverage and meets the host's depth, with no bloom of
    /// its own (the host's HDR target takes the light as it is).
    pub(crate) fn with_host(
        effect: &Effect,
        width: u32,
        height: u32,
        host: Option<SplatHost>,
    ) -> Result<Self, RuntimeError> {
        if width == 0 || height == 0 {
            return Err(RuntimeError::Output(format!(
                "image size {width}x{height} must be at least 1x1"
            )));
        }
        let irs: Vec<&EffectIr> = effect.groups().iter().map(|g| &g.effect.ir).collect();
        if let Some(why) = Self::why_not(&irs) {
            return Err(RuntimeError::Output(format!(
                "{why}: draw this effect with the raster pipeline (plume render --draw raster)"
            )));
        }
        let gpu = effect.gpu().clone();
        // The top-level group's glow blooms every group, as in `plume render`: all of them
        // composite into one HDR image then.
        let hdr = irs[0].render.glow.is_some() || host.is_some();
        let host_depth = host.and_then(|h| h.depth).map(|_| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat host depth"),
                size: 4 * u64::from(width) * u64::from(height),
                usage: crate::device::buffers::STORAGE,
                mapped_at_creation: false,
            })
        });
        let image = SplatImage {
            width,
            height,
            hdr,
            host,
            host_depth: host_depth.clone(),
            // The glow's clamp: light past it blooms as it does, so a pixel there is finished.
            // A host's image takes the light as it is.
            light_ceiling: splat_light_ceiling(
                irs[0]
                    .render
                    .glow
                    .filter(|_| host.is_none())
                    .map(|g| g.clamp),
            ),
        };
        let mut parts: Vec<(usize, SplatPart)> = Vec::with_capacity(irs.len());
        for (g, group) in effect.groups().iter().enumerate() {
            // Ribbons first, as the raster draw draws them under the group's sprites.
            let kinds: &[bool] = match irs[g].render.trail {
                Some(_) => &[true, false],
                None => &[false],
            };
            for &ribbons in kinds {
                let under = parts.first().map(|(_, p)| p.image().clone());
                let part = SplatPart::new(group, ribbons, &image, under.as_ref())?;
                parts.push((g, part));
            }
        }
        // The top-level group's glow, as `plume render` blooms a graph's image.
        let glow = match &irs[0].render.glow {
            Some(g) if host.is_none() => {
                let output = gpu.texture_2d(
                    "splat glow output",
                    (width, height),
                    wgpu::TextureFormat::Rgba8Unorm,
                    wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
                );
                let view = output.create_view(&Default::default());
                Some(SplatGlow {
                    passes: GlowPasses::new(&gpu, g, &view, width, height)?,
                    output,
                })
            }
            _ => None,
        };
        Ok(Self {
            gpu,
            width,
            height,
            parts,
            glow,
            host_depth,
            size_scale: 1.0,
        })
    }

    /// Records what the frame needs before the compute renderer's pass into `encoder`: each group's frame
    /// preparation (frame table, depth sort) and the camera.
    pub fn prepare(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        effect: &Effect,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        for (g, group) in effect.groups().iter().enumerate() {
            let frame = group.prepare_frame(encoder, camera)?;
            for (_, part) in self.parts.iter().filter(|(of, _)| *of == g) {
                part.write_view(encoder, camera, frame.steps, self.size_scale)?;
            }
        }
        Ok(())
    }

    /// Records the compute renderer itself into `pass`: each group's project, scan, entries, sort,
    /// ranges and composite, in group order.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>) -> Result<(), RuntimeError> {
        for (_, part) in &self.parts {
            part.record(pass)?;
        }
        Ok(())
    }

    /// Records one stage of the compute renderer into `pass`, for every group in order (the benchmark
    /// times them one by one).
    #[cfg(feature = "tools")]
    pub(crate) fn record_stage(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        stage: &str,
    ) -> Result<(), RuntimeError> {
        for (_, part) in &self.parts {
            part.record_stage(pass, stage)?;
        }
        Ok(())
    }

    /// Records the bloom of a glowing effect after the compute renderer's pass: its HDR image copied into
    /// the glow's texture, then the two blur passes (nothing for an effect that does not glow).
    pub(crate) fn record_glow(&self, encoder: &mut wgpu::CommandEncoder) {
        let Some(glow) = &self.glow else {
            return;
        };
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: self.parts[0].1.image(),
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(8 * splat_hdr_pitch(self.width)),
                    rows_per_image: Some(self.height),
                },
            },
            glow.passes.hdr_texture().as_image_copy(),
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        glow.passes.record(encoder);
    }

    /// The bloom's passes, for a glowing effect (the benchmark times them).
    #[cfg(feature = "tools")]
    pub(crate) fn glow_passes(&self) -> Option<&GlowPasses> {
        self.glow.as_ref().map(|g| &g.passes)
    }

    /// Whether every group's entry list held every entry the last frame needed (read after
    /// it ran); the lists that did not are grown, and the frame must be drawn again.
    pub(crate) fn fits_or_grow(&mut self) -> Result<bool, RuntimeError> {
        let mut fits = true;
        for (_, part) in &mut self.parts {
            fits &= part.fits_or_grow()?;
        }
        Ok(fits)
    }

    /// Draws `effect` from `camera` and returns the image as RGBA8 rows, top row first.
    pub fn render(&mut self, effect: &Effect, camera: &Camera) -> Result<Vec<u8>, RuntimeError> {
        loop {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            self.prepare(&mut encoder, effect, camera)?;
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("splat"),
                    timestamp_writes: None,
                });
                self.record(&mut pass)?;
            }
            self.record_glow(&mut encoder);
            self.gpu.queue.submit([encoder.finish()]);
            self.gpu.take_error()?;
            if self.fits_or_grow()? {
                return match &self.glow {
                    Some(glow) => crate::device::readback::read_texture(
                        &self.gpu,
                        &glow.output,
                        self.width,
                        self.height,
                    ),
                    None => {
                        crate::device::readback::read_buffer(&self.gpu, self.parts[0].1.image())
                    }
                };
            }
        }
    }

    /// Whether the last frame's sorted entries hold every sprite exactly as many times as
    /// `project` counted tiles for it, in every group (reads the buffers back; for tests).
    pub fn entries_are_complete(&self) -> Result<bool, RuntimeError> {
        for (_, part) in &self.parts {
            if !part.entries_are_complete()? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Lights every lit group's sprites with `lights` from the next frame on (each group
    /// starts with its effect file's lights).
    pub fn set_lights(&self, lights: &plume_compiler::lights::Lights) {
        for (_, part) in &self.parts {
            part.set_lights(lights);
        }
    }

    /// Reads `map` as every lit group's shadow map from the next frame on, as
    /// [`crate::EffectRenderer::set_shadow_map`] does (give the lights' shadow with
    /// [`Self::set_lights`]).
    pub fn set_shadow_map(&mut self, map: &wgpu::Texture) -> Result<(), RuntimeError> {
        let view = crate::draw::lights::shadow_map_view(map)?;
        let parts = self.parts.iter().map(|(_, p)| p.lit_and_shadowed());
        crate::draw::lights::check_reads_shadows(parts)?;
        self.bind_shadow_map(&view);
        Ok(())
    }

    /// (Whether a group is lit, whether one reads a shadow map.)
    pub(crate) fn lit_and_shadowed(&self) -> (bool, bool) {
        let parts = self.parts.iter().map(|(_, p)| p.lit_and_shadowed());
        parts.fold((false, false), |a, p| (a.0 || p.0, a.1 || p.1))
    }

    /// Reads `map` (an array view of a depth texture) as every lit group's shadow map from the
    /// next frame on.
    pub(crate) fn bind_shadow_map(&mut self, map: &wgpu::TextureView) {
        for (_, part) in &mut self.parts {
            part.set_shadow_map(map);
        }
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Entries the lists hold now, over every group.
    pub fn entries(&self) -> u64 {
        self.parts.iter().map(|(_, part)| part.entries()).sum()
    }
}
