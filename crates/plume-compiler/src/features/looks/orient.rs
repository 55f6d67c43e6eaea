//! Sprite orientation (`render.orient`): which way each particle's quad faces and how long it
//! is. This module owns the option end to end: its lowered form, the WGSL that places the quad
//! (in the draw module's `sprite_at`) and the f64 twin the reference drawing uses, so the two
//! place the same quad.
//!
//! A sprite is a quad spanned by two half axes from its centre: corner (cx, cy) in [-1, 1]² is
//! centre + cx · half_x + cy · half_y. The fragment shader's disc (and a texture's u, v) lives
//! in those corner coordinates, so a stretched quad draws a stretched disc.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, Writer};
use serde::Deserialize;

/// How a sprite's quad is oriented (`render.orient`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) enum Orient {
    /// Parallel to the image plane: a round dot from every side.
    #[default]
    Camera,
    /// Facing the camera, its long axis along the velocity's component in the image plane:
    /// length = max(size, min(size + stretch · speed, max_length)), width = size.
    Velocity {
        /// Metres of length per m/s of image-plane speed (seconds), >= 0.
        stretch: f64,
        /// Longest a sprite gets (m), > 0.
        max_length: f64,
    },
    /// Lying in the world plane through the particle perpendicular to this normal (a ripple
    /// on the ground: `Fixed((0.0, 1.0, 0.0))`).
    Fixed(Vec3),
    /// Turned to face the camera's position: each sprite's normal points at the eye, its x
    /// axis level with the camera's (up × normal), so sprites away from the image's centre
    /// turn towards it (bevy_hanabi's `FaceCameraPosition`).
    FaceCamera,
}

/// Image-plane speeds at or below this (squared, (m/s)²) have no direction: the sprite stays
/// upright and unstretched instead of normalising a zero vector.
pub(crate) const STILL_SPEED2: f64 = 1e-30;

/// The orientation, lowered: the fixed plane's axes computed once in f64.
impl Orient {
    /// Checks a streak's `stretch` (>= 0) and `max_length` (> 0), and a fixed plane's normal
    /// (not zero); `path` names `render.orient`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        match *self {
            Orient::Camera | Orient::FaceCamera => {}
            Orient::Velocity {
                stretch,
                max_length,
            } => {
                let v = path.variant("Velocity");
                c.non_negative(&v.field("stretch"), stretch);
                c.positive(&v.field("max_length"), max_length);
            }
            Orient::Fixed(normal) => c.direction(&path.variant("Fixed").inner(), normal),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrientIr {
    /// Parallel to the image plane, upright.
    Camera,
    /// Facing the camera, long axis along the image-plane velocity.
    Velocity {
        /// Metres of length per m/s of image-plane speed.
        stretch: f64,
        /// Longest length (m).
        max_length: f64,
    },
    /// In a world plane: `right` and `up` are unit vectors with right × up = the normal.
    Fixed {
        /// The plane's first axis (the sprite's +x).
        right: DVec3,
        /// The plane's second axis (the sprite's +y).
        up: DVec3,
    },
    /// Facing the camera's position.
    FaceCamera,
}

/// Below this squared length (m²) a sprite is at the eye, or its normal along the camera's up:
/// it keeps the `Camera` axes (or the camera's right) instead of normalising a zero vector.
pub(crate) const FACING_FLOOR2: f64 = 1e-12;

impl OrientIr {
    /// Lowers the schema's orientation (already checked: a fixed normal is a direction).
    pub(crate) fn lower(orient: &Orient) -> Self {
        match *orient {
            Orient::Camera => OrientIr::Camera,
            Orient::FaceCamera => OrientIr::FaceCamera,
            Orient::Velocity {
                stretch,
                max_length,
            } => OrientIr::Velocity {
                stretch,
                max_length,
            },
            Orient::Fixed(n) => {
                let normal = n.d().normalize_or_zero();
                // The camera's rule for "up": Y, unless the normal is (nearly) along Y.
                let reference = if normal.cross(DVec3::Y).length_squared() < 1e-6 {
                    DVec3::Z
                } else {
                    DVec3::Y
                };
                let right = reference.cross(normal).normalize_or_zero();
                OrientIr::Fixed {
                    right,
                    up: normal.cross(right),
                }
            }
        }
    }

    /// The variant's name as the effect file spells it.
    pub fn name(&self) -> &'static str {
        match self {
            OrientIr::Camera => "Camera",
            OrientIr::Velocity { .. } => "Velocity",
            OrientIr::Fixed { .. } => "Fixed",
            OrientIr::FaceCamera => "FaceCamera",
        }
    }

    /// Whether placing the quad reads the particle's velocity.
    pub(crate) fn needs_velocity(&self) -> bool {
        matches!(self, OrientIr::Velocity { .. })
    }

