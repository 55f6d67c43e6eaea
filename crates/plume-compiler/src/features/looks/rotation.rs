//! Sprite rotation and spin (`render.rotation`). This module owns the option end to end: its
//! lowered form, the WGSL that turns the quad in the draw module's `sprite_at` and the f64 twin
//! the reference drawing turns its quads with.
//!
//! Each particle draws a starting angle and a spin (both uniform in their ranges, from its id:
//! streams `ROTATION_ANGLE` and `ROTATION_SPIN`); at an age of `lived`
//! whole steps its quad is turned by angle + spin · lived · dt within its own plane,
//! counter-clockwise from half_x towards half_y (as the camera sees it for `Camera`; about the
//! normal, right-handed, for `Fixed`). A round untextured dot looks the same at every angle:
//! rotation shows with a texture.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::{rand_u32, stream, unit};
use crate::base::values::Range;
use crate::base::writer::{f32_lit, Writer};
use serde::Deserialize;

/// Sprite rotation (`render.rotation`): each particle draws a starting angle and a spin from
/// its id, uniform in the ranges.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Starting angle range (degrees, counter-clockwise).
    #[serde(default)]
    pub angle: Range,
    /// Spin range (degrees per second, counter-clockwise).
    #[serde(default)]
    pub spin: Range,
}

impl Rotation {
    /// Checks the angle and spin ranges, and that the sprite's direction is its own to turn
    /// (not `orient`'s: a streak along its velocity cannot turn); `path` names
    /// `render.rotation`.
    pub(crate) fn check(
        &self,
        path: &ValuePath,
        orient: crate::features::looks::orient::Orient,
        c: &mut Checker,
    ) {
        c.range(&path.field("angle"), self.angle);
        c.range(&path.field("spin"), self.spin);
        if let crate::features::looks::orient::Orient::Velocity { .. } = orient {
            c.error(
                path,
                "cannot turn a sprite whose direction render.orient: Velocity sets; use Camera or Fixed orientation, or leave rotation out",
            );
        }
    }
}

/// Rotation, lowered to radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationIr {
    /// Starting angle range (rad).
    pub angle: (f64, f64),
    /// Spin range (rad/s).
    pub spin: (f64, f64),
}

impl RotationIr {
    /// Lowers the schema's degrees to radians.
    pub fn lower(r: &Rotation) -> Self {
        Self {
            angle: (r.angle.0.to_radians(), r.angle.1.to_radians()),
            spin: (r.spin.0.to_radians(), r.spin.1.to_radians()),
        }
    }

    /// Whether the angle changes with age (so the draw needs every particle's age).
    pub(crate) fn spins(&self) -> bool {
        self.spin != (0.0, 0.0)
    }

    /// The angle (rad) of particle `id` (of an effect whose seed mixes to `seed_mix`) after
    /// `lived` whole steps of `dt` seconds: the f64 twin of `sprite_angle`.
    pub fn angle(&self, id: u32, seed_mix: u32, lived: u64, dt: f64) -> f64 {
        let draw = |range: (f64, f64), s: u32| {
            range.0 + (range.1 - range.0) * unit(rand_u32(seed_mix, id, s))
        };
        let start = draw(self.angle, stream::ROTATION_ANGLE);
        let spin = draw(self.spin, stream::ROTATION_SPIN);
        start + spin * (lived as f64 * dt)
    }

    /// Turns half axes `(x, y)` by `angle` within their plane: the f64 twin of the WGSL lines.
    pub fn turn(x: DVec3, y: DVec3, angle: f64) -> (DVec3, DVec3) {
        let (s, c) = angle.sin_cos();
        (x * c + y * s, y * c - x * s)
    }

    /// Emits `sprite_angle(id, lived)`: the angle (rad) of particle `id` after `lived` whole
    /// steps, as [`Self::angle`]. The spin's part is reduced to whole turns first, so that the
    /// f32 sine of an old, fast-spinning particle stays accurate.
    pub(crate) fn emit_angle_fn(&self, w: &mut Writer, dt: f64) {
        let tau = std::f64::consts::TAU;
        w.block("fn sprite_angle(id: u32, lived: u32) -> f32", |w| {
            w.line(format!(
                "let start = {} + {} * rand_unit(id, {}u);",
                f32_lit(self.angle.0),
                f32_lit(self.angle.1 - self.angle.0),
                stream::ROTATION_ANGLE
            ));
            if !self.spins() {
                w.line("return start;");
                return;
            }
            w.comment("Turns per step, then the fraction of a turn this age has reached.");
            w.line(format!(
                "let spin = ({} + {} * rand_unit(id, {}u)) * {};",
                f32_lit(self.spin.0),
                f32_lit(self.spin.1 - self.spin.0),
                stream::ROTATION_SPIN,
                f32_lit(dt / tau)
            ));
            w.line("let turns = f32(lived) * spin;");
            w.line(format!(
                "return start + (turns - trunc(turns)) * {};",
                f32_lit(tau)
            ));
        });
    }

    /// WGSL lines that turn `s.half_x` and `s.half_y` by `angle: f32` in scope.
    pub(crate) fn emit_turn(w: &mut Writer) {
        w.comment(
            "Turned within the sprite's plane, from half_x towards half_y (render.rotation).",
        );
        w.line("let cs = cos(angle);");
        w.line("let sn = sin(angle);");
        w.line("let hx = s.half_x;");
        w.line("s.half_x = hx * cs + s.half_y * sn;");
        w.line("s.half_y = s.half_y * cs - hx * sn;");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_by_a_quarter_maps_x_to_y_and_y_to_minus_x() {
        let (x, y) = RotationIr::turn(DVec3::X, DVec3::Y, std::f64::consts::FRAC_PI_2);
        assert!((x - DVec3::Y).length() < 1e-12 && (y + DVec3::X).length() < 1e-12);
    }

    #[test]
    fn angles_start_in_their_range_and_grow_with_the_spin() {
        let r = RotationIr::lower(&Rotation {
            angle: crate::base::values::Range(10.0, 20.0),
            spin: crate::base::values::Range(90.0, 90.0),
        });
        for id in 0..100 {
            let a0 = r.angle(id, 5, 0, 0.1).to_degrees();
            assert!((10.0..=20.0).contains(&a0), "{a0}");
            // 90 degrees a second: 9 per 0.1 s step.
            let a3 = r.angle(id, 5, 3, 0.1).to_degrees();
            assert!((a3 - a0 - 27.0).abs() < 1e-9);
        }
    }
}
