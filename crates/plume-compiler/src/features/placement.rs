//! Placement: an effect set in a host's world by a transform given at run time, so that its
//! particles stay where they were emitted while the emitter moves on (world space, as a game
//! engine's moving torch or rocket needs). Emitters spawn through the transform: positions by
//! the whole affine map, velocities by its linear part; forces, colliders and kill volumes
//! stay in world coordinates, and event children spawn at their parents' (already placed)
//! positions.
//!
//! Only an effect compiled with `CompileOptions::placed` carries it: its step parameters gain
//! the transform's three rows after their header, and its spawn kernel applies them. Every
//! other effect's WGSL is unchanged. A placed effect is never stateless: its particles'
//! starting points depend on where the emitter was, which no closed form of (id, age) knows.
//!
//! The f64 twin is [`Placement::point`] and [`Placement::vector`], which the reference
//! simulator applies to the same f32 rows the GPU reads.

use glam::DVec3;

use crate::base::writer::Writer;

/// An affine transform as three rows of a 3x4 matrix: `p' = R p + t` with row `i` holding
/// `(R[i][0], R[i][1], R[i][2], t[i])`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The rows, in f32 as the GPU reads them.
    pub rows: [[f32; 4]; 3],
}

impl Default for Placement {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Placement {
    /// No transform: the effect's own coordinates are the world's.
    pub const IDENTITY: Self = Self {
        rows: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
    };

    /// The transform of a column-major 4x4 matrix (its last row, assumed (0, 0, 0, 1), is
    /// ignored), or None when any entry is not finite.
    pub fn from_cols(cols: [f32; 16]) -> Option<Self> {
        if cols.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let at = |row: usize, col: usize| cols[col * 4 + row];
        Some(Self {
            rows: [0, 1, 2].map(|r| [at(r, 0), at(r, 1), at(r, 2), at(r, 3)]),
        })
    }

    /// The rows as the step parameters hold them: 12 little-endian f32 words.
    pub fn words(&self) -> [u32; 12] {
        let mut out = [0u32; 12];
        for (i, x) in self.rows.iter().flatten().enumerate() {
            out[i] = x.to_bits();
        }
        out
    }

    /// Where point `p` of the effect's space lands in the world (f64 over the f32 rows).
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.vector(p) + DVec3::from_array([0, 1, 2].map(|r| f64::from(self.rows[r][3])))
    }

    /// Vector `v` of the effect's space in the world (the linear part only).
    pub fn vector(&self, v: DVec3) -> DVec3 {
        DVec3::from_array([0, 1, 2].map(|r| {
            let row = self.rows[r].map(f64::from);
            row[0] * v.x + row[1] * v.y + row[2] * v.z
        }))
    }
}

/// Emits the step parameters' field (after the header's four words).
pub(crate) fn emit_params_field(w: &mut Writer) {
    w.line("placement: array<vec4<f32>, 3>,");
}

/// Emits the placement of the spawned `Spawned` named `s`: its position through the whole
/// transform, its velocity through the linear part (the f32 twin of [`Placement::point`] and
/// [`Placement::vector`]).
pub(crate) fn emit_apply(w: &mut Writer) {
    w.comment("Placed in the host's world (world space): position by the transform, velocity by its linear part.");
    w.line("let row0 = params.placement[0];");
    w.line("let row1 = params.placement[1];");
    w.line("let row2 = params.placement[2];");
    w.line("s.x = vec3<f32>(dot(row0.xyz, s.x) + row0.w, dot(row1.xyz, s.x) + row1.w, dot(row2.xyz, s.x) + row2.w);");
    w.line("s.v = vec3<f32>(dot(row0.xyz, s.v), dot(row1.xyz, s.v), dot(row2.xyz, s.v));");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_translation_and_a_quarter_turn_place_points_and_vectors() {
        // Column-major: a quarter turn about +y (x -> -z, z -> x), then a move by (1, 2, 3).
        let cols = [
            0.0, 0.0, -1.0, 0.0, //
            0.0, 1.0, 0.0, 0.0, //
            1.0, 0.0, 0.0, 0.0, //
            1.0, 2.0, 3.0, 1.0,
        ];
        let p = Placement::from_cols(cols).unwrap();
        assert_eq!(p.point(DVec3::X), DVec3::new(1.0, 2.0, 2.0));
        assert_eq!(p.vector(DVec3::X), DVec3::new(0.0, 0.0, -1.0));
        assert_eq!(Placement::IDENTITY.point(DVec3::ONE), DVec3::ONE);
        let mut bad = cols;
        bad[5] = f32::NAN;
        assert_eq!(Placement::from_cols(bad), None);
    }
}
