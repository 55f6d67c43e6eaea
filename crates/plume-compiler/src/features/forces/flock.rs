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

use crate::base::check::Checker;
use crate::base::layout::Layout;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, u32_lit, Writer};

/// Field names, as written in effect files.
pub const FIELDS: &[&str] = &[
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
    pub fn check(&self, path: &ValuePath, c: &mut Checker) {
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

/// From this many boids the grid was measured faster than all pairs (H200, effects/boids.ron
/// at its own density: 0.418 against 0.571 ms/step at 4,096; all pairs wins at 2,048 and below;
/// docs/performance.md).
pub const GRID_FASTER_FROM: u32 = 4096;

/// Below this capacity the grid's search splits each boid over nine threads, one row of 3
/// cells each, [`GRID_TILE`] boids a workgroup, and marks neighbours in masks before running
/// the pair function on them; from it on, one thread a boid walks all nine rows and runs the
/// pair function inline. Measured on the H100 with effects/boids.ron (docs/performance.md,
/// "Flocking"), ms a step split against one thread: 0.055 against 0.059 at 16k, 0.129 against
/// 0.155 at 64k, 0.234 against 0.263 at 128k (before the PCG bucket hash); with it, 0.355
/// against 0.359 at 256k (a tie), 0.728 against 0.703 at 512k and 1.54 against 1.37 at 1M,
/// where the GPU is full and nine threads' partial sums cost more than they hide.
pub const GRID_SPLIT_BELOW: u32 = 262_144;

/// Boids per workgroup of the split search. Its threads are laid out row by row (thread t:
/// row t / TILE of boid t % TILE), so that a warp of 32 walks two rows for 16 consecutive
/// sorted boids, which lie in one or two cells and read the same candidates. 9 x 16 = 144
/// threads, under WebGPU's default limit of 256 a workgroup.
pub const GRID_TILE: u32 = 16;

/// Candidates the one-thread search loads before testing any of them (more loads in flight per
/// thread: 16k boids 0.068 against 0.064 ms a step, 1M 1.82 against 1.75 ms on the H100).
pub const GRID_ROW_UNROLL: u32 = 4;

/// Candidates the split search loads and tests a round (one bit each in the round's mask):
/// 16k boids 0.0457 ms a step, against 0.0457 with 8 and 0.0478 with 32 (H100). The sorted
/// snapshot has this many spare entries past its last boid, for the last round's loads past
/// the run.
pub const GRID_ROUND: u32 = 16;

/// The main module's buffers that the grid's search module binds (at the layout's binding
/// numbers): the sorted snapshot, the results, the sorted order and the run starts.
pub const SEARCH_BUFFERS: [&str; 4] = ["boids", "flock_out", "grid_vals", "cell_start"];

/// Below this speed (m/s) a boid has no heading, so no avoidance.
pub const MIN_HEADING_SPEED: f64 = 1e-6;

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

    /// Hash-table buckets of the grid for `capacity` boids: a power of two >= 2 x capacity,
    /// at most 2^31 (so that the count fits the shaders' u32). Twice the capacity because the
    /// boids of another row that shares a boid's buckets are loaded and rejected: at 16k boids
    /// with as many buckets as boids, 681 candidates a boid against 443 in its own 27 cells.
    /// Twice as many buckets took the step from 0.0615 to 0.0585 ms there and from 1.605 to
    /// 1.547 ms at 1M with the scan hardly slower; four times as many slowed the scan more
    /// than they sped the search up (H100, docs/performance.md, "Flocking").
    pub fn grid_buckets(capacity: u32) -> u64 {
        (2 * u64::from(capacity.max(1)))
            .next_power_of_two()
            .min(1 << 31)
    }

    /// The f64 reference of the per-step pass: all pairs, in id order.
    pub fn frozen(&self, boids: &[(DVec3, DVec3)]) -> Vec<Frozen> {
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
    pub fn accel(&self, frozen: &Frozen, x: DVec3, v: DVec3) -> DVec3 {
        frozen.push
            + self.cohesion * (frozen.c - frozen.weight * x)
            + self.alignment * (frozen.vbar - frozen.weight * v)
    }

    /// Module-scope declarations: constants, the per-invocation frozen values and the
    /// acceleration added to `accel`.
    pub fn emit_declarations(&self, w: &mut Writer, capacity: u32, workgroup: u32) {
        if let Neighbors::Grid { .. } = self.neighbors {
            w.line(format!(
                "const GRID_BUCKETS: u32 = {}; // a power of two; cell_start has one more entry",
                u32_lit(Self::grid_buckets(capacity) as u32)
            ));
        }
        if self.scope == Scope::Global {
            let groups = capacity.div_ceil(workgroup);
            w.line(format!("const FLOCK_GROUPS: u32 = {};", u32_lit(groups)));
            w.comment(
                "flock_sums: FLOCK_GROUPS partial (sum x, count), (sum v, 0) pairs, then the means.",
            );
            w.line("const FLOCK_MEAN: u32 = 2u * FLOCK_GROUPS;");
        }
        w.comment("The boid's frozen flock values for this step (zero outside `update`).");
        w.line("var<private> flock_push: vec3<f32>;");
        w.line("var<private> flock_c: vec3<f32>;");
        w.line("var<private> flock_vbar: vec3<f32>;");
        w.line("var<private> flock_weight: f32;");
        w.block(
            "fn flock_accel(x: vec3<f32>, v: vec3<f32>) -> vec3<f32>",
            |w| {
                let mut sum = vec![String::from("flock_push")];
                if self.cohesion != 0.0 {
                    sum.push(format!(
                        "{} * (flock_c - flock_weight * x)",
                        f32_lit(self.cohesion)
                    ));
                }
                if self.alignment != 0.0 {
                    sum.push(format!(
                        "{} * (flock_vbar - flock_weight * v)",
                        f32_lit(self.alignment)
                    ));
                }
                w.line(format!("return {};", sum.join(" + ")));
            },
        );
    }

    /// Statements at the start of `update` (slot `i`, single chunk) that load the frozen values.
    pub fn emit_update_prologue(&self, w: &mut Writer) {
        w.line("let fo = flock_out[3u * i];");
        w.line("flock_push = fo.xyz;");
        match self.scope {
            Scope::Global => {
                w.line("let mean_x = flock_sums[FLOCK_MEAN];");
                w.block("if (mean_x.w > 0.0)", |w| {
                    w.line("flock_c = mean_x.xyz;");
                    w.line("flock_vbar = flock_sums[FLOCK_MEAN + 1u].xyz;");
                    w.line("flock_weight = 1.0;");
                });
            }
            Scope::Local => {
                w.comment("The w-weighted neighbour means, faded in below a total weight of 1.");
                w.line("let norm = max(fo.w, 1.0);");
                w.line("flock_c = flock_out[3u * i + 1u].xyz / norm;");
                w.line("flock_vbar = flock_out[3u * i + 2u].xyz / norm;");
                w.line("flock_weight = fo.w / norm;");
            }
        }
    }

    /// The grid's search as a module of its own (None for all pairs): `flock_grid`, which
    /// reads the sorted boids (`boids`), the run starts (`cell_start`) and the sorted order
    /// (`grid_vals`) through read-only bindings and writes `flock_out`, at the bindings the
    /// effect's `layout` gives them. The main module writes those buffers, so there they must
    /// be read-write; read through read-only bindings, the same search ran 7 to 8% faster on the
    /// H100 at every size (1M boids 1.744 against 1.606 ms a step, 16k 0.0644 against 0.0616;
    /// docs/performance.md, "Flocking"), as a driver may cache loads it knows no thread writes.
    pub fn emit_search_module(&self, name: &str, capacity: u32, layout: &Layout) -> Option<String> {
        let Neighbors::Grid { cell } = self.neighbors else {
            return None;
        };
        let binding = |name: &str| {
            layout
                .bindings
                .iter()
                .find(|b| b.name == name)
                .map(|b| b.binding)
                .expect("a grid flock's layout binds the grid's buffers")
        };
        let mut w = Writer::new();
        w.comment(format!(
            "Plume effect {name:?}, the flock's grid search: generated by plume-compiler {}; do not edit.",
            env!("CARGO_PKG_VERSION")
        ));
        w.blank();
        w.line(format!(
            "const WORKGROUP: u32 = {};",
            u32_lit(crate::base::kernel::WORKGROUP)
        ));
        w.line(format!(
            "const GRID_BUCKETS: u32 = {};",
            u32_lit(Self::grid_buckets(capacity) as u32)
        ));
        w.comment("The main module's buffers, read-only here but for the results.");
        for (buffer, (access, ty)) in SEARCH_BUFFERS.into_iter().zip([
            ("read", "vec4<f32>"),
            ("read_write", "vec4<f32>"),
            ("read", "u32"),
            ("read", "u32"),
        ]) {
            w.line(format!(
                "@group(0) @binding({}) var<storage, {access}> {buffer}: array<{ty}>;",
                binding(buffer)
            ));
        }
        w.blank();
        self.emit_pair_fn(&mut w);
        w.blank();
        emit_cell_fns(&mut w, cell);
        w.blank();
        if Self::split_search(capacity) {
            emit_split_search(&mut w);
        } else {
            emit_search(&mut w);
        }
        Some(w.finish())
    }

    /// The per-step kernels: `flock_snapshot` (+ the partial sums), `flock_reduce` (Global),
    /// and the neighbour pass (`flock_pairs`, or the grid's build kernels; its search is
    /// [`Self::emit_search_module`]).
    pub fn emit_kernels(&self, w: &mut Writer, verlet_h: Option<f64>) {
        self.emit_snapshot(w, verlet_h);
        if self.scope == Scope::Global {
            w.blank();
            emit_reduce(w);
        }
        w.blank();
        match self.neighbors {
            Neighbors::AllPairs => {
                self.emit_pair_fn(w);
                w.blank();
                emit_all_pairs(w);
            }
            Neighbors::Grid { cell } => emit_grid(w, cell),
        }
    }

    fn emit_snapshot(&self, w: &mut Writer, verlet_h: Option<f64>) {
        w.comment("Slot i's (x, alive) and (v, 0) as the flock sees them this step.");
        w.block("fn boid_of(i: u32) -> array<vec4<f32>, 2>", |w| {
            w.line("let p = load_particle(i);");
            w.block("if (p.id == DEAD)", |w| {
                w.line("return array<vec4<f32>, 2>(vec4<f32>(0.0), vec4<f32>(0.0));");
            });
            let v = match verlet_h {
                Some(h) => format!("vec3<f32>(p.dx, p.dy, p.dz) * {}", f32_lit(1.0 / h)),
                None => "vec3<f32>(p.vx, p.vy, p.vz)".to_string(),
            };
            w.line(format!(
                "return array<vec4<f32>, 2>(vec4<f32>(p.px, p.py, p.pz, 1.0), vec4<f32>({v}, 0.0));"
            ));
        });
        if self.scope == Scope::Global {
            w.line("var<workgroup> red_x: array<vec4<f32>, WORKGROUP>;");
            w.line("var<workgroup> red_v: array<vec4<f32>, WORKGROUP>;");
        }
        w.comment(
            "Copies every slot's (x, alive) and (v, 0) into `boids`, and sums them per workgroup.",
        );
        w.line("@compute @workgroup_size(WORKGROUP)");
        w.block(
            "fn flock_snapshot(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
            |w| {
                crate::base::kernel::emit_thread_index(w, "i", None);
                w.line("var bx = vec4<f32>(0.0);");
                w.line("var bv = vec4<f32>(0.0);");
                w.block("if (i < chunk.len)", |w| {
                    w.line("let b = boid_of(i);");
                    w.line("bx = b[0];");
                    w.line("bv = b[1];");
                    w.line("boids[2u * i] = bx;");
                    w.line("boids[2u * i + 1u] = bv;");
                });
                if self.scope == Scope::Global {
                    w.comment("A fixed reduction tree, so the sums are the same every run.");
                    w.line("red_x[lid] = vec4<f32>(bx.xyz * bx.w, bx.w);");
                    w.line("red_v[lid] = vec4<f32>(bv.xyz * bx.w, 0.0);");
                    emit_tree_reduce(w);
                    w.line("let g = wid.x + wid.y * groups.x;");
                    w.block("if (lid == 0u && g < FLOCK_GROUPS)", |w| {
                        w.line("flock_sums[2u * g] = red_x[0];");
                        w.line("flock_sums[2u * g + 1u] = red_v[0];");
                    });
                }
            },
        );
    }

    fn emit_pair_fn(&self, w: &mut Writer) {
        let core = self.core().max(f64::from(f32::MIN_POSITIVE));
        w.line(format!(
            "const FLOCK_R2: f32 = {}; // radius²: neighbours are closer",
            f32_lit(self.radius * self.radius)
        ));
        w.line(format!(
            "const FLOCK_INV_RADIUS: f32 = {};",
            f32_lit(1.0 / self.radius)
        ));
        w.line(format!(
            "const FLOCK_INV_CORE: f32 = {}; // 1 / (radius / 10)",
            f32_lit(1.0 / core)
        ));
        w.comment("A boid's heading (unit velocity), or zero when it is too slow to have one (no avoidance).");
        w.block("fn flock_heading(v: vec3<f32>) -> vec3<f32>", |w| {
            w.line("let s2 = dot(v, v);");
            w.block(
                format!(
                    "if (s2 <= {})",
                    f32_lit(MIN_HEADING_SPEED * MIN_HEADING_SPEED)
                ),
                |w| w.line("return vec3<f32>(0.0);"),
            );
            w.line("return v * inverseSqrt(s2);");
        });
        w.comment("Separation and avoidance on a boid with `heading` from a neighbour at offset d = x - xj, r2 = |d|² < radius², and the neighbour's weight w = 1 - r / radius. 1 / max(r, core) is min(1 / r, 1 / core): no division, and finite at r = 0, where d = 0 pushes nothing.");
        w.block(
            "fn flock_pair(d: vec3<f32>, r2: f32, heading: vec3<f32>) -> vec4<f32>",
            |w| {
                w.line("let inv_r = inverseSqrt(max(r2, 1e-30));");
                w.line("let w = max(1.0 - r2 * inv_r * FLOCK_INV_RADIUS, 0.0);");
                w.line("let near = min(inv_r, FLOCK_INV_CORE);");
                w.line("var a = vec3<f32>(0.0);");
                if self.separation != 0.0 {
                    w.line(format!(
                        "a += ({} * w * near) * d;",
                        f32_lit(self.separation)
                    ));
                }
                if self.avoidance != 0.0 {
                    w.line("let along = dot(d, heading);");
                    w.comment("How directly ahead the neighbour is: 0 beside or behind, so no jump.");
                    w.line("let ahead = max(-along, 0.0) * near;");
                    w.line("let side = d - along * heading;");
                    w.line("let to_side = min(inverseSqrt(max(dot(side, side), 1e-30)), FLOCK_INV_CORE);");
                    w.line(format!(
                        "a += ({} * w * ahead * to_side) * side;",
                        f32_lit(self.avoidance)
                    ));
                }
                w.line("return vec4<f32>(a, w);");
            },
        );
    }
}

/// Sums `red_x` and `red_v` into their element 0 by a fixed tree (the same order every run),
/// with the barriers that need every thread of the workgroup.
fn emit_tree_reduce(w: &mut Writer) {
    w.line("workgroupBarrier();");
    w.block("for (var s = WORKGROUP / 2u; s > 0u; s = s >> 1u)", |w| {
        w.block("if (lid < s)", |w| {
            w.line("red_x[lid] += red_x[lid + s];");
            w.line("red_v[lid] += red_v[lid + s];");
        });
        w.line("workgroupBarrier();");
    });
}

/// The neighbour pass's running sums, zeroed.
fn emit_accumulators(w: &mut Writer) {
    w.line("var push = vec3<f32>(0.0);");
    w.line("var sum_x = vec3<f32>(0.0);");
    w.line("var sum_v = vec3<f32>(0.0);");
    w.line("var sum_w = 0.0;");
    w.line("var count = 0.0;");
}

/// `flock_reduce`: one workgroup sums the partials in a fixed order and writes the means.
fn emit_reduce(w: &mut Writer) {
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn flock_reduce(@builtin(local_invocation_index) lid: u32)",
        |w| {
            w.line("var sx = vec4<f32>(0.0);");
            w.line("var sv = vec4<f32>(0.0);");
            w.block("for (var g = lid; g < FLOCK_GROUPS; g += WORKGROUP)", |w| {
                w.line("sx += flock_sums[2u * g];");
                w.line("sv += flock_sums[2u * g + 1u];");
            });
            w.line("red_x[lid] = sx;");
            w.line("red_v[lid] = sv;");
            emit_tree_reduce(w);
            w.block("if (lid == 0u)", |w| {
                w.line("let n = red_x[0].w;");
                w.line("let inv = select(0.0, 1.0 / n, n > 0.0);");
                w.line("flock_sums[FLOCK_MEAN] = vec4<f32>(red_x[0].xyz * inv, n);");
                w.line("flock_sums[FLOCK_MEAN + 1u] = vec4<f32>(red_v[0].xyz * inv, 0.0);");
            });
        },
    );
}

/// Writes slot `slot`'s accumulated pass results: (separation + avoidance, Σ w), (Σ w x,
/// count), (Σ w v, 0).
fn emit_store_out(w: &mut Writer, slot: &str) {
    w.line(format!("flock_out[3u * {slot}] = vec4<f32>(push, sum_w);"));
    w.line(format!(
        "flock_out[3u * {slot} + 1u] = vec4<f32>(sum_x, count);"
    ));
    w.line(format!(
        "flock_out[3u * {slot} + 2u] = vec4<f32>(sum_v, 0.0);"
    ));
}

/// Adds a neighbour (snapshot `ox`, `ov`) to the running sums of the boid at (`me`,
/// `heading`), unless `is_self` holds or the slot is free (all pairs: `ox.w` 0).
fn emit_accumulate(w: &mut Writer, is_self: &str, ox: &str, ov: &str) {
    emit_accumulate_if(w, &format!("{ox}.w > 0.0 && !({is_self})"), ox, ov);
}

/// Adds the candidate (snapshot `ox`, `ov`) where `counts` holds and it is closer than the
/// radius.
fn emit_accumulate_if(w: &mut Writer, counts: &str, ox: &str, ov: &str) {
    w.line(format!("let d = me.xyz - {ox}.xyz;"));
    w.line("let r2 = dot(d, d);");
    w.block(format!("if ({counts} && r2 < FLOCK_R2)"), |w| {
        w.line("let f = flock_pair(d, r2, heading);");
        emit_add_neighbour(w, ox, ov);
    });
}

/// Adds the pair function's result `f` for the neighbour (snapshot `ox`, `ov`) to the running
/// sums.
fn emit_add_neighbour(w: &mut Writer, ox: &str, ov: &str) {
    w.line("push += f.xyz;");
    w.line(format!("sum_x += f.w * {ox}.xyz;"));
    w.line(format!("sum_v += f.w * {ov}.xyz;"));
    w.line("sum_w += f.w;");
    w.line("count += 1.0;");
}

/// `flock_pairs`: every boid against every slot, 256 at a time through workgroup memory. Every
/// thread takes part in loading each tile (barriers need uniform control flow); only live boids
/// accumulate.
fn emit_all_pairs(w: &mut Writer) {
    w.line("const FLOCK_TILES: u32 = (CAPACITY + WORKGROUP - 1u) / WORKGROUP;");
    w.line("var<workgroup> tile: array<vec4<f32>, 512>;");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn flock_pairs(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "i", None);
            w.line("var me = vec4<f32>(0.0);");
            w.line("var me_v = vec4<f32>(0.0);");
            w.block("if (i < chunk.len)", |w| {
                w.line("me = boids[2u * i];");
                w.line("me_v = boids[2u * i + 1u];");
            });
            w.line("let heading = flock_heading(me_v.xyz);");
            emit_accumulators(w);
            w.block("for (var t = 0u; t < FLOCK_TILES; t++)", |w| {
                w.line("let src = t * WORKGROUP + lid;");
                w.line("var bx = vec4<f32>(0.0);");
                w.line("var bv = vec4<f32>(0.0);");
                w.block("if (src < CAPACITY)", |w| {
                    w.line("bx = boids[2u * src];");
                    w.line("bv = boids[2u * src + 1u];");
                });
                w.line("tile[2u * lid] = bx;");
                w.line("tile[2u * lid + 1u] = bv;");
                w.line("workgroupBarrier();");
                w.block("if (me.w > 0.0)", |w| {
                    w.block("for (var k = 0u; k < WORKGROUP; k++)", |w| {
                        w.line("let j = t * WORKGROUP + k;");
                        w.line("let ox = tile[2u * k];");
                        w.line("let ov = tile[2u * k + 1u];");
                        emit_accumulate(w, "j == i", "ox", "ov");
                    });
                });
                w.line("workgroupBarrier();");
            });
            w.block("if (i < chunk.len)", |w| emit_store_out(w, "i"));
        },
    );
}

