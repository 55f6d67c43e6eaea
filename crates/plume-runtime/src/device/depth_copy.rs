//! A depth texture copied into a buffer of f32 (row by row from the top) inside a caller's
//! encoder: how a `SceneDepth` collider gets the host's depth (in command order, whatever the
//! texture's format, sample count or lifetime) and how `Scene::read_depth` reads one back.

use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// The copy kernels, single-sampled and multisampled (made on first use).
#[derive(Default)]
pub(crate) struct DepthCopy {
    single: Option<wgpu::ComputePipeline>,
    multi: Option<wgpu::ComputePipeline>,
}

/// Why `depth` cannot be copied, if it cannot.
pub(crate) fn check_texture(depth: &wgpu::Texture) -> Result<(), RuntimeError> {
    let refuse = |why: String| Err(RuntimeError::Control(format!("scene depth: {why}")));
    if !depth.format().has_depth_aspect() {
        return refuse(format!(
            "the texture is {:?}, not a depth format",
            depth.format()
        ));
    }
    if depth.dimension() != wgpu::TextureDimension::D2 || depth.depth_or_array_layers() != 1 {
        return refuse("the texture must be a single 2D image".into());
    }
    if !depth.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return refuse("the texture needs TextureUsages::TEXTURE_BINDING to be read".into());
    }
    if depth.width() > 0xffff || depth.height() > 0xffff {
        return refuse(format!(
            "{} x {} pixels is past the 65535 a side the collider reads",
            depth.width(),
            depth.height()
        ));
    }
    Ok(())
}

/// The depths of `depth` (a single-sampled or multisampled 2D depth texture with
/// `TEXTURE_BINDING`), row by row from the top, read back (waits for the GPU).
pub(crate) fn read_depths(gpu: &Gpu, depth: &wgpu::Texture) -> Result<Vec<f32>, RuntimeError> {
    let out = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("depth read"),
        size: copy_bytes(depth),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    DepthCopy::default().record(gpu, &mut encoder, depth, &out);
    gpu.queue.submit([encoder.finish()]);
    let bytes = crate::device::readback::read_buffer(gpu, &out)?;
    gpu.take_error()?;
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// Bytes of the copy of `depth`.
pub(crate) fn copy_bytes(depth: &wgpu::Texture) -> u64 {
    u64::from(depth.width()) * u64::from(depth.height()) * 4
}

impl DepthCopy {
    fn pipeline(&mut self, gpu: &Gpu, multisampled: bool) -> &wgpu::ComputePipeline {
        let slot = if multisampled {
            &mut self.multi
        } else {
            &mut self.single
        };
        slot.get_or_insert_with(|| {
            let declaration = if multisampled {
                "@group(0) @binding(0) var depth: texture_multisampled_2d<f32>;"
            } else {
                "@group(0) @binding(0) var depth: texture_2d<f32>;"
            };
            let source = format!("{declaration}\n{}", include_str!("depth_copy.wgsl"));
            let module = gpu.shader_module("depth copy", &source);
            gpu.compute_pipeline(&module, "main", None)
        })
    }

    /// Records into `encoder` the copy of `depth` (checked with [`check_texture`]) into `out`
    /// (at least [`copy_bytes`] long, with STORAGE usage).
    pub(crate) fn record(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
        out: &wgpu::Buffer,
    ) {
        let pipeline = self.pipeline(gpu, depth.sample_count() > 1);
        let view = depth.create_view(&wgpu::TextureViewDescriptor {
            label: Some("depth copy"),
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth copy"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: out.as_entire_binding(),
                },
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("depth copy"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(depth.width().div_ceil(8), depth.height().div_ceil(8), 1);
    }
}
