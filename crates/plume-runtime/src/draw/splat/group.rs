//! One group's compute renderer: its `project` kernel (from the group's draw module), the scan,
//! the (tile, sprite) entries and their sort, and the composite (the fixed disc kernel of
//! `splat.wgsl` or the group's generated `composite`), into an image it owns or shares with
//! the groups drawn before it ([`super::ComputeOffscreen`] strings them together).

use plume_compiler::wgsl::draw::{
    splat_additive_lists, splat_discs, splat_hdr_pitch, splat_light_ceiling, splat_quad_words,
    splat_slices, DrawShape, SplatHost, DRAW_VIEW_BYTES, SPLAT_BINDINGS, SPLAT_HOST_DEPTH_BINDING,
    SPLAT_SLICES, SPLAT_TILE,
};
use plume_compiler::wgsl::trail;
use std::sync::atomic::{AtomicBool, Ordering};

use super::additive_lists::AdditiveLists;
use super::binding::{bind, record_part_view, ribbon_module, tile_kernels, tile_layout, uniform};
use super::quad_raster::{MergeTargets, QuadGroups, QuadRaster};
use crate::device::buffers::STORAGE;
use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::lights::LightsUniform;
use crate::draw::raster::{draw_module, draw_shape};
use crate::draw::texture::SpriteTexture;
use crate::error::RuntimeError;
use crate::sim::group::Group;
use crate::sort::radix::{GpuSorter, SortProgram};
use plume_compiler::lights::{Lights, LIGHTS_BINDING};

/// The tile kernels (`splat.wgsl`), their shared layout, and the buffers whose size does not
/// depend on the number of entries.
struct Tiles {
    layout: wgpu::BindGroupLayout,
    /// clear, emit, find_ranges, raster, merge_discs.
    kernels: [wgpu::ComputePipeline; 5],
    params: wgpu::Buffer,
    splats: wgpu::Buffer,
    offsets: wgpu::Buffer,
    counts: wgpu::Buffer,
    ranges: wgpu::Buffer,
    image: wgpu::Buffer,
    status: wgpu::Buffer,
    boxes: wgpu::Buffer,
    /// Per tile, the additive lists' counts and then cursors (`additive_lists.wgsl`).
    cursors: wgpu::Buffer,
    /// Additive discs' light from the slices of each tile's list, four words a pixel (a word
    /// stands in for other groups).
    disc_light: wgpu::Buffer,
}

/// The entry list of one length: its keys and values, their sort (none for additive lists),
/// and the tile kernels' bind group.
struct Entries {
    len: u64,
    /// The sprites of the entries, by tile (kept for [`GroupSplat::entries_are_complete`]).
    vals: wgpu::Buffer,
    sort: Option<SortProgram>,
    group: wgpu::BindGroup,
    /// `composite`'s bind groups (quads and ribbons only).
    quads_groups: Option<QuadGroups>,
}

/// The image a splat draws: its size, whether it is HDR (f16 pairs), and for a host's image
/// how it meets the host ([`SplatHost`]) and the buffer the host's depth is copied into.
#[derive(Clone)]
pub(crate) struct SplatImage {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) hdr: bool,
    pub(crate) host: Option<SplatHost>,
    /// One f32 a pixel (a host whose draw tests depth).
    pub(crate) host_depth: Option<wgpu::Buffer>,
    /// Light at which an HDR pixel is finished, in the composite's fixed-point units
    /// (`splat_light_ceiling`: the glow's clamp).
    pub(crate) light_ceiling: u32,
}

/// The compute renderer of one group into `width` x `height` images.
pub(crate) struct GroupSplat {
    gpu: Gpu,
    width: u32,
    height: u32,
    tiles_x: u32,
    tiles_y: u32,
    /// Sprites projected: one per slot of the capacity (hidden ones touch no tile).
    count: u32,
    draw_view: wgpu::Buffer,
    /// The lights of a lit look's quads (`render.lit`).
    lights: Option<LightsUniform>,
    project: wgpu::ComputePipeline,
    project_group: wgpu::BindGroup,
    /// The scan of the counts into the entries' offsets (sorted lists only).
    scan: Option<SortProgram>,
    tiles: Tiles,
    entries: Entries,
    /// Set for quads that composite; discs use the fixed `raster` kernel.
    quads: Option<QuadRaster>,
    /// Whether the last camera's projection has w independent of view x and y (set by
    /// `write_view`; picks `QuadRaster::tilted` when not).
    flat_view: AtomicBool,
    additive: bool,
    /// Additive light's lists, placed without a sort, where the composites sum light in fixed
    /// point; `None`: sorted lists (alpha).
    additive_lists: Option<AdditiveLists>,
    background: u32,
    /// [`SplatImage::light_ceiling`].
    light_ceiling: u32,
    /// Workgroups each tile's list of discs is split over: [`SPLAT_SLICES`] for additive
    /// discs, whose light `merge_discs` then sums; 1 for alpha discs (and quads, which do not
    /// use it).
    disc_slices: u32,
}

