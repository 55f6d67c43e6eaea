//! The view particles are sorted and drawn from: a host's view and projection matrices, or the
//! effect's own `camera` (a right-handed look-at and a perspective projection into wgpu's clip
//! space, depth in [0, 1]).

use glam::{DVec3, Mat4, Vec3};
use plume_compiler::ir::CameraIr;
use plume_compiler::wgsl::draw::DRAW_VIEW_BYTES;

use crate::device::buffers::staging;
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// View and projection matrices (column-major, right-handed view space looking down −z; the
/// projection maps into wgpu's clip space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World to view.
    pub view: Mat4,
    /// View to clip.
    pub proj: Mat4,
}

impl Camera {
    /// Near plane of the effect camera's projection (m).
    pub const NEAR: f32 = 0.05;
    /// Far plane of the effect camera's projection (m).
    pub const FAR: f32 = 10_000.0;

    /// A camera from a host's matrices.
    pub fn new(view: Mat4, proj: Mat4) -> Self {
        Self { view, proj }
    }

    /// The effect's camera for an image of `aspect` = width / height.
    pub fn from_effect(camera: &CameraIr, aspect: f32) -> Self {
        let (view, proj) = camera_matrices(camera, aspect);
        Self { view, proj }
    }

    /// The depth sort's axis: depth = dot(axis.xyz, x) + axis.w is the distance in front of
    /// the camera along its forward axis, −z in view space (row 2 of the view matrix, negated).
    pub fn depth_axis(&self) -> [f32; 4] {
        let v = &self.view;
        [-v.x_axis.z, -v.y_axis.z, -v.z_axis.z, -v.w_axis.z]
    }

    /// [`Self::depth_axis`] as the `DepthAxis` uniform's bytes.
    pub(crate) fn depth_axis_bytes(&self) -> Vec<u8> {
        self.depth_axis()
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect()
    }

    /// Where a world point lands in an image of `width` x `height` (pixels, origin top left,
    /// pixel centres at half-integers), or None when it is behind the camera.
    pub fn project(&self, width: u32, height: u32, p: DVec3) -> Option<(f32, f32)> {
        let clip = self.proj * self.view * p.as_vec3().extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some((
            (ndc.x * 0.5 + 0.5) * width as f32,
            (0.5 - ndc.y * 0.5) * height as f32,
        ))
    }
}

/// View and projection matrices of the effect's camera for an image of `aspect` = width /
/// height: a look-at from `eye` to `target` with +Y up (+Z up when looking along ±Y), and a
/// perspective with vertical `fov_y` between [`Camera::NEAR`] and [`Camera::FAR`].
pub(crate) fn camera_matrices(camera: &CameraIr, aspect: f32) -> (Mat4, Mat4) {
    let eye = camera.eye.as_vec3();
    let target = camera.target.as_vec3();
    let forward = (target - eye).normalize_or_zero();
    // Y is up unless the camera looks straight along it.
    let up = if forward.cross(Vec3::Y).length_squared() < 1e-6 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let view = Mat4::look_at_rh(eye, target, up);
    let proj = Mat4::perspective_rh(
        camera.fov_y.to_radians() as f32,
        aspect,
        Camera::NEAR,
        Camera::FAR,
    );
    (view, proj)
}

/// Records a copy of the `DrawView` uniform (camera, steps done, size scale) into `view` in
/// `encoder`, so that several frames prepared in one submission each draw with their own.
pub(crate) fn record_draw_view(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::Buffer,
    camera: &Camera,
    steps: u64,
    size_scale: f32,
) -> Result<(), RuntimeError> {
    let src = staging(
        gpu,
        "draw view",
        &draw_view_bytes(camera, steps, size_scale),
    )?;
    encoder.copy_buffer_to_buffer(&src, 0, view, 0, DRAW_VIEW_BYTES);
    Ok(())
}

/// The `DrawView` uniform's bytes: view and projection matrices, steps done (mod 2^32, as the
/// kernels' step index and die_at wrap), the size scale.
pub(crate) fn draw_view_bytes(camera: &Camera, steps: u64, size_scale: f32) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(DRAW_VIEW_BYTES as usize);
    for m in [camera.view, camera.proj] {
        for x in m.to_cols_array() {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    bytes.extend_from_slice(&(steps as u32).to_le_bytes());
    bytes.extend_from_slice(&size_scale.to_le_bytes());
    bytes.extend_from_slice(&[0; 8]);
    bytes
}
