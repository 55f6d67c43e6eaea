//! One group's solid mesh particles drawn by the compute renderer: the kernels of the group's
//! draw module (the compiler's `mesh_splat`) that clear a visibility buffer, place each
//! particle's mesh, rasterise every (particle, triangle) twice (the least depth a pixel, then
//! the first triangle at it) and shade each pixel once, into the image the group owns or
//! shares with the groups drawn before it. [`SplatPart`] is what [`super::ComputeOffscreen`]
//! strings together: a group's sprites (or ribbons) or its meshes.

use plume_compiler::lights::{Lights, LIGHTS_BINDING};
use plume_compiler::mesh_splat::{MESH_FRAME_WORDS, MESH_SPLAT_BINDINGS};
use plume_compiler::particle_mesh::MESH_VERTICES_BINDING;
use plume_compiler::wgsl::draw::{
    splat_hdr_pitch, DrawShape, DRAW_VIEW_BYTES, SPLAT_HOST_DEPTH_BINDING,
};

use super::binding::{bind, record_part_view, uniform};
use super::group::{GroupSplat, SplatImage};
use crate::device::buffers::{words_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::lights::{LightsUniform, ShadowBinding};
use crate::draw::pipeline::bind_resources;
use crate::draw::raster::{draw_module, draw_shape};
use crate::error::RuntimeError;
use crate::sim::group::Group;

/// A part of the compute renderer's image: one group's sprites (or its ribbons), or its meshes.
/// Each boxed: a part is large, and the parts live in one list.
pub(crate) enum SplatPart {
    /// A group's sprites, or its ribbons: projected, listed by tile and composited.
    Sprites(Box<GroupSplat>),
    /// A group's solid meshes: covered into a visibility buffer and shaded a pixel each.
    Meshes(Box<MeshSplat>),
}

/// The compute renderer of one group's solid meshes.
pub(crate) struct MeshSplat {
    gpu: Gpu,
    pixels: u64,
    /// Particle slots placed: the group's capacity.
    count: u32,
    triangles: u32,
    draw_view: wgpu::Buffer,
    lights: Option<LightsUniform>,
    image: wgpu::Buffer,
    /// The big triangles' list (a count, then ids): its first word is the status a host's
    /// readback reads (the triangles the last frame listed).
    big: wgpu::Buffer,
    /// Ids the list holds.
    big_len: u64,
    /// `mesh_clear`, `mesh_place`, `mesh_raster`, `mesh_raster_big`, `mesh_shade`.
    kernels: [wgpu::ComputePipeline; 5],
    /// What the kernels that read the big list bind besides it: `mesh_clear`, then
    /// `mesh_raster` (and `mesh_raster_big`) in each phase.
    clear_entries: Vec<(u32, wgpu::Buffer)>,
    raster_entries: [Vec<(u32, wgpu::Buffer)>; 2],
    /// Bind groups: `mesh_clear`'s, `mesh_place`'s, per phase `mesh_raster`'s and
    /// `mesh_raster_big`'s, and `mesh_shade`'s.
    clear_group: wgpu::BindGroup,
    place_group: wgpu::BindGroup,
    raster_groups: [[wgpu::BindGroup; 2]; 2],
    shade_group: wgpu::BindGroup,
    /// What `mesh_shade` binds besides a shadow map, to bind it again with another map.
    shade_entries: Vec<(u32, wgpu::Buffer)>,
    /// A lit look's shadow map and its samplers, for a look that reads one.
    shadow: Option<ShadowBinding>,
}

/// Workgroups of `mesh_raster_big`, each taking every so many of the listed triangles.
const BIG_WORKGROUPS: u32 = 512;

impl MeshSplat {
    /// The compute renderer of `group`'s meshes into `image`'s size: into `under`, the image of
    /// the parts drawn before it, or into an image of its own over the group's background.
    pub(crate) fn new(
        group: &Group,
        image: &SplatImage,
        under: Option<&wgpu::Buffer>,
    ) -> Result<Self, RuntimeError> {
        let gpu = group.gpu.clone();
        let (res, effect) = (&group.res, &group.effect);
        let mesh = effect.ir.render.mesh.as_ref().ok_or_else(|| {
            RuntimeError::Output("a mesh part of the compute renderer draws no mesh".into())
        })?;
        if let Some(why) = plume_compiler::wgsl::draw::splat_mesh_refusal(&effect.ir) {
            return Err(RuntimeError::Output(why.into()));
        }
        let (width, height) = (image.width, image.height);
        let pixels = u64::from(width) * u64::from(height);
        let count = effect.ir.capacity;
        let triangles = mesh.triangles.len() as u32;
        let jobs = u64::from(count) * u64::from(triangles);
        if jobs > u64::from(u32::MAX) {
            return Err(RuntimeError::Unsupported(format!(
                "{count} particles of {triangles} triangles are more than the compute renderer's mesh draw counts (2^32); draw this effect with the raster pipeline"
            )));
        }
        let shape = DrawShape {
            splat: true,
            hdr: image.hdr,
            host: image.host,
            ..draw_shape(effect, res)
        };
        let (module, mut particles) = draw_module(&gpu, effect, res, &shape, None)?;
        let device = &gpu.device;
        let draw_view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mesh splat draw view"),
            size: DRAW_VIEW_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let words = |label, n: u64| storage_words(&gpu, label, n);
        let buffers = mesh.buffers();
        let vertices = words_buffer(
            &gpu,
            "mesh vertices",
            buffers.vertex_words.iter().map(|w| w.to_bits()),
            STORAGE,
        )?;
        let indices = words_buffer(
            &gpu,
            "mesh indices",
            buffers.indices.iter().copied(),
            STORAGE,
        )?;
        let frames = words("mesh frames", MESH_FRAME_WORDS * u64::from(count));
        let depth = words("mesh depth", pixels);
        let pick = words("mesh pick", pixels);
        // An HDR image (a host's) holds two words a pixel in rows of the width rounded to 32.
        let image_buffer = match (under, image.hdr) {
            (Some(under), _) => under.clone(),
            (None, true) => words(
                "image",
                2 * u64::from(splat_hdr_pitch(width)) * u64::from(height),
            ),
            (None, false) => words("image", pixels),
        };
        let bg = effect.ir.render.background;
        // As a clear colour reaches an 8-bit target: each channel rounded to the nearest step.
        let byte = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u32;
        // Alpha 0: the parts before drew the image (or a host's image); pixels no mesh covers
        // keep it.
        let background = match (under, image.host) {
            (None, None) => byte(bg.x) | byte(bg.y) << 8 | byte(bg.z) << 16 | 255 << 24,
            _ => 0,
        };
        let params = |phase| {
            uniform(
                &gpu,
                "mesh splat",
                &[width, height, count, background, phase],
            )
        };
        let [b_params, b_indices, b_frames, b_depth, b_pick, b_image, _] = MESH_SPLAT_BINDINGS;
        let mut lights = LightsUniform::new(&gpu, effect);
        // The shade owns the shadow map's binding (the lights keep none of their own).
        let shadow = lights.as_mut().and_then(|l| l.shadow.take());
        let kernel = |entry| gpu.compute_pipeline(&module, entry, None);
        let kernels = [
            kernel("mesh_clear"),
            kernel("mesh_place"),
            kernel("mesh_raster"),
            kernel("mesh_raster_big"),
            kernel("mesh_shade"),
        ];
        gpu.take_error()?;
        let first = params(0)?;
        let clear_entries = vec![
            (b_params, first.clone()),
            (b_depth, depth.clone()),
            (b_pick, pick.clone()),
        ];
        particles.extend([
            (0, draw_view.clone()),
            (b_params, first.clone()),
            (b_frames, frames.clone()),
        ]);
        let place_group = bind(&gpu, &kernels[1].get_bind_group_layout(0), &particles);
        let corners = [
            (0, draw_view.clone()),
            (MESH_VERTICES_BINDING, vertices),
            (b_indices, indices),
            (b_frames, frames),
        ];
        let raster = |params: wgpu::Buffer| {
            let mut entries = corners.to_vec();
            entries.extend([
                (b_params, params),
                (b_depth, depth.clone()),
                (b_pick, pick.clone()),
            ]);
            // A host's depth, which each pixel is tested against.
            if let Some(host_depth) = &image.host_depth {
                entries.push((SPLAT_HOST_DEPTH_BINDING, host_depth.clone()));
            }
            entries
        };
        let raster_entries = [raster(first.clone()), raster(params(1)?)];
        // The unlit shade reads the particles' colours alone: no corners, view or lights.
        let mut shade = vec![
            (b_params, first),
            (b_frames, corners[3].1.clone()),
            (b_pick, pick),
            (b_image, image_buffer.clone()),
        ];
        if let Some(lights) = &lights {
            shade.extend(corners[..3].iter().cloned());
            shade.push((LIGHTS_BINDING, lights.buffer.clone()));
        }
        let shade_group = shade_group(&gpu, &kernels[4], &shade, shadow.as_ref());
        let big_len = FIRST_BIG_TRIANGLES;
        let big = words("mesh big triangles", 1 + big_len);
        let (clear_group, raster_groups) =
            big_groups(&gpu, &kernels, &big, &clear_entries, &raster_entries);
        gpu.take_error()?;
        Ok(Self {
            gpu,
            pixels,
            count,
            triangles,
            draw_view,
            lights,
            image: image_buffer,
            big,
            big_len,
            kernels,
            clear_entries,
            raster_entries,
            clear_group,
            place_group,
            raster_groups,
            shade_group,
            shade_entries: shade,
            shadow,
        })
    }

    /// Reads `map` (a depth texture's array view) as the shadow map from the next frame on;
    /// nothing for a look that reads none.
    fn set_shadow_map(&mut self, map: &wgpu::TextureView) {
        if let Some(shadow) = &mut self.shadow {
            shadow.map = map.clone();
            let (kernel, entries) = (&self.kernels[4], &self.shade_entries);
            self.shade_group = shade_group(&self.gpu, kernel, entries, Some(shadow));
        }
    }

    /// Whether the big triangles' list held every one the last frame listed (read after it
    /// ran); if not, it is grown, and the frame must be drawn again.
    fn fits_or_grow(&mut self) -> Result<bool, RuntimeError> {
        let needed = u64::from(crate::device::readback::read_words(&self.gpu, &self.big, 1)?[0]);
        let fits = needed <= self.big_len;
        self.grow(needed)?;
        Ok(fits)
    }

    /// Grows the big triangles' list to a quarter more than `needed` if it holds fewer.
    fn grow(&mut self, needed: u64) -> Result<(), RuntimeError> {
        if needed <= self.big_len {
            return Ok(());
        }
        let len = needed + needed / 4 + 4096;
        let limit = self.gpu.limits.max_storage_buffer_binding_size;
        if 4 * (1 + len) > limit {
            return Err(RuntimeError::Unsupported(format!(
                "{needed} big mesh triangles are more than the compute renderer lists within the adapter's {limit}-byte binding limit; draw this effect with the raster pipeline"
            )));
        }
        self.big = storage_words(&self.gpu, "mesh big triangles", 1 + len);
        self.big_len = len;
        let (e, r) = (&self.clear_entries, &self.raster_entries);
        let (clear, raster) = big_groups(&self.gpu, &self.kernels, &self.big, e, r);
        self.clear_group = clear;
        self.raster_groups = raster;
        Ok(())
    }

    /// Records the camera, the steps done and the size scale before the compute renderer's
    /// pass, as a sprite part does.
    fn write_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        steps: u64,
        size_scale: f32,
    ) -> Result<(), RuntimeError> {
        let view = (&self.draw_view, self.lights.as_ref());
        record_part_view(&self.gpu, encoder, view, camera, (steps, size_scale))
    }

    /// Records the mesh draw's kernels of `stage` (the compute renderer's stages: `project`
    /// clears and places, `raster` rasterises and shades; the others have none here).
    fn record_stage(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        stage: &str,
    ) -> Result<(), RuntimeError> {
        let [clear, place, raster, raster_big, shade] = &self.kernels;
        let (px, py) = self.gpu.grid(self.pixels, 256)?;
        match stage {
            "project" => {
                pass.set_pipeline(clear);
                pass.set_bind_group(0, &self.clear_group, &[]);
                pass.dispatch_workgroups(px, py, 1);
                let (x, y) = self.gpu.grid(u64::from(self.count), 256)?;
                pass.set_pipeline(place);
                pass.set_bind_group(0, &self.place_group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            }
            "raster" => {
                let jobs = u64::from(self.count) * u64::from(self.triangles);
                let (x, y) = self.gpu.grid(jobs, 256)?;
                for [small, big] in &self.raster_groups {
                    pass.set_pipeline(raster);
                    pass.set_bind_group(0, small, &[]);
                    pass.dispatch_workgroups(x, y, 1);
                    pass.set_pipeline(raster_big);
                    pass.set_bind_group(0, big, &[]);
                    pass.dispatch_workgroups(BIG_WORKGROUPS, 1, 1);
                }
                pass.set_pipeline(shade);
                pass.set_bind_group(0, &self.shade_group, &[]);
                pass.dispatch_workgroups(px, py, 1);
            }
            _ => {}
        }
        Ok(())
    }
}

/// `mesh_shade`'s bind group: `buffers`, and the shadow map with its samplers where the look
/// reads one.
fn shade_group(
    gpu: &Gpu,
    kernel: &wgpu::ComputePipeline,
    buffers: &[(u32, wgpu::Buffer)],
    shadow: Option<&ShadowBinding>,
) -> wgpu::BindGroup {
    let extra = shadow.map_or(Vec::new(), ShadowBinding::entries);
    let layout = kernel.get_bind_group_layout(0);
    bind_resources(gpu, &layout, buffers, None, &extra)
}

/// Ids the big triangles' list holds at first.
const FIRST_BIG_TRIANGLES: u64 = 1 << 10;

/// A storage buffer of `n` words (at least 4).
fn storage_words(gpu: &Gpu, label: &str, n: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: n.max(4) * 4,
        usage: STORAGE,
        mapped_at_creation: false,
    })
}