    /// The f64 twin of `emit_half_axes`: the world-space half axes of a sprite of
    /// width `size` and height `height` (for `Velocity`: its length before stretching) moving
    /// at `velocity`, `to_eye` from the camera's eye, for a camera whose unit right and up
    /// vectors (in world space) are `camera_right` and `camera_up`.
    pub fn half_axes(
        &self,
        (size, height): (f64, f64),
        (velocity, to_eye): (DVec3, DVec3),
        camera_right: DVec3,
        camera_up: DVec3,
    ) -> (DVec3, DVec3) {
        let half = 0.5 * size;
        match *self {
            OrientIr::Camera => (camera_right * half, camera_up * (0.5 * height)),
            OrientIr::FaceCamera => {
                let d2 = to_eye.length_squared();
                if d2 <= FACING_FLOOR2 {
                    return (camera_right * half, camera_up * (0.5 * height));
                }
                let normal = to_eye / d2.sqrt();
                let across = camera_up.cross(normal);
                let a2 = across.length_squared();
                let right = match a2 > FACING_FLOOR2 {
                    true => across / a2.sqrt(),
                    false => camera_right,
                };
                (right * half, normal.cross(right) * (0.5 * height))
            }
            OrientIr::Velocity {
                stretch,
                max_length,
            } => {
                let (vx, vy) = (velocity.dot(camera_right), velocity.dot(camera_up));
                let speed2 = vx * vx + vy * vy;
                let (speed, along) = if speed2 > STILL_SPEED2 {
                    let s = speed2.sqrt();
                    (s, (vx / s, vy / s))
                } else {
                    (0.0, (0.0, 1.0))
                };
                let length = velocity_length(height, speed, stretch, max_length);
                let x = camera_right * along.1 - camera_up * along.0;
                let y = camera_right * along.0 + camera_up * along.1;
                (x * half, y * (0.5 * length))
            }
            OrientIr::Fixed { right, up } => (right * half, up * (0.5 * height)),
        }
    }

    /// WGSL lines that set `s.half_x` and `s.half_y` (view space, vec3) from `s.size` (the
    /// width), the WGSL expression `height` and, for `Velocity`, a world-space
    /// `vel: vec3<f32>` in scope.
    pub(crate) fn emit_half_axes(&self, w: &mut Writer, height: &str) {
        match *self {
            OrientIr::FaceCamera => {
                let floor = f32_lit(FACING_FLOOR2);
                w.comment("Facing the eye, at the view's origin: the normal towards it, x level.");
                w.line("let to_eye = -s.center.xyz;");
                w.line("let d2 = dot(to_eye, to_eye);");
                w.line("var right = vec3<f32>(1.0, 0.0, 0.0);");
                w.line("var up = vec3<f32>(0.0, 1.0, 0.0);");
                w.block(format!("if (d2 > {floor})"), |w| {
                    w.line("let normal = to_eye * inverseSqrt(d2);");
                    w.line("let across = cross(vec3<f32>(0.0, 1.0, 0.0), normal);");
                    w.line("let a2 = dot(across, across);");
                    w.block(format!("if (a2 > {floor})"), |w| {
                        w.line("right = across * inverseSqrt(a2);");
                    });
                    w.line("up = cross(normal, right);");
                });
                w.line("s.half_x = right * (0.5 * s.size);");
                w.line(format!("s.half_y = up * (0.5 * {height});"));
            }
            OrientIr::Camera => {
                w.line("s.half_x = vec3<f32>(0.5 * s.size, 0.0, 0.0);");
                w.line(format!("s.half_y = vec3<f32>(0.0, 0.5 * {height}, 0.0);"));
            }
            OrientIr::Velocity {
                stretch,
                max_length,
            } => {
                w.comment("The velocity's image-plane part (view x, y): its direction and speed.");
                w.line("let vv = (draw.view * vec4<f32>(vel, 0.0)).xy;");
                w.line("let speed2 = dot(vv, vv);");
                w.line("var along = vec2<f32>(0.0, 1.0);");
                w.line("var speed = 0.0;");
                w.block(format!("if (speed2 > {})", f32_lit(STILL_SPEED2)), |w| {
                    w.line("speed = sqrt(speed2);");
                    w.line("along = vv / speed;");
                });
                w.line(format!(
                    "let len = max({height}, min({height} + {} * speed, {}));",
                    f32_lit(stretch),
                    f32_lit(max_length)
                ));
                w.line("s.half_x = vec3<f32>(along.y, -along.x, 0.0) * (0.5 * s.size);");
                w.line("s.half_y = vec3<f32>(along, 0.0) * (0.5 * len);");
            }
            OrientIr::Fixed { right, up } => {
                let v = |d: DVec3| {
                    format!(
                        "vec4<f32>({}, {}, {}, 0.0)",
                        f32_lit(d.x),
                        f32_lit(d.y),
                        f32_lit(d.z)
                    )
                };
                w.comment("The fixed plane's axes, turned into view space.");
                w.line(format!(
                    "s.half_x = (draw.view * {}).xyz * (0.5 * s.size);",
                    v(right)
                ));
                w.line(format!(
                    "s.half_y = (draw.view * {}).xyz * (0.5 * {height});",
                    v(up)
                ));
            }
        }
    }
}