/// The grid, a counting sort of the boids by cell, and a search by tiles of boids:
///
/// - `grid_clear` zeroes the bucket counts; `grid_bucket` gives each live boid its cell's
///   bucket and counts it (`atomicAdd`, which also hands it a place among its bucket's boids,
///   in whatever order the threads ran); the runtime scans the counts into `cell_start`, where
///   each bucket's run starts; `grid_scatter` puts each boid's slot at its run's start plus
///   that place.
/// - `grid_rank` makes the order the same every run: each boid's rank in its run is the number
///   of the run's slots below its own, so a run ends up in slot order, and the boid's snapshot
///   is written there (`boids` in sorted order: a bucket's boids contiguous).
/// - `flock_grid` (its own module, [`FlockIr::emit_search_module`]): below
///   [`GRID_SPLIT_BELOW`] boids a workgroup takes [`GRID_TILE`] consecutive sorted boids; nine
///   threads a boid each walk one row of 3 cells around the boid's own (27 cells in all), and
///   the boid's first thread adds the nine partial sums in row order. From it on, one thread a
///   boid walks the nine rows.
///
/// The bucket hash keeps x-neighbouring cells in consecutive buckets, so a row of 3 cells is
/// one run of sorted boids (two where the buckets wrap), and scatters the rows over the table
/// (a PCG hash of (y, z): the multiply-xor hash before it put 2,164 occupied cells of a 16k
/// flock in 1,677 of 32,768 buckets, and a boid walked 401 candidates for the 268 in its 27
/// cells; with PCG, 286). Other cells may share a row's buckets; a candidate counts only if its
/// row key (the snapshot's spare word) is the row's: a sorted boid in the row's buckets with
/// that key is either in the row's 3 cells, or in a row at least 4 cells away in y or z (the
/// key is (y, z) modulo 4), or in the same row at least `GRID_BUCKETS - 2` cells away in x, and
/// both lie beyond the radius (cell >= radius), so the distance test drops them. A boid adds
/// its neighbours in (row, x, slot) order, the same every run.
fn emit_grid(w: &mut Writer, cell: f64) {
    emit_cell_fns(w, cell);
    w.line("const NO_BUCKET: u32 = 0xffffffffu;");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "k", None);
            w.block("if (k <= GRID_BUCKETS)", |w| {
                w.line("atomicStore(&cell_start[k], 0u);");
            });
        },
    );
    w.comment("Each live boid's bucket, counted; grid_vals holds its place among its bucket's boids until the scatter.");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_bucket(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "i", Some("chunk.len"));
            w.line("let b = boid_of(i)[0];");
            w.line("var key = NO_BUCKET;");
            w.line("var place = 0u;");
            w.block("if (b.w > 0.0)", |w| {
                w.line("key = bucket_of(cell_of(b.xyz));");
                w.line("place = atomicAdd(&cell_start[key], 1u);");
            });
            w.line("grid_keys[i] = key;");
            w.line("grid_vals[i] = place;");
        },
    );
    w.comment("After the scan: each live boid's slot at its run's start plus its place (in thread order).");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "i", Some("chunk.len"));
            w.line("let key = grid_keys[i];");
            w.block("if (key != NO_BUCKET)", |w| {
                w.line("grid_placed[atomicLoad(&cell_start[key]) + grid_vals[i]] = i;");
            });
        },
    );
    w.comment("Each run in slot order (a boid's rank: the run's slots below its own), and the snapshot in that order: boids[k] is the boid of slot grid_vals[k].");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_rank(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "k", None);
            w.block("if (k >= atomicLoad(&cell_start[GRID_BUCKETS]))", |w| {
                w.line("return;")
            });
            w.line("let s = grid_placed[k];");
            w.line("let b = grid_keys[s];");
            w.line("let first = atomicLoad(&cell_start[b]);");
            w.line("let last = atomicLoad(&cell_start[b + 1u]);");
            w.line("var at = first;");
            w.block("for (var m = first; m < last; m++)", |w| {
                w.line("at += select(0u, 1u, grid_placed[m] < s);");
            });
            w.line("grid_vals[at] = s;");
            w.line("let bo = boid_of(s);");
            w.line("let bo_cell = cell_of(bo[0].xyz);");
            w.comment("The position's w word holds the key of the boid's row of cells.");
            w.line("boids[2u * at] = vec4<f32>(bo[0].xyz, row_key(bo_cell));");
            w.line("boids[2u * at + 1u] = vec4<f32>(bo[1].xyz, 0.0);");
        },
    );
}