/// The bind groups of the kernels that read the big triangles' list `big`: `mesh_clear`'s
/// (of `clear`), and per phase `mesh_raster`'s and `mesh_raster_big`'s (of `raster`).
fn big_groups(
    gpu: &Gpu,
    kernels: &[wgpu::ComputePipeline; 5],
    big: &wgpu::Buffer,
    clear: &[(u32, wgpu::Buffer)],
    raster: &[Vec<(u32, wgpu::Buffer)>; 2],
) -> (wgpu::BindGroup, [[wgpu::BindGroup; 2]; 2]) {
    let b_big = MESH_SPLAT_BINDINGS[6];
    let with_big = |entries: &[(u32, wgpu::Buffer)]| {
        let mut all = entries.to_vec();
        all.push((b_big, big.clone()));
        all
    };
    let group = |k: usize, entries: &[(u32, wgpu::Buffer)]| {
        bind(
            gpu,
            &kernels[k].get_bind_group_layout(0),
            &with_big(entries),
        )
    };
    let phase = |p: usize| [group(2, &raster[p]), group(3, &raster[p])];
    (group(0, clear), [phase(0), phase(1)])
}

impl SplatPart {
    /// The part of `group` (its ribbons, `ribbons`, or else its sprites or meshes) into
    /// `image`, over `under` (the image of the parts before it) or an image of its own.
    pub(crate) fn new(
        group: &Group,
        ribbons: bool,
        image: &SplatImage,
        under: Option<&wgpu::Buffer>,
    ) -> Result<Self, RuntimeError> {
        match (&group.effect.ir.render.mesh, ribbons) {
            (Some(_), false) => Ok(Self::Meshes(Box::new(MeshSplat::new(group, image, under)?))),
            _ => Ok(Self::Sprites(Box::new(GroupSplat::new(
                group, ribbons, image, under,
            )?))),
        }
    }

