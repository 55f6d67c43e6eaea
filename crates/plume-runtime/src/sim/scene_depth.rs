//! The depth image a `SceneDepth` collider meets (`plume_compiler::colliders::scene_depth`):
//! checks the host's depth texture, binds a depth-only view of it in the group's compute bind
//! groups and writes its camera into the `scene_camera` buffer.

use glam::Mat4;
use plume_compiler::colliders::scene_depth::DepthCamera;

use crate::error::RuntimeError;
use crate::sim::group::Group;

/// Why `depth` cannot be a scene depth image, if it cannot.
pub(crate) fn check_texture(depth: &wgpu::Texture) -> Result<(), RuntimeError> {
    let refuse = |why: String| Err(RuntimeError::Control(format!("scene depth: {why}")));
    if !depth.format().has_depth_aspect() {
        return refuse(format!(
            "the texture is {:?}, not a depth format",
            depth.format()
        ));
    }
    if depth.sample_count() != 1 {
        return refuse(format!(
            "the texture has {} samples; give a single-sampled depth texture (resolve or copy the multisampled one first)",
            depth.sample_count()
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

/// The camera's words, or why the matrices cannot be used.
pub(crate) fn camera(view: Mat4, projection: Mat4) -> Result<DepthCamera, RuntimeError> {
    DepthCamera::new(view, projection).map_err(RuntimeError::Control)
}

/// Binds `depth` (checked) and writes `camera` for `group`'s next steps; a group without a
/// `SceneDepth` collider is left alone.
pub(crate) fn bind(group: &mut Group, depth: &wgpu::Texture, camera: &DepthCamera) {
    if !group.effect.ir.collides_with_scene_depth() {
        return;
    }
    let view = depth.create_view(&wgpu::TextureViewDescriptor {
        label: Some("scene depth"),
        aspect: wgpu::TextureAspect::DepthOnly,
        ..Default::default()
    });
    group.res.set_scene_depth_view(&group.effect, view);
    let words = camera.words(depth.width(), depth.height());
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let buffer = group
        .res
        .extra_named(&group.effect, "scene_camera")
        .expect("a SceneDepth collider gets its camera buffer");
    group.gpu.queue.write_buffer(buffer, 0, &bytes);
}