/// The grid's cell arithmetic, shared by the build kernels (main module) and the search (its
/// own module): `cell_of`, `row_key` (what the sorted snapshot's spare word holds) and
/// `bucket_of`.
fn emit_cell_fns(w: &mut Writer, cell: f64) {
    w.line(format!("const INV_CELL: f32 = {};", f32_lit(1.0 / cell)));
    w.block("fn cell_of(x: vec3<f32>) -> vec3<i32>", |w| {
        w.comment(
            "Clamped so that far-away boids share the outermost cells instead of overflowing.",
        );
        w.line(
            "return vec3<i32>(clamp(floor(x * INV_CELL), vec3<f32>(-1.0e6), vec3<f32>(1.0e6)));",
        );
    });
    w.comment("A cell's row (y, z) modulo 4 each way, as a small whole f32: rows of one boid's 27 cells differ in it, and a row farther away that shares buckets with them lies beyond the radius.");
    w.block("fn row_key(c: vec3<i32>) -> f32", |w| {
        w.line("return f32((c.y & 3) | ((c.z & 3) << 2u));");
    });
    w.comment("The PCG hash, for the buckets.");
    crate::base::rng::emit_pcg(w, "grid_pcg");
    w.comment("A row's hash (PCG of y, then of that plus z) plus x: cells x - 1, x, x + 1 fall in consecutive buckets, and rows scatter over the whole table.");
    w.block("fn bucket_of(c: vec3<i32>) -> u32", |w| {
        w.line("let u = bitcast<vec3<u32>>(c);");
        w.line("return (grid_pcg(grid_pcg(u.y) + u.z) + u.x) & (GRID_BUCKETS - 1u);");
    });
}

