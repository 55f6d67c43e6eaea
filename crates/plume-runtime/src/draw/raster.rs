//! Drawing particles straight from the GPU buffers: the render pipeline of an effect's
//! generated draw module (`plume_compiler::wgsl::draw`) for one render target, its per-frame
//! `DrawView` uniform (written by `camera::record_draw_view`), and how many instances a draw
//! issues.
//!
//! - A stateful effect draws its live slots: by default through a compacted list of them
//!   (order kept) from 4096 slots, below that one instance per slot with free slots as
//!   degenerate quads ([`DeadSlots`]). With `sort: true` it draws through the sorted slots, and only as many
//!   instances as are alive: a one-thread kernel writes the indirect draw's instance count
//!   (capacity − free count) on the GPU, so nothing is read back.
//! - A stateless effect draws the slots of its segment table (a count the CPU knows); each
//!   vertex computes its particle from the closed form, so no compute pass runs (a sorted one
//!   still computes keys and sorts them).
//!
//! The draw tests depth against the host's depth buffer when the target has one, and writes
//! it only for opaque and cut-out mesh particles into a target that asks
//! (`DrawTarget::with_depth_writes`): sprites are translucent.

use plume_compiler::passes::layout::Role;
use std::sync::atomic::{AtomicU32, Ordering};

use plume_compiler::lights::{Lights, LIGHTS_BINDING};
use plume_compiler::wgsl::batch::INSTANCE_MODELS_BINDING;
use plume_compiler::wgsl::draw::{
    DrawShape, Primitive, DRAW_VIEW_BYTES, FIRST_DATA_BINDING, SCENE_DEPTH_BINDING,
};
use plume_compiler::CompiledEffect;

use crate::device::buffers::{words_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::device::resources::Resources;
use crate::draw::camera::{record_draw_view, Camera};
use crate::draw::instances::{alive_instances, Instances};
use crate::draw::lights::{LightsUniform, ShadowBinding};
use crate::draw::live_list::LiveList;
use crate::draw::pipeline::{blend_state, draw_group, plain, render_pipeline};
use crate::draw::texture::SpriteTexture;
use crate::draw::trail::TrailDraw;
use crate::error::RuntimeError;

use crate::draw::target::DrawTarget;

/// How a stateful, unsorted draw skips the free slots (a sorted draw and a stateless draw
/// already issue only the live instances). The default compacts the list of an effect of
/// `COMPACT_FROM_SLOTS` slots or more, where the list costs less at any occupancy: a hidden
/// quad still costs its four vertices, while listing the slots is one short compute pass
/// (docs/performance.md, "Free slots: hidden quads or a compacted list"). A small effect
/// draws every slot instead: its hidden quads cost little, and the list would cost a
/// compute pass of three dispatches a frame, which a game with hundreds of small effects pays
/// on the CPU for each.
// The benchmarks (feature `tools`) try each; the draw takes the default.
#[cfg_attr(not(feature = "tools"), allow(dead_code))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeadSlots {
    /// One instance per slot; the vertex shader turns a free slot into a degenerate quad.
    Hidden,
    /// A compacted list of the live slots first (three compute passes),
    /// then an indirect draw of exactly those.
    Compacted,
    /// Compacted from `COMPACT_FROM_SLOTS` slots, hidden below.
    #[default]
    BySize,
}

/// The capacity from which [`DeadSlots::BySize`] compacts the list of live slots: about where
/// 4 hidden vertices a slot cost what the list's three small dispatches do (docs/performance.md,
/// "Free slots: hidden quads or a compacted list").
pub(crate) const COMPACT_FROM_SLOTS: u32 = 4096;

/// Choices of a draw beyond its target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrawOptions {
    /// Another blend state than the effect's (the benchmark measures blending's cost with
    /// `REPLACE`).
    pub blend: Option<wgpu::BlendState>,
    /// How free slots are skipped.
    pub dead_slots: DeadSlots,
    /// The sprite's geometry: a quad (the default) or one triangle around the disc.
    pub primitive: Primitive,
}

