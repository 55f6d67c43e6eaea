//! Flocking (the GPUBoids seed, after Reynolds): forces between particles.
//!
//! For boid i with position x and velocity v, over every other live boid j with d = x - x_j,
//! r = |d| < radius, w = 1 - r / radius and core = radius / 10:
//!
//! ```text
//! separation: a += separation · w · d / max(r, core)
//! avoidance:  ahead = max(0, -d · v̂) / max(r, core)    (v̂ = v / |v|; none when |v| <= 1e-6)
//!             s = d - (d · v̂) v̂,  a += avoidance · w · ahead · s / max(|s|, core)
//! cohesion:   a += cohesion · (Σ w_j (x_j - x)) / max(Σ w_j, 1)
//! alignment:  a += alignment · (Σ w_j (v_j - v)) / max(Σ w_j, 1)
//! ```
//! Cohesion and alignment above are the Local scope: a w-weighted mean of the neighbours,
//! faded in while the neighbourhood is sparse (Σ w < 1). Global uses the plain mean of all live
//! boids (weight 1 each, itself included) instead. Every term is continuous in the positions: a
//! neighbour enters or leaves the radius, or passes from ahead to beside, with zero weight, so
//! the flock has no force jumps for f32 and f64 to decide differently.
//!
//! Separation, avoidance and the means are computed once per step, at its start, from a
//! snapshot of every boid taken after the step's spawns: one all-pairs pass over
//! workgroup-shared tiles (the seed's N² force splatting) or a uniform grid. Cohesion and
//! alignment then act on the boid's own live x and v inside the integrator, so their
//! stiffness (a spring of ω² = cohesion, a damping of rate alignment) has each integrator's
//! usual limits; separation and avoidance are held for the step.

use glam::DVec3;
use serde::Deserialize;

mod accumulate;
mod grid;
mod kernels;

use crate::base::check::Checker;
use crate::base::layout::Role;
use crate::base::path::ValuePath;

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &[
    "radius",
    "separation",
    "avoidance",
    "cohesion",
    "alignment",
    "scope",
    "neighbors",
];

/// Where cohesion and alignment take their averages from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Scope {
    /// Every live boid (a parallel reduction each step; the seed's mip-map average).
    #[default]
    Global,
    /// The neighbours within `radius`.
    Local,
}

/// How neighbours within `radius` are found. Both find exactly the same neighbours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub enum Neighbors {
    /// Every boid against every other, in workgroup-shared tiles.
    #[default]
    AllPairs,
    /// A uniform grid of cubic cells (`cell >= radius`), hashed into a table, searched over the
    /// 27 cells around each boid.
    Grid {
        /// Cell edge (m), at least `radius`.
        cell: f64,
    },
}

/// `Flock(...)` as written.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flock {
    /// Neighbour cutoff (m), > 0.
    pub radius: f64,
    /// Push apart (m/s²) at zero distance, fading to 0 at `radius`.
    #[serde(default)]
    pub separation: f64,
    /// Sideways steer (m/s²) away from neighbours ahead.
    #[serde(default)]
    pub avoidance: f64,
    /// Spring rate (1/s²) toward the mean position.
    #[serde(default)]
    pub cohesion: f64,
    /// Rate (1/s) toward the mean velocity.
    #[serde(default)]
    pub alignment: f64,
    /// Where the means come from.
    #[serde(default)]
    pub scope: Scope,
    /// Neighbour search.
    #[serde(default)]
    pub neighbors: Neighbors,
}

impl Flock {
    /// Checks `radius > 0`, non-negative strengths and `cell >= radius`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.positive(&path.field("radius"), self.radius);
        c.non_negative(&path.field("separation"), self.separation);
        c.non_negative(&path.field("avoidance"), self.avoidance);
        c.non_negative(&path.field("cohesion"), self.cohesion);
        c.non_negative(&path.field("alignment"), self.alignment);
        if let Neighbors::Grid { cell } = self.neighbors {
            let p = path.field("neighbors").variant("Grid").field("cell");
            if c.finite(&p, cell) && self.radius.is_finite() && cell < self.radius {
                c.error(
                    &p,
                    format!(
                        "must be >= radius ({}), got {cell}: the 27 cells around a boid must cover its radius",
                        self.radius
                    ),
                );
            }
        }
    }

    /// Lowers to the IR's flock.
    pub fn lower(&self, origin: usize) -> FlockIr {
        FlockIr {
            radius: self.radius,
            separation: self.separation,
            avoidance: self.avoidance,
            cohesion: self.cohesion,
            alignment: self.alignment,
            scope: self.scope,
            neighbors: self.neighbors,
            origin,
        }
    }
}