/// The candidates of the row of 3 cells from cell `c` along x: the sorted boids in buckets
/// `bucket_of(c) .. + 2` (mod the buckets: one run, or two where they wrap), of which those
/// with the row's key (another row may share the buckets; see [`emit_grid`]) are tested
/// against boid `k` at (`me`, `heading`), in run order, [`GRID_ROW_UNROLL`] loaded at a time
/// (more loads in flight per thread). One thread a boid: see [`emit_row_masked`] for the split
/// search.
fn emit_row(w: &mut Writer) {
    emit_row_runs(w, |w| {
        w.block(
            format!("for (var m = first; m < last; m += {GRID_ROW_UNROLL}u)"),
            |w| {
                for j in 0..GRID_ROW_UNROLL {
                    w.line(format!("let m{j} = min(m + {j}u, last - 1u);"));
                    w.line(format!("let x{j} = boids[2u * m{j}];"));
                    w.line(format!("let v{j} = boids[2u * m{j} + 1u];"));
                }
                for j in 0..GRID_ROW_UNROLL {
                    w.block(format!("if (m + {j}u < last)"), |w| {
                        emit_accumulate_if(
                            w,
                            &format!("x{j}.w == key && m{j} != k"),
                            &format!("x{j}"),
                            &format!("v{j}"),
                        );
                    });
                }
            },
        );
    });
}

