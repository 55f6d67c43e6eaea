//! An effect's ribbons (`render.trail`): the pipeline of its trail draw module
//! (`plume_compiler::wgsl::trail`) and the bind group of the particle buffers and trail rings
//! it reads. [`crate::draw::raster::EffectRenderer`] draws it before its sprites, in the same pass
//! and with the same blending, one instance per slot (a free slot's ribbon is degenerate).

use plume_compiler::wgsl::draw::{DrawShape, DRAW_VIEW_BYTES, FIRST_DATA_BINDING};
use plume_compiler::wgsl::trail::{self, FIRST_TRAIL_BINDING};
use plume_compiler::CompiledEffect;

use crate::device::gpu::Gpu;
use crate::device::resources::Resources;
use crate::draw::pipeline::{draw_group, render_pipeline};
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;

/// The trail draw of one effect into one kind of target.
pub(crate) struct TrailDraw {
    pipeline: wgpu::RenderPipeline,
    /// Bind group 0's buffers (without the scene depth), to rebuild it with another depth.
    buffers: Vec<(u32, wgpu::Buffer)>,
    group: wgpu::BindGroup,
    vertices: u32,
    instances: u32,
}

impl TrailDraw {
    /// The trail draw of `effect` (stateful, with a trail), whose buffers `res` holds, bound as
    /// `shape` says. It shares the sprite draw's uniforms (`shared`: the `DrawView`, and a lit
    /// look's lights) and the views its group binds (`views`: the scene depth of a soft draw, a
    /// lit look's shadow map and samplers), as its module reads what the sprites' does.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        gpu: &Gpu,
        effect: &CompiledEffect,
        res: &Resources,
        shape: DrawShape,
        target: &DrawTarget,
        blend: wgpu::BlendState,
        shared: &[(u32, wgpu::Buffer)],
        views: &[(u32, wgpu::BindingResource<'_>)],
    ) -> Result<Self, RuntimeError> {
        let spec = effect
            .ir
            .render
            .trail
            .as_ref()
            .expect("a trail draw is made for an effect with a trail");
        let source = match &effect.trail_wgsl {
            Some(compiled) if shape == DrawShape::single(&effect.ir) => compiled.clone(),
            _ => trail::emit(&effect.ir, &effect.layout, &shape),
        };
        let module = gpu.shader_module("trail", &source);
        let pipeline = render_pipeline(
            gpu,
            &module,
            ("vs_trail", "fs_trail"),
            crate::draw::pipeline::plain(wgpu::PrimitiveTopology::TriangleStrip),
            // Trails blend: they never write depth.
            &DrawTarget {
                writes_depth: false,
                ..*target
            },
            blend,
        );
        debug_assert!(shared
            .iter()
            .any(|(b, v)| *b == 0 && v.size() == DRAW_VIEW_BYTES));
        let mut buffers = shared.to_vec();
        buffers.extend(trail_buffers(effect, res, shape.through_list)?);
        let group = draw_group(gpu, &pipeline, &buffers, None, views);
        Ok(Self {
            pipeline,
            buffers,
            group,
            vertices: trail::vertices(spec),
            instances: effect.ir.capacity,
        })
    }

    /// Binds `views` again (the sprite draw's, after the host gave another scene depth or
    /// shadow map).
    pub(crate) fn rebind(&mut self, gpu: &Gpu, views: &[(u32, wgpu::BindingResource<'_>)]) {
        self.group = draw_group(gpu, &self.pipeline, &self.buffers, None, views);
    }

    /// Records the ribbons into `pass`.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.draw(0..self.vertices, 0..self.instances);
    }
}

/// What a trail draw module reads besides its view (the raster draw's and the compute
/// renderer's alike): the depth order when it draws `through_list`, and each particle buffer with
/// its trail ring.
pub(crate) fn trail_buffers(
    effect: &CompiledEffect,
    res: &Resources,
    through_list: bool,
) -> Result<Vec<(u32, wgpu::Buffer)>, RuntimeError> {
    let mut buffers = Vec::new();
    if through_list {
        buffers.push((1, crate::sort::depth::sort_buffers(res)?.vals.clone()));
    }
    for (k, chunk) in res.chunks(effect)?.iter().enumerate() {
        let ring = chunk
            .trail
            .as_ref()
            .expect("the chunks of an effect with a trail hold rings");
        buffers.push((FIRST_DATA_BINDING + k as u32, chunk.buffer.clone()));
        buffers.push((FIRST_TRAIL_BINDING + k as u32, ring.clone()));
    }
    Ok(buffers)
}