/// A velocity-aligned sprite's length: the size plus `stretch` per m/s, capped at
/// `max_length`, never shorter than the size.
pub(crate) fn velocity_length(size: f64, speed: f64, stretch: f64, max_length: f64) -> f64 {
    size.max((size + stretch * speed).min(max_length))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::values::Vec3;

    #[test]
    fn fixed_axes_are_unit_and_span_the_plane() {
        for n in [
            Vec3(0.0, 1.0, 0.0),
            Vec3(0.0, 0.0, 2.0),
            Vec3(1.0, -1.0, 0.5),
        ] {
            let OrientIr::Fixed { right, up } = OrientIr::lower(&Orient::Fixed(n)) else {
                panic!("not fixed");
            };
            let normal = n.d().normalize();
            assert!((right.length() - 1.0).abs() < 1e-12 && (up.length() - 1.0).abs() < 1e-12);
            assert!(right.dot(normal).abs() < 1e-12 && up.dot(normal).abs() < 1e-12);
            assert!((right.cross(up) - normal).length() < 1e-12);
        }
    }

    #[test]
    fn a_velocity_sprite_stretches_along_the_image_plane_velocity_within_its_limits() {
        let o = OrientIr::lower(&Orient::Velocity {
            stretch: 0.1,
            max_length: 1.0,
        });
        let (right, up) = (DVec3::X, DVec3::Y);
        // Moving right at 4 m/s: 0.2 + 0.4 = 0.6 long along x, 0.2 wide along y.
        let (x, y) = o.half_axes(
            (0.2, 0.2),
            (DVec3::new(4.0, 0.0, -7.0), DVec3::Z),
            right,
            up,
        );
        assert!((y - DVec3::new(0.3, 0.0, 0.0)).length() < 1e-12, "{y}");
        assert!((x - DVec3::new(0.0, -0.1, 0.0)).length() < 1e-12, "{x}");
        // Fast: capped at max_length; towards the camera only: no direction, no stretch.
        let (_, y) = o.half_axes(
            (0.2, 0.2),
            (DVec3::new(0.0, 100.0, 0.0), DVec3::Z),
            right,
            up,
        );
        assert!((y.length() - 0.5).abs() < 1e-12);
        let (x, y) = o.half_axes((0.2, 0.2), (DVec3::new(0.0, 0.0, 5.0), DVec3::Z), right, up);
        assert_eq!(
            (x, y),
            (DVec3::new(0.1, 0.0, 0.0), DVec3::new(0.0, 0.1, 0.0))
        );
        // A cap below the size never shrinks the sprite.
        assert_eq!(velocity_length(0.5, 10.0, 1.0, 0.1), 0.5);
        // A height of its own is the length before stretching; the width stays the size.
        let (x, y) = o.half_axes(
            (0.2, 0.4),
            (DVec3::new(4.0, 0.0, -7.0), DVec3::Z),
            right,
            up,
        );
        assert!((y - DVec3::new(0.4, 0.0, 0.0)).length() < 1e-12, "{y}");
        assert!((x - DVec3::new(0.0, -0.1, 0.0)).length() < 1e-12, "{x}");
    }

    #[test]
    fn a_sprite_facing_the_camera_turns_its_normal_to_the_eye() {
        let o = OrientIr::FaceCamera;
        // Straight ahead it is the Camera quad; off to the right it turns about the up axis.
        let (x, y) = o.half_axes(
            (0.2, 0.4),
            (DVec3::ZERO, DVec3::Z * 5.0),
            DVec3::X,
            DVec3::Y,
        );
        assert!((x - DVec3::X * 0.1).length() < 1e-12 && (y - DVec3::Y * 0.2).length() < 1e-12);
        let to_eye = DVec3::new(-3.0, 0.0, 4.0);
        let (x, y) = o.half_axes((0.2, 0.4), (DVec3::ZERO, to_eye), DVec3::X, DVec3::Y);
        assert!(x.dot(to_eye).abs() < 1e-12 && y.dot(to_eye).abs() < 1e-12);
        assert!((x.length() - 0.1).abs() < 1e-12 && (y - DVec3::Y * 0.2).length() < 1e-12);
        assert!(x.cross(y).dot(to_eye) > 0.0, "its front faces the eye");
        // At the eye, or straight above it: no NaN, the camera's axes.
        for to_eye in [DVec3::ZERO, DVec3::Y * 3.0] {
            let (x, y) = o.half_axes((0.2, 0.2), (DVec3::ZERO, to_eye), DVec3::X, DVec3::Y);
            assert!(x.is_finite() && y.is_finite() && (x - DVec3::X * 0.1).length() < 1e-12);
        }
    }

    #[test]
    fn width_and_height_span_the_two_axes() {
        let n = Vec3(0.0, 1.0, 0.0);
        for o in [OrientIr::Camera, OrientIr::lower(&Orient::Fixed(n))] {
            let (right, up) = match o {
                OrientIr::Fixed { right, up } => (right, up),
                _ => (DVec3::X, DVec3::Y),
            };
            let (x, y) = o.half_axes((0.2, 0.6), (DVec3::ZERO, DVec3::Z), DVec3::X, DVec3::Y);
            assert!((x - right * 0.1).length() < 1e-12 && (y - up * 0.3).length() < 1e-12);
        }
    }
}