/// The row from cell `c`: its first bucket `b0` and its `key`, then the one or two runs of its
/// 3 buckets (two where the buckets wrap), each as `first .. last` for `body`.
fn emit_row_runs(w: &mut Writer, body: impl Fn(&mut Writer)) {
    w.line("let b0 = bucket_of(c);");
    w.line("let key = row_key(c);");
    w.line("let wrapped = max(b0 + 3u, GRID_BUCKETS) - GRID_BUCKETS;");
    w.block("for (var r = 0u; r < 2u; r++)", |w| {
        w.line("let first = cell_start[select(0u, b0, r == 0u)];");
        w.line("let last = cell_start[select(wrapped, min(b0 + 3u, GRID_BUCKETS), r == 0u)];");
        body(w);
    });
}

/// The split search's walk of the same row, [`GRID_ROUND`] candidates a round: all of the
/// round's loaded at once, tested by position alone (the row's key and the distance), the
/// neighbours marked in a bit mask, then the pair function run on the marked ones in run order.
/// In a warp, inline pair code runs for every candidate that any of its threads accepts, nearly
/// all of them; with the masks it runs as often as the warp's busiest thread has neighbours
/// among the round's. (With one thread a boid the masks were slower: 1.66 against 1.55 ms at
/// 1M.) The last round reads up to `GRID_ROUND - 1` boids past the run (the snapshot has that
/// many spare entries) and masks them off; the boid itself is masked off by its index.
fn emit_row_masked(w: &mut Writer) {
    emit_row_runs(w, |w| {
        w.block(
            format!("for (var base = first; base < last; base += {GRID_ROUND}u)"),
            |w| {
                for j in 0..GRID_ROUND {
                    w.line(format!("let x{j} = boids[2u * (base + {j}u)];"));
                }
                w.line("var hits = 0u;");
                for j in 0..GRID_ROUND {
                    w.line(format!("let d{j} = me.xyz - x{j}.xyz;"));
                    w.line(format!(
                        "hits |= select(0u, {}u, x{j}.w == key && dot(d{j}, d{j}) < FLOCK_R2);",
                        1u32 << j
                    ));
                }
                w.comment("Only the run's candidates, and not the boid itself.");
                w.line(format!(
                    "hits &= (2u << (min(last - base, {GRID_ROUND}u) - 1u)) - 1u;"
                ));
                w.line(format!(
                    "hits &= select(0xffffffffu, ~(1u << (k - base)), k - base < {GRID_ROUND}u);"
                ));
                w.block("while (hits != 0u)", |w| {
                    w.line("let m = base + firstTrailingBit(hits);");
                    w.line("hits &= hits - 1u;");
                    w.line("let xm = boids[2u * m];");
                    w.line("let vm = boids[2u * m + 1u];");
                    w.line("let d = me.xyz - xm.xyz;");
                    w.line("let f = flock_pair(d, dot(d, d), heading);");
                    emit_add_neighbour(w, "xm", "vm");
                });
            },
        );
    });
}

