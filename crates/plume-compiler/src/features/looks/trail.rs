//! Trails (`render.trail`). This module owns the option end to end: its lowered form, the
//! update's line that records a sample into the ring buffer, which ring entries the draw reads
//! (the same arithmetic for the WGSL and its CPU twin, [`TrailIr::window`]), and the f64
//! reference's history (`History`).
//!
//! The update of step `s` records the particle's position at the step's start (time s · dt)
//! when `s` is a multiple of `every`: sample k = s / every goes to ring entry k mod R, where
//! R = points − 1, with the particle's id + 1 beside it. A slot's R entries are consecutive
//! (entry r of slot i at i · R + r), so the draw reads one ribbon's points from a cache line or
//! two, while the update's stores land 16 · R bytes apart. Laid out entry-major instead (one
//! step's samples consecutive, the stores coalesced), the update was slightly cheaper but the
//! draw's vertex stage far slower, as each ribbon's points then lie a step's samples apart
//! (docs/performance.md, "Trails").
//!
//! The draw joins the particle's position now and its samples newest first; an entry whose id
//! is not the particle's (a slot's earlier occupant, or never written: 0) is not part of its
//! trail, so a young particle's ribbon is shorter and no spawn has to clear the ring.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::{default_colors, ColorStop, SizeStop};
use crate::base::writer::{u32_lit, Writer};
use serde::Deserialize;

/// Trails (`render.trail`): a camera-facing ribbon through each particle's position now and
/// its `points - 1` most recent samples, taken every `every` steps. The samples live in a ring
/// buffer the update writes, so an effect with a trail keeps 16 bytes per past position per
/// particle more state, and is stateful.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trail {
    /// Positions the ribbon joins, the particle's own included (2 to 64).
    #[serde(default = "default_trail_points")]
    pub points: u32,
    /// Steps between two samples (1: every step).
    #[serde(default = "default_trail_every")]
    pub every: u32,
    /// Ribbon width (m) along the trail, `(t, width)`: t = 0 at the particle, 1 at the tail.
    #[serde(default = "default_trail_width")]
    pub(crate) width: Vec<SizeStop>,
    /// Colour along the trail, `(t, (r, g, b, a))`, multiplying the particle's own colour.
    #[serde(default = "default_colors")]
    pub(crate) color: Vec<ColorStop>,
}

impl Trail {
    /// Its checks: 2 to 64 points, every at least 1 step, and its width and colour curves.
    pub(crate) fn check(&self, c: &mut Checker, path: &ValuePath) {
        // 64 points keep a ribbon's vertex count (128) and its history (1 KiB) bounded.
        if !(2..=64).contains(&self.points) {
            c.error(
                &path.field("points"),
                format!(
                    "must be 2 to 64 (the particle and up to 63 past positions), got {}",
                    self.points
                ),
            );
        }
        if self.every == 0 {
            c.error(&path.field("every"), "must be at least 1 step");
        }
        super::check_sizes(c, &path.field("width"), &self.width, "width");
        super::check_colors(c, &path.field("color"), &self.color);
    }
}

fn default_trail_points() -> u32 {
    16
}

fn default_trail_every() -> u32 {
    1
}

fn default_trail_width() -> Vec<SizeStop> {
    vec![SizeStop(0.0, 0.05), SizeStop(1.0, 0.0)]
}

/// The f64 twin of how a strip's vertices are placed, by the trail module and by a ribbon's
/// `vs_ribbon` alike: for each of `points` its two vertices (side −1, then +1), `half(j)` to
/// either side across the strip's direction there (from the point before to the point after,
/// the point itself at an end) and the line of sight from `eye`; a point with no direction
/// gets both vertices on it.
pub fn strip_sides(points: &[DVec3], eye: DVec3, half: &dyn Fn(usize) -> f64) -> Vec<[DVec3; 2]> {
    let last = points.len().saturating_sub(1);
    (0..points.len())
        .map(|j| {
            let here = points[j];
            let along = points[j.saturating_sub(1)] - points[(j + 1).min(last)];
            // In view space the GPU crosses the direction with the point's position from the
            // eye; a rotation keeps cross products, so world space gives the same axis.
            let side = along.cross(here - eye);
            let len2 = side.length_squared();
            let offset = if len2 > 1e-30 {
                side * (half(j) / len2.sqrt())
            } else {
                DVec3::ZERO
            };
            [here - offset, here + offset]
        })
        .collect()
}

