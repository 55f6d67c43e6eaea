//! The depth image a `SceneDepth` collider reads and the camera it was drawn with, as the host
//! gives them: the runtime writes [`DepthCamera::words`] into the `scene_camera` binding, and
//! the reference reads a [`DepthImage`].

use glam::{DMat4, Mat4};

/// The camera a depth image was drawn with (column-major f32, as the GPU reads it), with the
/// inverses both the kernel and the reference use.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthCamera {
    /// World to view (right-handed, looking down −z).
    pub view: [f32; 16],
    /// View to clip (wgpu's clip space, depth in [0, 1], standard or reversed).
    pub projection: [f32; 16],
    /// Clip to view.
    pub inverse_projection: [f32; 16],
    /// View to world.
    pub inverse_view: [f32; 16],
}

/// f32 words of [`DepthCamera::words`]: (width, height, 0, 0), then the four matrices.
pub const CAMERA_WORDS: usize = 4 + 4 * 16;

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
            view: view.to_cols_array(),
            projection: projection.to_cols_array(),
            inverse_projection: f32s(p.inverse()),
            inverse_view: f32s(v.inverse()),
        })
    }

    /// The `scene_camera` binding's contents for an image of `width` x `height`.
    pub fn words(&self, width: u32, height: u32) -> [f32; CAMERA_WORDS] {
        let mut out = [0.0; CAMERA_WORDS];
        out[0] = width as f32;
        out[1] = height as f32;
        for (k, m) in [
            &self.view,
            &self.projection,
            &self.inverse_projection,
            &self.inverse_view,
        ]
        .into_iter()
        .enumerate()
        {
            out[4 + 16 * k..4 + 16 * (k + 1)].copy_from_slice(m);
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
