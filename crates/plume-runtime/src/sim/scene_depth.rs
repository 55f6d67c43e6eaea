//! The depth image a `SceneDepth` collider meets (`plume_compiler::colliders::scene_depth`):
//! the host's depth texture copied into the group's `scene_depth` buffer (grown to its size)
//! and its camera into `scene_camera`, both recorded into the host's encoder, so that the
//! steps recorded after them meet that image.

use glam::Mat4;
use plume_compiler::colliders::scene_depth::DepthCamera;
use plume_compiler::passes::layout::Role;

use crate::device::buffers::staging;
use crate::device::depth_copy::{copy_bytes, DepthCopy};
use crate::error::RuntimeError;
use crate::sim::group::Group;

pub(crate) use crate::device::depth_copy::check_texture;

/// The camera's words, or why the matrices cannot be used.
pub(crate) fn camera(view: Mat4, projection: Mat4) -> Result<DepthCamera, RuntimeError> {
    DepthCamera::new(view, projection).map_err(RuntimeError::Control)
}

/// Records into `encoder` the copy of `depth` (checked) and of `camera` for `group`'s steps
/// recorded after it; a group without a `SceneDepth` collider is left alone.
pub(crate) fn record(
    group: &mut Group,
    copy: &mut DepthCopy,
    encoder: &mut wgpu::CommandEncoder,
    depth: &wgpu::Texture,
    camera: &DepthCamera,
) -> Result<(), RuntimeError> {
    if !group.effect.ir.collides_with_scene_depth() {
        return Ok(());
    }
    let binding = |role| {
        group
            .effect
            .layout
            .binding_of(role)
            .map(|b| b.binding)
            .expect("a SceneDepth collider has its bindings")
    };
    let (image_at, camera_at) = (binding(Role::SceneDepth), binding(Role::SceneCamera));
    let bytes = copy_bytes(depth);
    let held = group.res.extra_buffer(image_at).map_or(0, |b| b.size());
    if held < bytes {
        let grown = group.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene_depth"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        group.res.replace_extra(&group.effect, image_at, grown);
    }
    let image = group
        .res
        .extra_buffer(image_at)
        .expect("the scene depth's buffer was made above");
    copy.record(&group.gpu, encoder, depth, image);
    let words = camera.words(depth.width(), depth.height());
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let source = staging(&group.gpu, "scene camera", &bytes)?;
    let target = group
        .res
        .extra_buffer(camera_at)
        .expect("a SceneDepth collider gets its camera buffer");
    encoder.copy_buffer_to_buffer(&source, 0, target, 0, bytes.len() as u64);
    Ok(())
}