/// The unit normal of a lit trail's strip at each of `points` (as [`strip_sides`] places them,
/// seen from `eye`): the strip is a flat card, its normal the way to the eye made square to the
/// strip's direction there; zero where the strip has no direction or runs along the line of
/// sight. The f64 twin of the trail module's lighting.
pub fn strip_normals(points: &[DVec3], eye: DVec3) -> Vec<DVec3> {
    let last = points.len().saturating_sub(1);
    (0..points.len())
        .map(|j| {
            let along = points[j.saturating_sub(1)] - points[(j + 1).min(last)];
            let e = eye - points[j];
            let facing = e - along * (e.dot(along) / along.length_squared().max(1e-30));
            facing.normalize_or_zero()
        })
        .collect()
}

/// Bytes of one ring entry: the position's three f32 bit patterns and the id + 1.
pub(crate) const ENTRY_BYTES: u32 = 16;

/// A trail, lowered.
#[derive(Clone, Debug, PartialEq)]
pub struct TrailIr {
    /// Positions the ribbon joins, the particle's own included (2 to 64).
    pub points: u32,
    /// Steps between two samples (at least 1).
    pub every: u32,
    /// Width stops (t, m) along the trail: t = 0 at the particle, 1 at the tail.
    pub width: Vec<(f64, f64)>,
    /// Colour stops (t, rgba) multiplying the particle's colour along the trail.
    pub color: Vec<(f64, [f64; 4])>,
}

impl TrailIr {
    /// Lowers the schema's trail.
    pub fn lower(t: &Trail) -> Self {
        Self {
            points: t.points,
            every: t.every,
            width: t.width.iter().map(|s| (s.0, s.1)).collect(),
            color: t
                .color
                .iter()
                .map(|s| (s.0, [s.1 .0, s.1 .1, s.1 .2, s.1 .3]))
                .collect(),
        }
    }

    /// Past samples each particle keeps: the ring's length, `points − 1`.
    pub fn ring(&self) -> u32 {
        self.points - 1
    }

    /// Bytes of history per particle.
    pub fn bytes_per_particle(&self) -> u32 {
        ENTRY_BYTES * self.ring()
    }

    /// Whether the update of step `step` records the position at its start.
    pub(crate) fn samples_at(&self, step: u64) -> bool {
        step.is_multiple_of(u64::from(self.every))
    }

    /// The ring entry of sample `k`.
    pub fn entry(&self, k: u64) -> u64 {
        k % u64::from(self.ring())
    }

    /// The samples the ring holds after `steps` steps, newest first: the draw's points 1, 2,
    /// ... as (sample index, ring entry). Empty before the first sample.
    pub fn window(&self, steps: u64) -> impl Iterator<Item = (u64, u64)> + '_ {
        let newest = steps.checked_sub(1).map(|s| s / u64::from(self.every));
        let count = newest.map_or(0, |m| (m + 1).min(u64::from(self.ring())));
        (0..count).map(move |j| {
            let k = newest.unwrap_or(0) - j;
            (k, self.entry(k))
        })
    }

    /// The ribbon's width (m) at trail fraction `t`.
    pub(crate) fn width_at(&self, t: f64) -> f64 {
        let stops: Vec<(f64, [f64; 1])> = self.width.iter().map(|&(t, w)| (t, [w])).collect();
        crate::base::values::interpolate(&stops, t)[0]
    }

    /// The colour factor at trail fraction `t`.
    pub fn color_at(&self, t: f64) -> [f64; 4] {
        crate::base::values::interpolate(&self.color, t)
    }

    /// The f64 twin of the trail module's vertex placement: for each of a ribbon's `points`
    /// (the particle now, then its samples newest first), its two vertices (side −1, then
    /// +1), half the width at its trail fraction (times `size_scale`) to either side across
    /// the trail's direction there and the line of sight from `eye`; a point with no direction
    /// gets both vertices on it.
    pub fn strip_vertices(&self, points: &[DVec3], eye: DVec3, size_scale: f64) -> Vec<[DVec3; 2]> {
        strip_sides(points, eye, &|j| {
            0.5 * self.width_at(j as f64 / f64::from(self.ring())) * size_scale
        })
    }

    /// Emits the update's record of the position `x` at the step's start into the ring
    /// (`trail`, binding 16) for particle `p` in chunk slot `i`.
    pub(crate) fn emit_record(&self, w: &mut Writer) {
        let ring = u32_lit(self.ring());
        w.comment("Trail: the position at this step's start into the ring (render.trail).");
        let store = |w: &mut Writer, sample: &str| {
            w.line(format!(
                "trail[i * {ring} + {sample} % {ring}] = vec4<u32>(bitcast<vec3<u32>>(x), p.id + 1u);"
            ));
        };
        if self.every == 1 {
            store(w, "params.step");
        } else {
            let every = u32_lit(self.every);
            w.block(format!("if (params.step % {every} == 0u)"), |w| {
                store(w, &format!("(params.step / {every})"))
            });
        }
    }
}