/// One group's draw into one kind of target (its ribbons, then its sprites): a part of the
/// public [`crate::EffectRenderer`], prepared each frame by [`crate::Effect::prepare_draw`].
pub(crate) struct GroupDraw {
    pipeline: wgpu::RenderPipeline,
    view: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// What bind group 0 holds besides the scene depth and the shadow map, to rebuild it
    /// with other ones.
    buffers: Vec<(u32, wgpu::Buffer)>,
    texture: Option<SpriteTexture>,
    /// The scene depth a soft draw reads (the host's, or a stand-in at the far plane).
    scene_depth: Option<wgpu::TextureView>,
    /// Whether the draw module fades sprites near the scene depth (`render.soft`).
    soft: bool,
    /// Whether it writes depth (opaque or cut-out meshes into a target that lets them).
    writes_depth: bool,
    /// The ribbons (`render.trail`), drawn before the sprites.
    trail: Option<TrailDraw>,
    /// The lights of a lit look (`render.lit`).
    lights: Option<LightsUniform>,
    instances: Instances,
    /// Vertices per sprite (4: a quad strip; 3: a triangle; a mesh's), or indices where
    /// `indices` is set.
    vertices: u32,
    /// The index buffer of an indexed draw (a mesh's).
    indices: Option<wgpu::Buffer>,
    size_scale: f32,
    gpu: Gpu,
}

