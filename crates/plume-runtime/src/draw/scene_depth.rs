//! The scene depth a soft draw reads (`render.soft`): the host's depth texture, bound with
//! [`crate::draw::raster::EffectRenderer::set_scene_depth`], or until then a 1x1 placeholder cleared
//! to the far plane, so that sprites are not faded (the draw module clamps its reads to the
//! texture's size).

use crate::device::gpu::Gpu;
use crate::draw::target::DepthTest;
use crate::error::RuntimeError;

/// A 1x1 depth texture of the test's format holding the far plane's depth (0 for a reversed-Z
/// test, `Greater` or `GreaterEqual`; 1 otherwise); its depth-only view.
pub(crate) fn far_placeholder(
    gpu: &Gpu,
    test: &DepthTest,
) -> Result<wgpu::TextureView, RuntimeError> {
    let texture = gpu.texture_2d(
        "scene depth placeholder",
        (1, 1),
        test.format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let far = match test.compare {
        wgpu::CompareFunction::Greater | wgpu::CompareFunction::GreaterEqual => 0.0,
        _ => 1.0,
    };
    let attachment_view = texture.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("scene depth placeholder"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &attachment_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(far),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: test
                .format
                .has_stencil_aspect()
                .then_some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    gpu.queue.submit([encoder.finish()]);
    gpu.take_error()?;
    Ok(texture.create_view(&wgpu::TextureViewDescriptor {
        aspect: wgpu::TextureAspect::DepthOnly,
        ..Default::default()
    }))
}
