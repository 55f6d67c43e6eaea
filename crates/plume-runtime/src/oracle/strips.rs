//! The reference drawing of trails (`render.trail`), beside [`crate::oracle::sprites`]'s
//! sprites: each particle's strip points (read back from the GPU's rings, or the f64
//! reference's), their vertices placed on the CPU in f64 by `TrailIr::strip_vertices` and
//! coloured there, drawn as triangles by a fixed shader before the sprites.

use std::collections::HashMap;

use glam::{DVec3, Mat4};
use plume_compiler::ir::EffectIr;
use plume_compiler::reference::ParticleRecord;

use crate::device::gpu::Gpu;
use crate::draw::pipeline::blend_state;
use crate::draw::pipeline::vertex_pipeline;
use crate::draw::target::DrawTarget;
use crate::outputs::offscreen::FORMAT;

/// One strip vertex (of a trail, or of a ribbon joining particles): world position, side (−1
/// or +1 across the strip), colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StripVertex {
    /// Position in world space.
    pub position: [f32; 3],
    /// −1 or +1: which edge of the strip.
    pub across: f32,
    /// Colour and opacity.
    pub color: [f32; 4],
}

/// Bytes of one vertex: a vec3, a float and a vec4 of f32.
pub(crate) const STRIP_VERTEX_BYTES: u64 = 32;

/// The trail strips of `records` (in draw order) whose points `trails` holds by id, facing a camera
/// with view matrix `view`, as a triangle list: each segment the two triangles the GPU's strip
/// makes of it. Colours are the particle's at its life fraction times the trail's at each
/// point's fraction, and with `render.lit` lit at each point by the effect's lights through
/// the strip's normal there (`trail::strip_normals`).
pub fn trail_strips(
    records: &[ParticleRecord],
    trails: &[(u32, Vec<DVec3>)],
    ir: &EffectIr,
    view: Mat4,
) -> Vec<StripVertex> {
    let Some(trail) = &ir.render.trail else {
        return Vec::new();
    };
    // The eye: where the view matrix takes the origin from.
    let eye = view.as_dmat4().inverse().transform_point3(DVec3::ZERO);
    let by_id: HashMap<u32, &Vec<DVec3>> = trails.iter().map(|(id, p)| (*id, p)).collect();
    let mut out = Vec::new();
    for r in records {
        let Some(points) = by_id.get(&r.id) else {
            continue;
        };
        if points.len() < 2 || !r.position.is_finite() {
            continue;
        }
        let life = match r.lifetime {
            Some(l) if l > 0.0 => (r.age / l).clamp(0.0, 1.0),
            _ => 0.0,
        };
        let c = ir.render.color_at(life);
        let particle = [c[0] * r.tint.x, c[1] * r.tint.y, c[2] * r.tint.z, c[3]];
        let sides = trail.strip_vertices(points, eye, 1.0);
        let normals = plume_compiler::trail::strip_normals(points, eye);
        push_triangles(&mut out, &sides, &|j| {
            let tint = trail.color_at(j as f64 / f64::from(trail.ring()));
            let c = std::array::from_fn(|c| particle[c] * tint[c]);
            strip_color(ir, c, normals[j], points[j])
        });
    }
    out
}

/// A strip point's colour `c` as drawn: lit at world point `p` through the strip's unit
/// `normal` there when the look is lit (the effect's lights, `Lights::received`, `Lit::shade`),
/// else as it is.
pub(crate) fn strip_color(ir: &EffectIr, c: [f64; 4], normal: DVec3, p: DVec3) -> [f32; 4] {
    let rgb = DVec3::new(c[0], c[1], c[2]);
    let rgb = match &ir.render.lit {
        Some(lit) => lit.shade(rgb, ir.lights.received(normal, p, lit.wrap)),
        None => rgb,
    };
    [rgb.x as f32, rgb.y as f32, rgb.z as f32, c[3] as f32]
}

/// Appends the triangles of a strip whose points' vertices are `sides` (side −1, then +1) and
/// whose point j is of colour `color(j)`: each segment the two triangles the GPU's strip makes
/// of it.
pub(crate) fn push_triangles(
    out: &mut Vec<StripVertex>,
    sides: &[[DVec3; 2]],
    color: &dyn Fn(usize) -> [f32; 4],
) {
    let vertex = |j: usize, side: usize| StripVertex {
        position: sides[j][side].as_vec3().to_array(),
        across: if side == 0 { -1.0 } else { 1.0 },
        color: color(j),
    };
    for j in 0..sides.len().saturating_sub(1) {
        let (a, b, c, d) = (
            vertex(j, 0),
            vertex(j, 1),
            vertex(j + 1, 0),
            vertex(j + 1, 1),
        );
        out.extend([a, b, c, b, c, d]);
    }
}

/// The reference strip pipeline, drawing into [`FORMAT`] with one blend mode.
pub(crate) struct StripPipeline {
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
}

impl StripPipeline {
    /// The pipeline, reading the reference renderer's `camera` uniform (view, projection).
    pub(crate) fn new(
        gpu: &Gpu,
        blend: plume_compiler::schema::Blend,
        camera: &wgpu::Buffer,
    ) -> Self {
        let device = &gpu.device;
        let source = [
            include_str!("reference_camera.wgsl"),
            include_str!("reference_strip.wgsl"),
        ]
        .concat();
        let module = gpu.shader_module("reference strips", &source);
        let pipeline = vertex_pipeline(
            gpu,
            &module,
            ("vs", "fs"),
            crate::draw::pipeline::plain(wgpu::PrimitiveTopology::TriangleList),
            &DrawTarget::new(FORMAT),
            blend_state(blend),
            None,
            &[Some(wgpu::VertexBufferLayout {
                array_stride: STRIP_VERTEX_BYTES,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x4],
            })],
        );
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reference strips"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        Self { pipeline, group }
    }

    /// A vertex buffer of `vertices` (None when there are none).
    pub(crate) fn upload(gpu: &Gpu, vertices: &[StripVertex]) -> Option<wgpu::Buffer> {
        if vertices.is_empty() {
            return None;
        }
        let mut bytes = Vec::with_capacity(vertices.len() * STRIP_VERTEX_BYTES as usize);
        for v in vertices {
            let fields = [&v.position[..], &[v.across][..], &v.color[..]];
            for x in fields.into_iter().flatten() {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reference strips"),
            size: bytes.len() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue.write_buffer(&buffer, 0, &bytes);
        Some(buffer)
    }

    /// Records the draw of `count` vertices from `buffer` into `pass`.
    pub(crate) fn record(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        buffer: &wgpu::Buffer,
        count: u32,
    ) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, buffer.slice(..));
        pass.draw(0..count, 0..1);
    }
}