impl GroupDraw {
    /// The draw of `effect`, whose buffers `res` holds, into `target`.
    pub(crate) fn new(
        gpu: &Gpu,
        effect: &CompiledEffect,
        res: &Resources,
        target: &DrawTarget,
        options: &DrawOptions,
    ) -> Result<Self, RuntimeError> {
        if let Some(flags) = gpu.downlevel {
            if !flags.contains(wgpu::DownlevelFlags::VERTEX_STORAGE) {
                return Err(RuntimeError::Unsupported(format!(
                    "{} cannot read storage buffers in vertex shaders, which drawing from the GPU buffers needs; use a Vulkan adapter (without a GPU: Debian's mesa-vulkan-drivers gives lavapipe)",
                    gpu.info.name
                )));
            }
        }
        let device = &gpu.device;
        let stateless = effect.layout.stateless();
        let compacted = match options.dead_slots {
            DeadSlots::Hidden => false,
            DeadSlots::Compacted => true,
            DeadSlots::BySize => effect.ir.capacity >= COMPACT_FROM_SLOTS,
        } && !stateless
            && !effect.ir.sort
            // Ribbons draw every table entry, reading slots from it; a mesh's instances draw
            // its vertices, not a sprite's.
            && effect.ir.render.ribbon.is_none()
            && effect.ir.render.mesh.is_none();
        let live = match compacted {
            true => Some(LiveList::new(gpu, res, effect, options.primitive)?),
            false => None,
        };
        let soft = effect.ir.render.soft.is_some() && target.depth.is_some() && target.soft;
        if soft && target.sample_count != 1 {
            return Err(RuntimeError::Unsupported(format!(
                "soft particles (render.soft) read the depth buffer as a single-sample texture; draw {:?} into a pass with one sample per pixel, or hard (DrawTarget::with_soft(false)), or leave render.soft out",
                effect.ir.name
            )));
        }
        let shape = DrawShape {
            through_list: effect.ir.sort || compacted,
            primitive: options.primitive,
            soft,
            ..draw_shape(effect, res)
        };
        let (module, mut entries) =
            draw_module(gpu, effect, res, &shape, live.as_ref().map(|l| &l.list))?;
        let blend = options.blend.unwrap_or(blend_state(effect.ir.render.blend));
        let topology = match options.primitive {
            Primitive::Quad => wgpu::PrimitiveTopology::TriangleStrip,
            Primitive::Triangle => wgpu::PrimitiveTopology::TriangleList,
        };
        let ribbon = effect.ir.render.ribbon;
        let mesh = effect.ir.render.mesh.as_ref();
        if let Some(why) = mesh.and_then(|m| m.missing.as_ref()) {
            return Err(RuntimeError::Compile(format!(
                "{why} (the effect was compiled to be stepped, not drawn; drawing it needs its mesh)"
            )));
        }
        let (entry_points, primitive) = match (ribbon, mesh) {
            (Some(_), _) => (
                ("vs_ribbon", "fs_ribbon"),
                plain(wgpu::PrimitiveTopology::TriangleStrip),
            ),
            // Closed meshes: their back faces are hidden behind their front ones.
            (None, Some(_)) => (
                ("vs_mesh", "fs_mesh"),
                wgpu::PrimitiveState {
                    cull_mode: Some(wgpu::Face::Back),
                    ..plain(wgpu::PrimitiveTopology::TriangleList)
                },
            ),
            (None, None) => (("vs", "fs"), plain(topology)),
        };
        let mesh_buffers = match ribbon {
            Some(_) => None,
            None => mesh.map(|m| m.buffers()),
        };
        let vertices = match (ribbon, &mesh_buffers) {
            (Some(_), _) => plume_compiler::ribbon::SEGMENT_VERTICES,
            (None, Some(buffers)) => buffers.draw_count(),
            (None, None) => options.primitive.vertices(),
        };
        // Opaque and cut-out meshes write depth where the target lets them; nothing else does.
        let solid = matches!(
            effect.ir.render.blend,
            plume_compiler::schema::Blend::Opaque | plume_compiler::schema::Blend::Mask(_)
        );
        let pipeline_target = DrawTarget {
            writes_depth: target.writes_depth && mesh.is_some() && solid,
            ..*target
        };
        let pipeline = render_pipeline(
            gpu,
            &module,
            entry_points,
            primitive,
            &pipeline_target,
            blend,
        );
        let view = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("draw view"),
            size: DRAW_VIEW_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        entries.push((0, view.clone()));
        if ribbon.is_some() {
            let table = res.extra_of(effect, Role::RibbonTable).ok_or_else(|| {
                RuntimeError::Gpu(
                    "a ribbon group has no ribbon table (a bug in the compiler)".into(),
                )
            })?;
            entries.push((plume_compiler::ribbon::RIBBON_DRAW_BINDING, table.clone()));
        }
        let mut indices = None;
        if let Some(buffers) = &mesh_buffers {
            let words = buffers.vertex_words.iter().map(|w| w.to_bits());
            let buffer = words_buffer(gpu, "mesh vertices", words, STORAGE)?;
            entries.push((plume_compiler::particle_mesh::MESH_VERTICES_BINDING, buffer));
            let list = buffers.indices.iter().copied();
            let usage = wgpu::BufferUsages::INDEX;
            indices = Some(words_buffer(gpu, "mesh indices", list, usage)?);
        }
        let lights = LightsUniform::new(gpu, effect);
        if let Some(lights) = &lights {
            entries.push((LIGHTS_BINDING, lights.buffer.clone()));
        }
        let texture = SpriteTexture::for_render(gpu, &effect.ir.render)?;
        let placeholder = match (soft, &target.depth) {
            (true, Some(test)) => Some(crate::draw::scene_depth::far_placeholder(gpu, test)?),
            _ => None,
        };
        let group = draw_group(
            gpu,
            &pipeline,
            &entries,
            texture.as_ref(),
            &bound_views(placeholder.as_ref(), lights.as_ref()),
        );
        let trail = match &effect.ir.render.trail {
            Some(_) if !stateless => Some(TrailDraw::new(
                gpu,
                effect,
                res,
                DrawShape {
                    // Every slot, in the depth order when there is one: the compacted list
                    // would need its own indirect count.
                    through_list: effect.ir.sort,
                    primitive: Primitive::Quad,
                    ..shape
                },
                target,
                blend,
                &shared_uniforms(&view, lights.as_ref()),
                &bound_views(placeholder.as_ref(), lights.as_ref()),
            )?),
            _ => None,
        };
        let instances = if let Some(ribbon) = ribbon {
            // A segment per table entry.
            Instances::Slots(ribbon.entries())
        } else if let Some(live) = live {
            Instances::Compacted(Box::new(live))
        } else if stateless {
            Instances::Frame(AtomicU32::new(0))
        } else if effect.ir.sort {
            alive_instances(gpu, res, effect.ir.capacity, vertices)?
        } else {
            Instances::Slots(effect.ir.capacity)
        };
        gpu.take_error()?;
        Ok(Self {
            pipeline,
            view,
            group,
            buffers: entries,
            texture,
            scene_depth: placeholder,
            soft,
            writes_depth: pipeline_target.writes_depth,
            trail,
            lights,
            instances,
            vertices,
            indices,
            size_scale: 1.0,
            gpu: gpu.clone(),
        })
    }