/// One particle's recorded samples in the f64 reference, newest first: the CPU twin of its
/// ring entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct History {
    samples: Vec<DVec3>,
}

impl History {
    /// Records the position at the start of step `step`, if the trail samples it.
    pub(crate) fn record(&mut self, trail: &TrailIr, step: u64, x: DVec3) {
        if trail.samples_at(step) {
            self.samples.insert(0, x);
            self.samples.truncate(trail.ring() as usize);
        }
    }

    /// The ribbon's points: `now`, then the samples newest first.
    pub(crate) fn ribbon(&self, now: DVec3) -> Vec<DVec3> {
        std::iter::once(now)
            .chain(self.samples.iter().copied())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trail(points: u32, every: u32) -> TrailIr {
        TrailIr {
            points,
            every,
            width: vec![(0.0, 0.1)],
            color: vec![(0.0, [1.0; 4])],
        }
    }

    #[test]
    fn the_window_lists_the_samples_the_ring_still_holds() {
        let t = trail(4, 2);
        // Samples at the starts of steps 0, 2, 4, ...: after 5 steps, samples 2, 1, 0.
        assert_eq!(t.window(0).count(), 0);
        assert_eq!(t.window(1).collect::<Vec<_>>(), [(0, 0)]);
        assert_eq!(t.window(5).collect::<Vec<_>>(), [(2, 2), (1, 1), (0, 0)]);
        // After 9 steps, samples 4, 3, 2 (ring of 3: entries 1, 0, 2).
        assert_eq!(t.window(9).collect::<Vec<_>>(), [(4, 1), (3, 0), (2, 2)]);
    }

    #[test]
    fn the_history_keeps_the_newest_samples_at_the_trail_spacing() {
        let t = trail(3, 2);
        let mut h = History::default();
        for step in 0..7u64 {
            h.record(&t, step, DVec3::splat(step as f64));
        }
        // Steps 0, 2, 4, 6 sampled; the ring keeps 2.
        let now = DVec3::splat(7.0);
        assert_eq!(
            h.ribbon(now),
            [now, DVec3::splat(6.0), DVec3::splat(4.0)].to_vec()
        );
        // The history and the window agree on how many samples there are.
        assert_eq!(t.window(7).count(), 2);
    }

    #[test]
    fn strip_vertices_lie_across_the_trail_and_the_line_of_sight() {
        let t = trail(3, 1);
        // A trail along +x seen from +z: the ribbon spans y, 0.1 m wide at every point.
        let eye = DVec3::new(0.0, 0.0, 10.0);
        let points = [DVec3::new(2.0, 0.0, 0.0), DVec3::X, DVec3::ZERO];
        let v = t.strip_vertices(&points, eye, 1.0);
        for (j, [a, b]) in v.iter().enumerate() {
            assert!(((*a - *b).length() - 0.1).abs() < 1e-12, "point {j}");
            assert!(((*a + *b) * 0.5 - points[j]).length() < 1e-12);
            assert!((*a - *b).normalize().abs().y > 1.0 - 1e-12);
        }
        // A trail that has not moved draws nothing.
        let still = t.strip_vertices(&[DVec3::ONE; 3], eye, 1.0);
        assert!(still.iter().all(|[a, b]| a == b));
    }

    #[test]
    fn width_and_colour_interpolate_along_the_trail() {
        let t = TrailIr {
            points: 8,
            every: 1,
            width: vec![(0.0, 0.2), (1.0, 0.0)],
            color: vec![(0.0, [1.0, 1.0, 1.0, 1.0]), (1.0, [1.0, 0.0, 0.0, 0.0])],
        };
        assert!((t.width_at(0.25) - 0.15).abs() < 1e-12);
        assert_eq!(t.color_at(0.5), [1.0, 0.5, 0.5, 0.5]);
        assert_eq!(t.bytes_per_particle(), 7 * 16);
    }
}
