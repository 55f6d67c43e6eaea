//! The preview's camera: it starts as the effect's `camera` and orbits, pans and zooms about its
//! target with the mouse. Kept across reloads, so an author keeps the view they chose.

use glam::{DVec3, Mat4, Vec3};
use plume_compiler::ir::CameraIr;
use plume_runtime::Camera;

/// Radians of orbit per pixel dragged.
const ORBIT_PER_PIXEL: f64 = 0.005;
/// Steepest pitch (just short of straight up or down, where "up" would be undefined).
const MAX_PITCH: f64 = 1.55;

/// An orbiting camera: a target, a distance, and yaw and pitch about the target.
#[derive(Clone, Debug, PartialEq)]
pub struct Orbit {
    /// The point looked at and orbited.
    pub target: DVec3,
    /// Eye to target (m).
    pub distance: f64,
    /// Angle about +Y (radians).
    pub yaw: f64,
    /// Angle above the horizontal (radians).
    pub pitch: f64,
    /// Vertical field of view (degrees).
    pub fov_y: f64,
}

impl Orbit {
    /// The orbit that reproduces the effect's camera.
    pub fn from_effect(camera: &CameraIr) -> Self {
        let offset = camera.eye - camera.target;
        let distance = offset.length().max(1e-3);
        Self {
            target: camera.target,
            distance,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
            fov_y: camera.fov_y,
        }
    }

    /// The eye position.
    pub fn eye(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + DVec3::new(cp * sy, sp, cp * cy) * self.distance
    }

    /// Orbits by a mouse drag of (dx, dy) pixels: right turns the view right, up looks from
    /// higher.
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * ORBIT_PER_PIXEL;
        self.pitch = (self.pitch + dy * ORBIT_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Pans by a drag of (dx, dy) pixels in a window `height` pixels tall: the target moves in
    /// the view plane so that the scene follows the mouse.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let forward = (self.target - self.eye()).normalize_or_zero();
        let right = forward.cross(DVec3::Y).normalize_or(DVec3::X);
        let up = right.cross(forward);
        // Metres per pixel at the target's distance.
        let scale = 2.0 * self.distance * (self.fov_y.to_radians() * 0.5).tan() / height.max(1.0);
        self.target += (-right * dx + up * dy) * scale;
    }

    /// Zooms by `notches` of the wheel (positive: closer), 10% of the distance each.
    pub fn zoom(&mut self, notches: f64) {
        self.distance = (self.distance * 0.9f64.powf(notches)).clamp(1e-3, 1e6);
    }

    /// View and projection for a window of `aspect` = width / height.
    pub fn camera(&self, aspect: f32) -> Camera {
        let view = Mat4::look_at_rh(self.eye().as_vec3(), self.target.as_vec3(), Vec3::Y);
        let proj = Mat4::perspective_rh(
            self.fov_y.to_radians() as f32,
            aspect,
            Camera::NEAR,
            Camera::FAR,
        );
        Camera::new(view, proj)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn effect_camera() -> CameraIr {
        CameraIr {
            eye: DVec3::new(0.0, 4.0, 14.0),
            target: DVec3::new(0.0, 3.0, 0.0),
            fov_y: 45.0,
        }
    }

    #[test]
    fn it_starts_as_the_effect_camera() {
        let c = effect_camera();
        let orbit = Orbit::from_effect(&c);
        assert!((orbit.eye() - c.eye).length() < 1e-9);
        let ours = orbit.camera(16.0 / 9.0);
        let theirs = Camera::from_effect(&c, 16.0 / 9.0);
        for (a, b) in ours
            .view
            .to_cols_array()
            .iter()
            .zip(theirs.view.to_cols_array())
        {
            assert!((a - b).abs() < 1e-5);
        }
        assert_eq!(ours.proj, theirs.proj);
    }

    #[test]
    fn orbit_keeps_the_distance_zoom_changes_it_pan_moves_the_target() {
        let mut o = Orbit::from_effect(&effect_camera());
        let d = o.distance;
        o.orbit(120.0, -40.0);
        assert!(((o.eye() - o.target).length() - d).abs() < 1e-9);
        o.zoom(1.0);
        assert!((o.distance - 0.9 * d).abs() < 1e-9);
        let t = o.target;
        o.pan(10.0, 0.0, 720.0);
        assert!((o.target - t).length() > 0.0);
        // Pitch never reaches the pole.
        o.orbit(0.0, 1e6);
        assert!(o.pitch <= MAX_PITCH && o.eye().is_finite());
    }
}