/// The flock in the IR.
#[derive(Clone, Debug, PartialEq)]
pub struct FlockIr {
    /// Cutoff (m).
    pub radius: f64,
    /// Separation strength (m/s²).
    pub separation: f64,
    /// Avoidance strength (m/s²).
    pub avoidance: f64,
    /// Cohesion rate (1/s²).
    pub cohesion: f64,
    /// Alignment rate (1/s).
    pub alignment: f64,
    /// Where the means come from.
    pub scope: Scope,
    /// Neighbour search.
    pub neighbors: Neighbors,
    /// Index in the file's `forces`.
    pub origin: usize,
}

/// What the per-step pass gives each boid, held for the step: the flock's acceleration on it is
/// push + cohesion (c - weight x) + alignment (vbar - weight v).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frozen {
    /// Separation + avoidance (m/s²).
    pub push: DVec3,
    /// Σ w_j x_j / max(Σ w_j, 1) (Local) or the mean position (Global).
    pub c: DVec3,
    /// Σ w_j v_j / max(Σ w_j, 1) (Local) or the mean velocity (Global).
    pub vbar: DVec3,
    /// Σ w_j / max(Σ w_j, 1) (Local), or 1 (Global, any boid alive): in [0, 1].
    pub weight: f64,
}

/// From this many boids the grid beat all pairs (effects/boids.ron at its own density), which
/// won at 2,048 and below (docs/performance.md, "Flocking").
pub const GRID_FASTER_FROM: u32 = 4096;

/// Below this capacity the grid's search splits each boid over nine threads, one row of 3
/// cells each, [`GRID_TILE`] boids a workgroup, and marks neighbours in masks before running
/// the pair function on them; from it on, one thread a boid walks all nine rows. With
/// effects/boids.ron the split search was the faster below this size and the two tie at it;
/// above it the GPU is full and nine threads' partial sums cost more than they hide
/// (docs/performance.md, "Flocking").
pub const GRID_SPLIT_BELOW: u32 = 262_144;

/// Boids per workgroup of the split search. Its threads are laid out row by row (thread t:
/// row t / TILE of boid t % TILE), so that a warp of 32 walks two rows for 16 consecutive
/// sorted boids, which lie in one or two cells and read the same candidates. 9 x 16 = 144
/// threads, under WebGPU's default limit of 256 a workgroup.
pub const GRID_TILE: u32 = 16;

/// Candidates the one-thread search loads and tests at a time, [`GRID_ONE_LOADS_PER_ROUND`]
/// times a round; a round's neighbours are marked in one mask, and the pair function runs on
/// them after its last loads. In a warp the pair loop runs as often as the busiest thread has
/// neighbours in the round, so a longer round wastes less of it; loaded 10 at a time, the
/// kernel keeps its registers (57). At 1M boids rounds of 3 x 10 beat rounds of 20 loaded at
/// once (80 registers), 2 x 16 and 4 x 8; two mask words for rounds of up to 64 and the pair
/// loop's next loads started before its pair function were slower (docs/performance.md,
/// "Flocking"; benchmarks/h100-speed/flock-batches/README.md).
pub(crate) const GRID_ONE_LOADS: u32 = 10;

/// Loads of [`GRID_ONE_LOADS`] candidates in a round of the one-thread search.
pub(crate) const GRID_ONE_LOADS_PER_ROUND: u32 = 3;

/// Sub-cells along x of each cell where the one-thread search runs (from [`GRID_SPLIT_BELOW`]):
/// a row is then 2 x 3 + 1 = 7 sub-cells, 7/3 of a cell, where a boid reaches 2 cells of it
/// (its radius either way), instead of 3 whole cells: 22% fewer candidates walked, and at 1M
/// boids a faster step than whole cells or 2 or 4 sub-cells gave. The neighbours are the same;
/// the order they are added in changes within a cell (by sub-cell, then slot), so the sums
/// round differently. Rows clipped, sub-cell by sub-cell, to the sphere of the radius (44%
/// fewer candidates than whole cells) were slower: the clipping cost more than it saved
/// (docs/performance.md, "Flocking").
pub(crate) const GRID_X_SPLIT: u32 = 3;

/// Candidates the split search loads and tests a round (one bit each in the round's mask):
/// at 16k boids as fast as 8 and faster than 32.
pub(crate) const GRID_ROUND: u32 = 16;

/// Spare entries of the sorted snapshot past its last boid, for the loads past a run (up to
/// one fewer than the longer of the two searches' loads at a time).
pub(crate) const GRID_SPARE: u32 = if GRID_ROUND > GRID_ONE_LOADS {
    GRID_ROUND
} else {
    GRID_ONE_LOADS
};

// A round's marks are the bits of one u32.
const _: () = assert!(GRID_ROUND <= 32 && GRID_ONE_LOADS * GRID_ONE_LOADS_PER_ROUND <= 32);

/// The main module's buffers that the grid's search module binds (at the layout's binding
/// numbers): the sorted snapshot, the results, the sorted order and the run starts.
pub const SEARCH_BUFFERS: [Role; 4] =
    [Role::Boids, Role::FlockOut, Role::GridVals, Role::CellStart];