    /// See [`GroupSplat::write_view`].
    pub(crate) fn write_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        steps: u64,
        size_scale: f32,
    ) -> Result<(), RuntimeError> {
        match self {
            Self::Sprites(s) => s.write_view(encoder, camera, steps, size_scale),
            Self::Meshes(m) => m.write_view(encoder, camera, steps, size_scale),
        }
    }

    /// Records every stage into `pass`.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) -> Result<(), RuntimeError> {
        for stage in super::group::STAGES {
            self.record_stage(pass, stage)?;
        }
        Ok(())
    }

    /// Records one stage into `pass` (the benchmark times them one by one).
    pub(crate) fn record_stage(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        stage: &str,
    ) -> Result<(), RuntimeError> {
        match self {
            Self::Sprites(s) => s.record_stage(pass, stage),
            Self::Meshes(m) => m.record_stage(pass, stage),
        }
    }

    /// See [`GroupSplat::fits_or_grow`]: the sprites' entries, or the meshes' big triangles.
    pub(crate) fn fits_or_grow(&mut self) -> Result<bool, RuntimeError> {
        match self {
            Self::Sprites(s) => s.fits_or_grow(),
            Self::Meshes(m) => m.fits_or_grow(),
        }
    }

    /// See [`GroupSplat::grow`]: the sprites' entries, or the meshes' big triangles.
    pub(crate) fn grow(&mut self, needed: u64) -> Result<(), RuntimeError> {
        match self {
            Self::Sprites(s) => s.grow(needed),
            Self::Meshes(m) => m.grow(needed),
        }
    }

    /// See [`GroupSplat::status`]: the entries, or the big triangles, the last frame needed.
    pub(crate) fn status(&self) -> &wgpu::Buffer {
        match self {
            Self::Sprites(s) => s.status(),
            Self::Meshes(m) => &m.big,
        }
    }

    /// See [`GroupSplat::entries_are_complete`]; meshes have no entries.
    pub(crate) fn entries_are_complete(&self) -> Result<bool, RuntimeError> {
        match self {
            Self::Sprites(s) => s.entries_are_complete(),
            Self::Meshes(_) => Ok(true),
        }
    }

    /// The image this part draws into.
    pub(crate) fn image(&self) -> &wgpu::Buffer {
        match self {
            Self::Sprites(s) => s.image(),
            Self::Meshes(m) => &m.image,
        }
    }

    /// Lights the part with `lights` from the next frame on.
    pub(crate) fn set_lights(&self, lights: &Lights) {
        let uniform = match self {
            Self::Sprites(s) => return s.set_lights(lights),
            Self::Meshes(m) => &m.lights,
        };
        if let Some(uniform) = uniform {
            uniform.set(lights);
        }
    }

    /// Reads `map` as the shadow map from the next frame on.
    pub(crate) fn set_shadow_map(&mut self, map: &wgpu::TextureView) {
        match self {
            Self::Sprites(s) => s.set_shadow_map(map),
            Self::Meshes(m) => m.set_shadow_map(map),
        }
    }

    /// (Whether the part is lit, whether it reads a shadow map.)
    pub(crate) fn lit_and_shadowed(&self) -> (bool, bool) {
        match self {
            Self::Sprites(s) => s.lit_and_shadowed(),
            Self::Meshes(m) => (m.lights.is_some(), m.shadow.is_some()),
        }
    }

    /// Entries the lists hold now (none for meshes).
    pub(crate) fn entries(&self) -> u64 {
        match self {
            Self::Sprites(s) => s.entries(),
            Self::Meshes(_) => 0,
        }
    }
}