/// The compute renderer's stages, in order.
pub(crate) const STAGES: [&str; 6] = ["project", "scan", "emit", "sort", "ranges", "raster"];

impl GroupSplat {
    /// A splat of `group`'s sprites, or of its ribbons (`ribbons`: the strips' segments,
    /// from its trail draw module), into `width` x `height` images: into `under`, the image
    /// of the parts drawn before it (over what they drew), or into an image of its own over
    /// the group's background.
    pub(crate) fn new(
        group: &Group,
        ribbons: bool,
        image: &SplatImage,
        under: Option<&wgpu::Buffer>,
    ) -> Result<Self, RuntimeError> {
        let (width, height, hdr) = (image.width, image.height, image.hdr);
        let gpu = group.gpu.clone();
        let (res, effect) = (&group.res, &group.effect);
        let device = &gpu.device;
        let shape = DrawShape {
            splat: true,
            hdr,
            host: image.host,
            // Light stops at the glow's clamp where it is below the HDR image's own limit.
            clamped: hdr && image.light_ceiling < splat_light_ceiling(None),
            // The composite's line masks by subgroup transposes (subgroups of 32 only).
            subgroups: gpu.has_subgroups_of(32),
            ..draw_shape(effect, res)
        };
        let (module, mut entries, count) = match (&effect.ir.render.trail, ribbons) {
            (Some(trail), true) => {
                let segments = u64::from(effect.ir.capacity) * u64::from(trail::segments(trail));
                let count = u32::try_from(segments).map_err(|_| {
                    RuntimeError::Output(format!(
                        "{segments} ribbon segments are more than the compute renderer counts (2^32); draw this effect with the raster pipeline"
                    ))
                })?;
                let (module, entries) = ribbon_module(&gpu, effect, res, shape)?;
                (module, entries, count)
            }
            _ => {
                let (module, entries) = draw_module(&gpu, effect, res, &shape, None)?;
                (module, entries, effect.ir.capacity)
            }
        };
        let discs = !ribbons && splat_discs(&effect.ir, hdr);
        // Additive light summed in fixed point by the composites, in any order: its
        // lists are placed without a sort, from the counts alone (no offsets, no scan).
        let unsorted = splat_additive_lists(&effect.ir);
        let record_words = match (discs, ribbons) {
            (true, _) => 4,
            // Ribbon segments are made again where they are used, not stored.
            (false, true) => 0,
            (false, false) => splat_quad_words(&effect.ir, image.host.is_some()),
        };
        let (tiles_x, tiles_y) = (width.div_ceil(SPLAT_TILE), height.div_ceil(SPLAT_TILE));
        // Additive discs: each tile's list split over slices (`splat.wgsl`'s raster), whose
        // light `merge_discs` sums from four words a pixel.
        let sliced_discs = discs && unsorted;
        let disc_slices = if sliced_discs { SPLAT_SLICES } else { 1 };
        let disc_light_bytes = 16 * u64::from(width) * u64::from(height);
        // Every buffer is bound whole: none may pass the adapter's binding size.
        let limit = gpu.limits.max_storage_buffer_binding_size;
        // Quads and ribbons composite into a vec4 of partial sums a pixel and slice.
        let partial_bytes = match discs {
            false => {
                16 * u64::from(splat_slices(&effect.ir)) * u64::from(width) * u64::from(height)
            }
            true => 0,
        };
        let largest = (record_words.max(2) * u64::from(count) * 4)
            .max(8 * u64::from(width) * u64::from(height))
            .max(partial_bytes)
            .max(if sliced_discs { disc_light_bytes } else { 0 });
        if largest > limit {
            return Err(RuntimeError::Unsupported(format!(
                "{}: the compute renderer of {count} records into {width}x{height} needs a {largest}-byte buffer, past the adapter's {limit}-byte binding limit; draw this effect with the raster pipeline",
                gpu.info.name
            )));
        }
        let words = |label, n: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: n.max(1) * 4,
                usage: STORAGE,
                mapped_at_creation: false,
            })
        };
        let draw_view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("splat draw view"),
            size: DRAW_VIEW_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = tile_layout(&gpu);
        let tiles = Tiles {
            kernels: tile_kernels(&gpu, &layout)?,
            layout,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat params"),
                // Nine words (tiles_shared.wgsl's `Params`), in whole 16-byte rows.
                size: 48,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            splats: words("splats", record_words * u64::from(count)),
            offsets: match unsorted {
                // A word stands in for the tile kernels' binding.
                true => words("tile offsets (unused)", 1),
                false => words("tile offsets", u64::from(count)),
            },
            counts: words("tile counts", u64::from(count)),
            ranges: words("tile ranges", 2 * u64::from(tiles_x) * u64::from(tiles_y)),
            // An HDR image (the effect glows) holds two words a pixel in rows a copy can take.
            image: match (under, hdr) {
                (Some(image), _) => image.clone(),
                (None, true) => words(
                    "image",
                    2 * u64::from(splat_hdr_pitch(width)) * u64::from(height),
                ),
                (None, false) => words("image", u64::from(width) * u64::from(height)),
            },
            status: words("splat status", 4),
            boxes: words("tile boxes", 2 * u64::from(count)),
            cursors: words("tile cursors", u64::from(tiles_x) * u64::from(tiles_y)),
            disc_light: match sliced_discs {
                true => words("splat disc light", disc_light_bytes / 4),
                false => words("splat disc light (unused)", 1),
            },
        };
        let [b_view, b_splats, b_counts, b_offsets, b_boxes] = SPLAT_BINDINGS;
        let splat_view = uniform(&gpu, "splat view", &[width, height, tiles_x, count])?;
        entries.extend([(0, draw_view.clone()), (b_view, splat_view.clone())]);
        let mut reads = match ribbons {
            true => entries.clone(),
            false => vec![(b_splats, tiles.splats.clone())],
        };
        // The host's depth, which the composite tests each pixel against; a soft
        // effect's fade reads the projection too (ribbons read the view already).
        if let Some(depth) = &image.host_depth {
            reads.push((SPLAT_HOST_DEPTH_BINDING, depth.clone()));
            let soft = image.host.is_some_and(|h| h.soft) && effect.ir.render.soft.is_some();
            if soft && !ribbons {
                reads.push((0, draw_view.clone()));
            }
        }
        // A lit look's composite shades each pixel (each ribbon point) by the lights (in the
        // view: no matrix).
        let mut lights = LightsUniform::new(&gpu, effect);
        if let Some(lights) = &lights {
            reads.push((LIGHTS_BINDING, lights.buffer.clone()));
        }
        if !ribbons {
            entries.push((b_splats, tiles.splats.clone()));
        }
        entries.extend([
            (b_counts, tiles.counts.clone()),
            (b_boxes, tiles.boxes.clone()),
        ]);
        if !unsorted {
            entries.push((b_offsets, tiles.offsets.clone()));
        }
        let project = gpu.compute_pipeline(&module, "project", None);
        let texture = match ribbons || discs {
            true => None,
            false => SpriteTexture::for_render(&gpu, &effect.ir.render)?,
        };
        // The composite owns the shadow map's binding (the lights keep none of their own).
        let shadow = lights.as_mut().and_then(|l| l.shadow.take());
        let quads = (!discs).then(|| {
            let targets = MergeTargets {
                params: &tiles.params,
                image: &tiles.image,
            };
            let size = (width, height);
            let reads = (reads, shadow);
            QuadRaster::new(
                &gpu, &module, effect, &shape, ribbons, size, targets, texture, reads,
            )
        });
        // `project` binds all its module's bindings but `composite`'s: its layout holds these.
        let project_group = bind(&gpu, &project.get_bind_group_layout(0), &entries);
        let bg = effect.ir.render.background;
        // As a clear colour reaches an 8-bit target: each channel rounded to the nearest step.
        let byte = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u32;
        // Alpha 0: the composite starts from the image (the groups drawn before; a host's, always).
        let background = match under {
            _ if image.host.is_some() => 0,
            Some(_) => 0,
            None => byte(bg.x) | byte(bg.y) << 8 | byte(bg.z) << 16 | 255 << 24,
        };
        let additive = effect.ir.render.blend == plume_compiler::schema::Blend::Additive;
        let additive_lists = match unsorted {
            true => Some(AdditiveLists::new(&gpu, &tiles.layout)?),
            false => None,
        };
        // A first guess at the entries: a quarter more than the sprites (most touch one tile).
        let first = u64::from(count) + u64::from(count) / 4 + 4096;
        let scan = match unsorted {
            true => None,
            false => Some(GpuSorter::new(&gpu).scan_program(&tiles.offsets, u64::from(count))?),
        };
        let mut splat = Self {
            entries: Entries {
                len: 0,
                vals: tiles.counts.clone(),
                sort: None,
                group: project_group.clone(),
                quads_groups: None,
            },
            gpu,
            width,
            height,
            tiles_x,
            tiles_y,
            count,
            draw_view,
            lights,
            project,
            project_group,
            scan,
            tiles,
            quads,
            flat_view: AtomicBool::new(true),
            additive,
            additive_lists,
            background,
            light_ceiling: image.light_ceiling,
            disc_slices,
        };
        splat.resize(first)?;
        Ok(splat)
    }

    /// (Re)builds the entry list for `len` entries: its buffers, its sort (only the bits a
    /// tile index needs) and the tile kernels' bind group.
    fn resize(&mut self, len: u64) -> Result<(), RuntimeError> {
        let limit = self.gpu.limits.max_storage_buffer_binding_size;
        if len * 4 > limit {
            return Err(RuntimeError::Unsupported(format!(
                "the compute renderer's tile lists need {len} entries, {} bytes a list, past the adapter's {limit}-byte binding limit; draw this effect with the raster pipeline",
                len * 4
            )));
        }
        let device = &self.gpu.device;
        let make = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: len * 4,
                usage: STORAGE,
                mapped_at_creation: false,
            })
        };
        let vals = make("splat vals");
        // Additive lists have no keys: a word stands in for the binding.
        let keys = match self.additive_lists {
            Some(_) => device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat keys (unused)"),
                size: 4,
                usage: STORAGE,
                mapped_at_creation: false,
            }),
            None => make("splat keys"),
        };
        let tiles = self.tiles_x * self.tiles_y;
        // Unused entries keep the largest key, whose low bits (all ones) sort after every tile.
        let key_bits = 32 - tiles.leading_zeros();
        let words = [
            self.width,
            self.height,
            self.tiles_x,
            tiles,
            self.count,
            len.min(u64::from(u32::MAX)) as u32,
            u32::from(self.additive),
            self.background,
            self.light_ceiling,
        ];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        self.gpu.queue.write_buffer(&self.tiles.params, 0, &bytes);
        let t = &self.tiles;
        let all = [
            (0, t.params.clone()),
            (1, t.splats.clone()),
            (2, t.offsets.clone()),
            (3, t.counts.clone()),
            (4, keys.clone()),
            (5, vals.clone()),
            (6, t.ranges.clone()),
            (7, t.image.clone()),
            (8, t.status.clone()),
            (9, t.boxes.clone()),
            (10, t.cursors.clone()),
            (11, t.disc_light.clone()),
        ];
        let quads_groups =
            (self.quads.as_ref()).map(|q| q.bind_groups(&self.gpu, &t.params, &vals, &t.ranges));
        self.entries = Entries {
            len,
            vals: vals.clone(),
            sort: match self.additive_lists {
                Some(_) => None,
                None => Some(GpuSorter::new(&self.gpu).radix_program(&keys, &vals, len, key_bits)?),
            },
            group: bind(&self.gpu, &t.layout, &all),
            quads_groups,
        };
        Ok(())
    }

    /// Records the camera, the steps done (`steps`, from the group's frame preparation) and
    /// the sprites' size scale into `encoder`, before the compute renderer's pass.
    pub(crate) fn write_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        steps: u64,
        size_scale: f32,
    ) -> Result<(), RuntimeError> {
        let flat = camera.proj.x_axis.w == 0.0 && camera.proj.y_axis.w == 0.0;
        self.flat_view.store(flat, Ordering::Relaxed);
        let view = (&self.draw_view, self.lights.as_ref());
        record_part_view(&self.gpu, encoder, view, camera, (steps, size_scale))
    }

    /// Lights a lit look's quads with `lights` from the next frame on.
    pub(crate) fn set_lights(&self, lights: &Lights) {
        if let Some(uniform) = &self.lights {
            uniform.set(lights);
        }
    }

    /// Reads `map` (a depth texture's array view) as the shadow map from the next frame on.
    pub(crate) fn set_shadow_map(&mut self, map: &wgpu::TextureView) {
        let Some(quads) = &mut self.quads else {
            return;
        };
        // Made again if made already (else with the first entry lists).
        if quads.set_shadow_map(map) && self.entries.quads_groups.is_some() {
            let t = &self.tiles;
            self.entries.quads_groups =
                Some(quads.bind_groups(&self.gpu, &t.params, &self.entries.vals, &t.ranges));
        }
    }

    /// (Whether the group is lit, whether it reads a shadow map.)
    pub(crate) fn lit_and_shadowed(&self) -> (bool, bool) {
        let shadowed = self.quads.as_ref().is_some_and(QuadRaster::reads_shadows);
        (self.lights.is_some(), shadowed)
    }

    /// Records one stage of the compute renderer into `pass` (the benchmark times them one by one).
    pub(crate) fn record_stage(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        stage: &str,
    ) -> Result<(), RuntimeError> {
        let [clear, emit, ranges, raster, merge_discs] = &self.tiles.kernels;
        let e = &self.entries;
        let (x, y) = self.gpu.grid(u64::from(self.count), 256)?;
        let tiles = u64::from(self.tiles_x) * u64::from(self.tiles_y);
        if let Some(lists) = &self.additive_lists {
            if lists.record_stage(&self.gpu, pass, &e.group, stage, self.count, tiles)? {
                return Ok(());
            }
        }
        match stage {
            "project" => {
                pass.set_pipeline(&self.project);
                pass.set_bind_group(0, &self.project_group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            }
            "scan" => {
                if let Some(scan) = &self.scan {
                    scan.record(pass);
                }
            }
            "emit" => {
                let (cx, cy) = self.gpu.grid(e.len.max(tiles), 256)?;
                pass.set_bind_group(0, &e.group, &[]);
                pass.set_pipeline(clear);
                pass.dispatch_workgroups(cx, cy, 1);
                pass.set_pipeline(emit);
                pass.dispatch_workgroups(x, y, 1);
            }
            "sort" => {
                if let Some(sort) = &e.sort {
                    sort.record(pass);
                }
            }
            "ranges" => {
                let (rx, ry) = self.gpu.grid(e.len, 256)?;
                pass.set_bind_group(0, &e.group, &[]);
                pass.set_pipeline(ranges);
                pass.dispatch_workgroups(rx, ry, 1);
            }
            "raster" => match (&self.quads, &e.quads_groups) {
                (Some(q), Some(groups)) => {
                    let flat = self.flat_view.load(Ordering::Relaxed);
                    q.record(pass, groups, flat, (self.tiles_x, self.tiles_y));
                }
                _ => {
                    pass.set_bind_group(0, &e.group, &[]);
                    pass.set_pipeline(raster);
                    pass.dispatch_workgroups(self.tiles_x, self.tiles_y, self.disc_slices);
                    // Additive discs: the slices' light over the image.
                    if self.additive {
                        pass.set_pipeline(merge_discs);
                        pass.dispatch_workgroups(self.tiles_x, self.tiles_y, 1);
                    }
                }
            },
            _ => {
                return Err(RuntimeError::Output(format!(
                    "the compute renderer has no stage {stage}"
                )))
            }
        }
        Ok(())
    }

    /// Whether the entry list held every entry the last frame needed (read after it ran); if
    /// not, it is grown to a quarter more than needed, and the frame must be drawn again.
    pub(crate) fn fits_or_grow(&mut self) -> Result<bool, RuntimeError> {
        let needed =
            u64::from(crate::device::readback::read_words(&self.gpu, &self.tiles.status, 1)?[0]);
        if needed <= self.entries.len {
            return Ok(true);
        }
        self.grow(needed)?;
        Ok(false)
    }

    /// Grows the entry list to a quarter more than `needed` if it holds fewer.
    pub(crate) fn grow(&mut self, needed: u64) -> Result<(), RuntimeError> {
        if needed > self.entries.len {
            self.resize(needed + needed / 4 + 4096)?;
        }
        Ok(())
    }

    /// The word the last frame left the entries it needed in (for a readback that does not
    /// wait: the embedding API's compute draw).
    pub(crate) fn status(&self) -> &wgpu::Buffer {
        &self.tiles.status
    }

    /// Whether the last frame's sorted entries hold every sprite exactly as many times as
    /// `project` counted tiles for it (reads the buffers back; for tests).
    pub(crate) fn entries_are_complete(&self) -> Result<bool, RuntimeError> {
        let t = &self.tiles;
        let lists = [&t.status, &t.counts, &self.entries.vals];
        super::binding::entries_are_complete(&self.gpu, lists)
    }

    /// The image this group composites into.
    pub(crate) fn image(&self) -> &wgpu::Buffer {
        &self.tiles.image
    }

    /// Entries the list holds now.
    pub(crate) fn entries(&self) -> u64 {
        self.entries.len
    }
}