    /// Whether this draw fades sprites near the scene's depth (the effect has `render.soft` and
    /// the target a depth buffer): then bind the host's depth with [`Self::set_scene_depth`].
    pub(crate) fn is_soft(&self) -> bool {
        self.soft
    }

    /// Whether this draw writes depth.
    pub(crate) fn writes_depth(&self) -> bool {
        self.writes_depth
    }

    /// Binds the host's depth buffer for soft particles (see
    /// [`crate::EffectRenderer::set_scene_depth`]); does nothing for a draw that is not soft.
    pub(crate) fn set_scene_depth(&mut self, depth: &wgpu::TextureView) {
        if self.soft {
            self.scene_depth = Some(depth.clone());
            self.rebind();
        }
    }

    /// Reads `map` (an array view of a depth texture) as a lit look's shadow map; nothing for
    /// a draw that reads none.
    pub(crate) fn set_shadow_map(&mut self, map: &wgpu::TextureView) {
        if let Some(shadow) = self.lights.as_mut().and_then(|l| l.shadow.as_mut()) {
            shadow.map = map.clone();
            self.rebind();
        }
    }

    /// (Whether the draw is lit, whether it reads a shadow map.)
    pub(crate) fn lit_and_shadowed(&self) -> (bool, bool) {
        let lights = self.lights.as_ref();
        (lights.is_some(), lights.is_some_and(|l| l.shadow.is_some()))
    }

    /// Makes bind group 0 again (and its trail's) with the scene depth and shadow map held now.
    fn rebind(&mut self) {
        let views = bound_views(self.scene_depth.as_ref(), self.lights.as_ref());
        let texture = self.texture.as_ref();
        self.group = draw_group(&self.gpu, &self.pipeline, &self.buffers, texture, &views);
        if let Some(trail) = &mut self.trail {
            trail.rebind(&self.gpu, &views);
        }
    }

    /// Scales every sprite's size (1: the effect's own sizes).
    pub(crate) fn set_size_scale(&mut self, scale: f32) {
        self.size_scale = scale;
    }

    /// Lights a lit look with `lights` from the next frame on; nothing for an unlit one.
    pub(crate) fn set_lights(&self, lights: &Lights) {
        if let Some(uniform) = &self.lights {
            uniform.set(lights);
        }
    }

    /// Records the frame's `DrawView` (camera and steps done) into `encoder`, as a copy, so
    /// that several prepares in one submission each draw with their own.
    pub(crate) fn write_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        steps: u64,
    ) -> Result<(), RuntimeError> {
        if let Some(lights) = &self.lights {
            lights.record(&self.gpu, encoder, camera)?;
        }
        record_draw_view(
            &self.gpu,
            encoder,
            &self.view,
            camera,
            steps,
            self.size_scale,
        )
    }

    /// Records what decides the instances on the GPU: the live count, or the compacted list.
    pub(crate) fn record_instance_count(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
    ) -> Result<(), RuntimeError> {
        match &self.instances {
            Instances::Alive { kernel, group, .. } => {
                pass.set_pipeline(kernel);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
            Instances::Compacted(live) => live.record(pass)?,
            _ => {}
        }
        Ok(())
    }

    /// Whether the draw needs [`Self::record_instance_count`] each frame.
    pub(crate) fn counts_on_gpu(&self) -> bool {
        matches!(
            self.instances,
            Instances::Alive { .. } | Instances::Compacted(_)
        )
    }

    /// Sets a stateless draw's instances (the frame's threads).
    pub(crate) fn set_frame_instances(&self, threads: u32) {
        if let Instances::Frame(n) = &self.instances {
            n.store(threads, Ordering::Relaxed);
        }
    }

    /// Records the draw into the caller's render pass (after its preparation in the same or an
    /// earlier submission). Sets its own pipeline and bind group 0.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(trail) = &self.trail {
            trail.draw(pass);
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        if let Some(indices) = &self.indices {
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        }
        let indexed = self.indices.is_some();
        let instances = match &self.instances {
            Instances::Slots(n) => 0..*n,
            Instances::Frame(n) => 0..n.load(Ordering::Relaxed),
            // Meshes, the indexed draws, are never compacted: only `Alive`'s arguments have
            // the indexed form's five words.
            Instances::Alive { args, .. } if indexed => return pass.draw_indexed_indirect(args, 0),
            Instances::Alive { args, .. } => return pass.draw_indirect(args, 0),
            Instances::Compacted(live) => return pass.draw_indirect(&live.args, 0),
        };
        match (instances.is_empty(), indexed) {
            (true, _) => {}
            (false, true) => pass.draw_indexed(0..self.vertices, 0, instances),
            (false, false) => pass.draw(0..self.vertices, instances),
        }
    }
}