/// Below this speed (m/s) a boid has no heading, so no avoidance.
pub(crate) const MIN_HEADING_SPEED: f64 = 1e-6;

impl FlockIr {
    /// The soft core (m) of separation and avoidance.
    pub fn core(&self) -> f64 {
        self.radius / 10.0
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        format!(
            "Flock radius = {} separation = {} avoidance = {} cohesion = {} alignment = {} scope = {:?} neighbors = {:?}",
            self.radius, self.separation, self.avoidance, self.cohesion, self.alignment, self.scope, self.neighbors
        )
    }

    /// Whether the grid's search of `capacity` boids runs nine threads a boid
    /// ([`GRID_SPLIT_BELOW`]).
    pub fn split_search(capacity: u32) -> bool {
        capacity < GRID_SPLIT_BELOW
    }

    /// Sub-cells along x of a grid cell for `capacity` boids: [`GRID_X_SPLIT`] where the
    /// one-thread search runs, 1 (whole cells) where the split search does.
    pub(crate) fn x_split(capacity: u32) -> u32 {
        if Self::split_search(capacity) {
            1
        } else {
            GRID_X_SPLIT
        }
    }

    /// Hash-table buckets of the grid for `capacity` boids: a power of two >= 2 x capacity, at
    /// most 2^31 (so that the count fits the shaders' u32). The boids of other rows that share
    /// a row's buckets are loaded and rejected: about one a bucket with as many buckets as
    /// boids, half as many with twice as many. At 16k boids: 681 candidates a boid against 443
    /// in its own 27 cells with as many buckets as boids, and twice as many made the step
    /// faster. At 1M boids, 2 buckets a boid shorten the search by more than they lengthen the
    /// scan (whose zeros are not written back over zeros), where one a boid was slower; 4 a
    /// boid shorten the search further but lengthen the scan as much (docs/performance.md,
    /// "Flocking").
    pub fn grid_buckets(capacity: u32) -> u64 {
        (2 * u64::from(capacity.max(1)))
            .next_power_of_two()
            .min(1 << 31)
    }

    /// The f64 reference of the per-step pass: all pairs, in id order.
    pub(crate) fn frozen(&self, boids: &[(DVec3, DVec3)]) -> Vec<Frozen> {
        let n = boids.len();
        let global = (self.scope == Scope::Global && n > 0).then(|| {
            let (sx, sv) = boids
                .iter()
                .fold((DVec3::ZERO, DVec3::ZERO), |(a, b), (x, v)| {
                    (a + *x, b + *v)
                });
            (sx / n as f64, sv / n as f64, 1.0)
        });
        boids
            .iter()
            .enumerate()
            .map(|(i, &(x, v))| {
                let mut push = DVec3::ZERO;
                let (mut sx, mut sv, mut sw) = (DVec3::ZERO, DVec3::ZERO, 0.0);
                for (j, &(xj, vj)) in boids.iter().enumerate() {
                    if j == i {
                        continue;
                    }
                    if let Some((p, w)) = self.pair(x, v, xj) {
                        push += p;
                        sx += w * xj;
                        sv += w * vj;
                        sw += w;
                    }
                }
                let (c, vbar, weight) = match self.scope {
                    Scope::Global => global.unwrap_or_default(),
                    Scope::Local => {
                        let norm = f64::max(sw, 1.0);
                        (sx / norm, sv / norm, sw / norm)
                    }
                };
                Frozen {
                    push,
                    c,
                    vbar,
                    weight,
                }
            })
            .collect()
    }

    /// Separation + avoidance on a boid at (x, v) from a neighbour at `xj`, and the neighbour's
    /// weight w = 1 - r / radius, or None when `xj` is not within the radius.
    pub fn pair(&self, x: DVec3, v: DVec3, xj: DVec3) -> Option<(DVec3, f64)> {
        let d = x - xj;
        let r = d.length();
        if r >= self.radius {
            return None;
        }
        let w = 1.0 - r / self.radius;
        let core = self.core();
        let mut a = self.separation * w * (d / r.max(core));
        let speed = v.length();
        if self.avoidance != 0.0 && speed > MIN_HEADING_SPEED {
            let heading = v / speed;
            let along = d.dot(heading);
            let ahead = (-along).max(0.0) / r.max(core);
            let side = d - along * heading;
            a += self.avoidance * w * ahead * (side / side.length().max(core));
        }
        Some((a, w))
    }

    /// The flock's acceleration on a boid at its live (x, v), given the step's frozen values.
    pub(crate) fn accel(&self, frozen: &Frozen, x: DVec3, v: DVec3) -> DVec3 {
        frozen.push
            + self.cohesion * (frozen.c - frozen.weight * x)
            + self.alignment * (frozen.vbar - frozen.weight * v)
    }
}