/// `flock_grid`, one thread a boid: its nine rows of 3 cells in turn.
fn emit_search(w: &mut Writer) {
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn flock_grid(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "k", None);
            w.block("if (k >= cell_start[GRID_BUCKETS])", |w| w.line("return;"));
            w.line("let me = boids[2u * k];");
            w.line("let me_v = boids[2u * k + 1u];");
            w.line("let heading = flock_heading(me_v.xyz);");
            emit_accumulators(w);
            w.line("let home = cell_of(me.xyz);");
            w.block("for (var n = 0; n < 9; n++)", |w| {
                w.line("let c = home + vec3<i32>(-1, n % 3 - 1, n / 3 - 1);");
                emit_row(w);
            });
            emit_store_out(w, "grid_vals[k]");
        },
    );
}

/// `flock_grid`, nine threads a boid, one row each ([`GRID_TILE`] boids a workgroup, each row
/// walked by [`emit_row_masked`]); the boid's first thread adds the nine partial sums in row
/// order.
fn emit_split_search(w: &mut Writer) {
    w.line(format!("const GRID_TILE: u32 = {};", u32_lit(GRID_TILE)));
    w.comment("Per thread: its row's (push, Σw), (Σw x, count), (Σw v, 0).");
    w.line("var<workgroup> grid_partial: array<vec4<f32>, 27u * GRID_TILE>;");
    w.line("@compute @workgroup_size(9u * GRID_TILE)");
    w.block(
        "fn flock_grid(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32)",
        |w| {
            w.comment("Row n of boid b: a warp's threads search consecutive boids.");
            w.line("let n = lid / GRID_TILE;");
            w.line("let b = lid % GRID_TILE;");
            w.line("let k = (wid.x + wid.y * groups.x) * GRID_TILE + b;");
            w.line("let live = cell_start[GRID_BUCKETS];");
            emit_accumulators(w);
            w.comment("No early return: every thread reaches the barrier.");
            w.block("if (k < live)", |w| {
                w.line("let me = boids[2u * k];");
                w.line("let me_v = boids[2u * k + 1u];");
                w.line("let heading = flock_heading(me_v.xyz);");
                w.line("let c = cell_of(me.xyz) + vec3<i32>(-1, i32(n % 3u) - 1, i32(n / 3u) - 1);");
                emit_row_masked(w);
            });
            w.line("let at = 3u * (b * 9u + n);");
            w.line("grid_partial[at] = vec4<f32>(push, sum_w);");
            w.line("grid_partial[at + 1u] = vec4<f32>(sum_x, count);");
            w.line("grid_partial[at + 2u] = vec4<f32>(sum_v, 0.0);");
            w.line("workgroupBarrier();");
            w.block("if (n == 0u && k < live)", |w| {
                w.line("var a = vec4<f32>(0.0);");
                w.line("var s = vec4<f32>(0.0);");
                w.line("var d = vec4<f32>(0.0);");
                w.block("for (var r = 0u; r < 9u; r++)", |w| {
                    w.line("a += grid_partial[3u * (b * 9u + r)];");
                    w.line("s += grid_partial[3u * (b * 9u + r) + 1u];");
                    w.line("d += grid_partial[3u * (b * 9u + r) + 2u];");
                });
                w.line("push = a.xyz;");
                w.line("sum_w = a.w;");
                w.line("sum_x = s.xyz;");
                w.line("count = s.w;");
                w.line("sum_v = d.xyz;");
                emit_store_out(w, "grid_vals[k]");
            });
        },
    );
}
