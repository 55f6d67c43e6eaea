//! What composites quads and ribbon segments (every sprite but a round camera-facing one): the
//! effect's generated `composite` kernel, a second one for tilted views where camera-facing
//! quads composite affinely, `merge`, the slices' partial sums and the sprite's texture.

use plume_compiler::wgsl::draw::{
    splat_affine_quads, splat_slices, DrawShape, SPLAT_FLAT_VIEW, SPLAT_PARTIAL_BINDING,
    SPLAT_RASTER_BINDINGS,
};

use super::binding::bind;
use crate::device::buffers::STORAGE;
use crate::device::gpu::Gpu;
use crate::draw::lights::ShadowBinding;
use crate::draw::pipeline::bind_resources;
use crate::draw::texture::SpriteTexture;

/// The generated composite of a group's quads or ribbon segments and what it reads.
pub(super) struct QuadRaster {
    pipeline: wgpu::ComputePipeline,
    /// For camera-facing quads (`splat_affine_quads`), `composite` for a projection whose w
    /// leans on view x or y (`SPLAT_FLAT_VIEW` false), which divides at each pixel.
    tilted: Option<wgpu::ComputePipeline>,
    /// `merge`, which composes the slices' partial sums into the image, and its bind group.
    merge: (wgpu::ComputePipeline, wgpu::BindGroup),
    /// Workgroups each tile's list is split over (`splat_slices`).
    slices: u32,
    /// The slices' partial sums (a vec4 a pixel and slice).
    partials: wgpu::Buffer,
    texture: Option<SpriteTexture>,
    /// What `composite` reads besides the tile buffers: the records (quads), or what
    /// `segment_record` reads to make them again (ribbons: the particles, the rings, the view).
    reads: Vec<(u32, wgpu::Buffer)>,
    /// A lit look's shadow map and its samplers.
    shadow: Option<ShadowBinding>,
}

/// The composite's bind groups for one entry list: one for each of its pipelines (their
/// derived layouts differ).
pub(super) struct QuadGroups {
    flat: wgpu::BindGroup,
    tilted: Option<wgpu::BindGroup>,
}

/// The tile buffers `merge` binds: the tiles' parameters and the image.
pub(super) struct MergeTargets<'a> {
    pub params: &'a wgpu::Buffer,
    pub image: &'a wgpu::Buffer,
}

impl QuadRaster {
    /// The composite of `module` (the group's draw module in the compute renderer's `shape`, or its trail
    /// module for `ribbons`) into a `width` x `height` image.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        gpu: &Gpu,
        module: &wgpu::ShaderModule,
        effect: &plume_compiler::CompiledEffect,
        shape: &DrawShape,
        ribbons: bool,
        (width, height): (u32, u32),
        targets: MergeTargets<'_>,
        texture: Option<SpriteTexture>,
        (reads, shadow): (Vec<(u32, wgpu::Buffer)>, Option<ShadowBinding>),
    ) -> Self {
        let pixels = u64::from(width) * u64::from(height);
        let slices = splat_slices(&effect.ir);
        let partials = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("splat partials"),
            size: (16 * u64::from(slices) * pixels).max(4),
            usage: STORAGE,
            mapped_at_creation: false,
        });
        let merge = gpu.compute_pipeline(module, "merge", None);
        let [params, _, _, image] = SPLAT_RASTER_BINDINGS;
        let merge_group = bind(
            gpu,
            &merge.get_bind_group_layout(0),
            &[
                (params, targets.params.clone()),
                (SPLAT_PARTIAL_BINDING, partials.clone()),
                (image, targets.image.clone()),
            ],
        );
        // Camera-facing quads composite affinely where the projection is flat; a second
        // pipeline divides at each pixel for one whose w leans on view x or y.
        let tilted = (!ribbons && splat_affine_quads(&effect.ir, shape)).then(|| {
            gpu.compute_pipeline_with(module, "composite", None, &[(SPLAT_FLAT_VIEW, 0.0)])
        });
        Self {
            pipeline: gpu.compute_pipeline(module, "composite", None),
            tilted,
            merge: (merge, merge_group),
            slices,
            partials,
            texture,
            reads,
            shadow,
        }
    }

    /// Whether the composite reads a shadow map.
    pub(super) fn reads_shadows(&self) -> bool {
        self.shadow.is_some()
    }

    /// Reads `map` as the shadow map from the next [`Self::bind_groups`] on; whether the
    /// composite reads one.
    pub(super) fn set_shadow_map(&mut self, map: &wgpu::TextureView) -> bool {
        if let Some(shadow) = &mut self.shadow {
            shadow.map = map.clone();
        }
        self.shadow.is_some()
    }

    /// The composite's bind groups over the tiles' parameters, the list of sprites by tile
    /// and the tiles' ranges in it.
    pub(super) fn bind_groups(
        &self,
        gpu: &Gpu,
        params: &wgpu::Buffer,
        sprites: &wgpu::Buffer,
        ranges: &wgpu::Buffer,
    ) -> QuadGroups {
        let group = |pipeline: &wgpu::ComputePipeline| {
            let [b_params, b_sprites, b_ranges, _] = SPLAT_RASTER_BINDINGS;
            let mut buffers = vec![
                (b_params, params.clone()),
                (b_sprites, sprites.clone()),
                (b_ranges, ranges.clone()),
                (SPLAT_PARTIAL_BINDING, self.partials.clone()),
            ];
            buffers.extend(self.reads.iter().cloned());
            let layout = pipeline.get_bind_group_layout(0);
            let extra = self
                .shadow
                .as_ref()
                .map_or(Vec::new(), ShadowBinding::entries);
            bind_resources(gpu, &layout, &buffers, self.texture.as_ref(), &extra)
        };
        QuadGroups {
            flat: group(&self.pipeline),
            tilted: self.tilted.as_ref().map(group),
        }
    }

    /// Records the composite over `tiles` (x, y) and its merge into `pass`, with the pipeline
    /// for a `flat` projection (w independent of view x and y) or a tilted one.
    pub(super) fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        groups: &QuadGroups,
        flat: bool,
        (tiles_x, tiles_y): (u32, u32),
    ) {
        match (&self.tilted, &groups.tilted) {
            (Some(tilted), Some(group)) if !flat => {
                pass.set_bind_group(0, group, &[]);
                pass.set_pipeline(tilted);
            }
            _ => {
                pass.set_bind_group(0, &groups.flat, &[]);
                pass.set_pipeline(&self.pipeline);
            }
        }
        pass.dispatch_workgroups(tiles_x, tiles_y, self.slices);
        pass.set_pipeline(&self.merge.0);
        pass.set_bind_group(0, &self.merge.1, &[]);
        pass.dispatch_workgroups(tiles_x, tiles_y, 1);
    }
}
