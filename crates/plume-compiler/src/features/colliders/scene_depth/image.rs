//! The depth image a `SceneDepth` collider reads and the camera it was drawn with, as the host
//! gives them: the runtime writes [`DepthCamera::words`] into the `scene_camera` binding, and
//! the reference reads a [`DepthImage`].

use glam::{DMat4, Mat4};

/// The camera a depth image was drawn with (column-major f32, as the GPU reads it), with the
/// inverses both the kernel and the reference use.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthCamera {
    /// World to clip: projection · view, multiplied in f64 and rounded once.
    pub(crate) view_projection: [f32; 16],
    /// World to view (right-handed, looking down −z).
    pub view: [f32; 16],
    /// View to clip (wgpu's clip space, depth in [0, 1], standard or reversed).
    pub projection: [f32; 16],
    /// Clip to view.
    pub(crate) inverse_projection: [f32; 16],
    /// View to world.
    pub(crate) inverse_view: [f32; 16],
}

/// f32 words of [`DepthCamera::words`], in vec4s: (width, height, 0, 0); view · projection's
/// columns; the view's row 2 (−depth = row 2 · (x, 1)); the inverse projection's columns; the
/// inverse view's; the view's.
pub(crate) const CAMERA_VEC4S: usize = 18;

/// f32 words of [`DepthCamera::words`].
pub(crate) const CAMERA_WORDS: usize = 4 * CAMERA_VEC4S;

/// Where each part starts in [`DepthCamera::words`], in vec4s.
pub mod at {
    /// (width, height, 0, 0).
    pub const SIZE: usize = 0;
    /// The view-projection's columns.
    pub(crate) const VIEW_PROJECTION: usize = 1;
    /// The view's row 2.
    pub(crate) const VIEW_ROW_Z: usize = 5;
    /// The inverse projection's columns.
    pub(crate) const INVERSE_PROJECTION: usize = 6;
    /// The inverse view's columns.
    pub(crate) const INVERSE_VIEW: usize = 10;
    /// The view's columns.
    pub(crate) const VIEW: usize = 14;
}

impl DepthCamera {
    /// The camera of `view` and `projection`; refused when either is not finite or not
    /// invertible.
    pub fn new(view: Mat4, projection: Mat4) -> Result<Self, String> {
        let finite = |m: &Mat4| m.to_cols_array().iter().all(|x| x.is_finite());
        if !finite(&view) || !finite(&projection) {
            return Err("the scene depth's camera has a matrix that is not finite".into());
        }
        let (v, p) = (view.as_dmat4(), projection.as_dmat4());
        let invertible = |m: &DMat4| {
            let d = m.determinant();
            d.is_finite() && d.abs() > 1e-30
        };
        if !invertible(&v) || !invertible(&p) {
            return Err("the scene depth's camera has a matrix that is not invertible".into());
        }
        let f32s = |m: DMat4| m.as_mat4().to_cols_array();
        Ok(Self {
            view_projection: f32s(p * v),
            view: view.to_cols_array(),
            projection: projection.to_cols_array(),
            inverse_projection: f32s(p.inverse()),
            inverse_view: f32s(v.inverse()),
        })
    }

    /// The `scene_camera` binding's contents for an image of `width` x `height`.
    pub fn words(&self, width: u32, height: u32) -> [f32; CAMERA_WORDS] {
        let mut out = [0.0; CAMERA_WORDS];
        out[4 * at::SIZE] = width as f32;
        out[4 * at::SIZE + 1] = height as f32;
        let mut put = |vec4: usize, m: &[f32; 16]| out[4 * vec4..4 * vec4 + 16].copy_from_slice(m);
        put(at::VIEW_PROJECTION, &self.view_projection);
        put(at::INVERSE_PROJECTION, &self.inverse_projection);
        put(at::INVERSE_VIEW, &self.inverse_view);
        put(at::VIEW, &self.view);
        for c in 0..4 {
            out[4 * at::VIEW_ROW_Z + c] = self.view[4 * c + 2];
        }
        out
    }
}

/// A depth image and its camera, as the reference reads it (the GPU reads the host's texture).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Depth per pixel, row by row from the top.
    pub depth: Vec<f32>,
    /// The camera it was drawn with.
    pub camera: DepthCamera,
}