/// The uniforms a trail shares with its sprites' draw: the `DrawView` and a lit look's lights.
fn shared_uniforms(
    view: &wgpu::Buffer,
    lights: Option<&LightsUniform>,
) -> Vec<(u32, wgpu::Buffer)> {
    let lights = lights.map(|l| (LIGHTS_BINDING, l.buffer.clone()));
    [(0, view.clone())].into_iter().chain(lights).collect()
}

/// The resources a draw binds besides its buffers and texture: the scene depth (a soft
/// draw's) and the shadow map with its samplers (a lit one's).
fn bound_views<'a>(
    scene_depth: Option<&'a wgpu::TextureView>,
    lights: Option<&'a LightsUniform>,
) -> Vec<(u32, wgpu::BindingResource<'a>)> {
    let depth = scene_depth.map(|d| (SCENE_DEPTH_BINDING, wgpu::BindingResource::TextureView(d)));
    let shadow = lights
        .and_then(|l| l.shadow.as_ref())
        .map_or(Vec::new(), ShadowBinding::entries);
    depth.into_iter().chain(shadow).collect()
}

/// The draw module's shape on this device: how many particle buffers it binds (a stateless
/// effect binds none), through the depth order when the effect sorts, quads, no splat.
pub(crate) fn draw_shape(effect: &CompiledEffect, res: &Resources) -> DrawShape {
    DrawShape {
        chunks: if effect.layout.stateless() {
            1
        } else {
            res.chunk_count() as u32
        },
        chunk_slots: res.chunk_slots.min(u64::from(u32::MAX)) as u32,
        ..DrawShape::single(&effect.ir)
    }
}

/// The draw module of `shape` (the compiled one when it matches) and the buffers its bindings
/// 1 and up hold: the slot list (`list`, else the depth order), then the particle buffers or
/// the frame table. Binding 0, the `DrawView`, is the caller's.
pub(crate) fn draw_module(
    gpu: &Gpu,
    effect: &CompiledEffect,
    res: &Resources,
    shape: &DrawShape,
    list: Option<&wgpu::Buffer>,
) -> Result<(wgpu::ShaderModule, Vec<(u32, wgpu::Buffer)>), RuntimeError> {
    // The compiled effect carries the one-buffer module; other shapes are emitted here.
    let source = if *shape == DrawShape::single(&effect.ir) {
        effect.draw_wgsl.clone()
    } else {
        plume_compiler::wgsl::draw::emit(&effect.ir, &effect.layout, shape)
    };
    let module = gpu.shader_module("draw", &source);
    let mut entries = Vec::new();
    if shape.through_list {
        let order = match list {
            Some(list) => list.clone(),
            None => crate::sort::depth::sort_buffers(res)?.vals.clone(),
        };
        entries.push((1, order));
    }
    if effect.layout.stateless() {
        let frame = res
            .frame
            .as_ref()
            .expect("a stateless effect has a frame table");
        entries.push((FIRST_DATA_BINDING, frame.clone()));
    } else {
        for (k, chunk) in res.chunks(effect)?.iter().enumerate() {
            entries.push((FIRST_DATA_BINDING + k as u32, chunk.buffer.clone()));
        }
    }
    if effect.layout.batched {
        // A batch's instances' transforms (`sim::batch`).
        let models = res.extra_of(effect, Role::InstanceModels).ok_or_else(|| {
            RuntimeError::Gpu("a batch has no instance transforms (a bug in the compiler)".into())
        })?;
        entries.push((INSTANCE_MODELS_BINDING, models.clone()));
    }
    Ok((module, entries))
}
