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

use crate::check::Checker;
use crate::path::ValuePath;
use crate::wgsl::writer::{f32_lit, u32_lit, Writer};

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

/// Boids per workgroup of the grid's split search (9 threads each, one per run of 3 cells).
pub const GRID_BOIDS_PER_GROUP: u32 = 32;

/// Below this capacity the grid's search splits each boid over 9 threads (one per run of 3
/// cells); from it on, one thread walks all 9 runs. Measured on the H100 with
/// effects/boids.ron (docs/performance.md): split 0.089 against 0.260 ms at 16k boids and 0.285
/// against 0.330 at 64k, but 1.05 against 0.81 at 256k and 4.76 against 2.92 at 1M, where the
/// GPU is full anyway and one thread a boid lets a warp's 32 neighbouring boids read the same
/// candidates together.
pub const GRID_SPLIT_SEARCH_BELOW: u32 = 131_072;

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

    /// Hash-table buckets of the grid for `capacity` boids: a power of two >= capacity, at
    /// most 2^31 (so that the count fits the shaders' u32).
    pub fn grid_buckets(capacity: u32) -> u64 {
        // In u64: a capacity above 2^31 would overflow u32.
        u64::from(capacity.max(1)).next_power_of_two().min(1 << 31)
    }

    /// Whether the grid's search of `capacity` boids runs 9 threads a boid
    /// ([`GRID_SPLIT_SEARCH_BELOW`]).
    pub fn split_search(capacity: u32) -> bool {
        capacity < GRID_SPLIT_SEARCH_BELOW
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

    /// The per-step kernels: `flock_snapshot` (+ the partial sums), `flock_reduce` (Global),
    /// and the neighbour pass (`flock_pairs`, or the grid's kernels).
    pub fn emit_kernels(&self, w: &mut Writer, verlet_h: Option<f64>, capacity: u32) {
        self.emit_snapshot(w, verlet_h);
        if self.scope == Scope::Global {
            w.blank();
            emit_reduce(w);
        }
        w.blank();
        self.emit_pair_fn(w);
        w.blank();
        match self.neighbors {
            Neighbors::AllPairs => emit_all_pairs(w),
            Neighbors::Grid { cell } => emit_grid(w, cell, Self::split_search(capacity)),
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
                crate::wgsl::emit_thread_index(w, "i", None);
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
        w.line(format!(
            "const FLOCK_RADIUS: f32 = {};",
            f32_lit(self.radius)
        ));
        w.comment("Separation and avoidance on a boid at (x, v) from a neighbour at xj.");
        w.block(
            "fn flock_pair(x: vec3<f32>, v: vec3<f32>, xj: vec3<f32>) -> vec4<f32>",
            |w| {
                w.line("let d = x - xj;");
                w.line("let r = length(d);");
                w.block("if (r >= FLOCK_RADIUS)", |w| {
                    w.line("return vec4<f32>(0.0);");
                });
                w.line(format!("let w = 1.0 - r * {};", f32_lit(1.0 / self.radius)));
                w.line("var a = vec3<f32>(0.0);");
                let core = f32_lit(self.core().max(f64::from(f32::MIN_POSITIVE)));
                if self.separation != 0.0 {
                    w.line(format!(
                        "a += {} * w * (d / max(r, {core}));",
                        f32_lit(self.separation)
                    ));
                }
                if self.avoidance != 0.0 {
                    w.line("let speed = length(v);");
                    w.block(format!("if (speed > {})", f32_lit(MIN_HEADING_SPEED)), |w| {
                        w.line("let heading = v / speed;");
                        w.line("let along = dot(d, heading);");
                        w.comment("How directly ahead the neighbour is: 0 beside or behind, so no jump.");
                        w.line(format!("let ahead = max(-along, 0.0) / max(r, {core});"));
                        w.line("let side = d - along * heading;");
                        w.line(format!(
                            "a += {} * w * ahead * (side / max(length(side), {core}));",
                            f32_lit(self.avoidance)
                        ));
                    });
                }
                w.comment("w > 0 marks a neighbour and weighs it in the local means.");
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

/// Adds a neighbour (snapshot `ox`, `ov`) to the running sums, unless `is_self` holds.
fn emit_accumulate(w: &mut Writer, is_self: &str, ox: &str, ov: &str) {
    w.block(format!("if ({ox}.w > 0.0 && !({is_self}))"), |w| {
        w.line(format!("let f = flock_pair(me.xyz, me_v.xyz, {ox}.xyz);"));
        w.block("if (f.w > 0.0)", |w| {
            w.line("push += f.xyz;");
            w.line(format!("sum_x += f.w * {ox}.xyz;"));
            w.line(format!("sum_v += f.w * {ov}.xyz;"));
            w.line("sum_w += f.w;");
            w.line("count += 1.0;");
        });
    });
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
            crate::wgsl::emit_thread_index(w, "i", None);
            w.line("var me = vec4<f32>(0.0);");
            w.line("var me_v = vec4<f32>(0.0);");
            w.block("if (i < chunk.len)", |w| {
                w.line("me = boids[2u * i];");
                w.line("me_v = boids[2u * i + 1u];");
            });
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

/// The grid: `grid_clear` zeroes the bucket counts; `grid_bucket` gives each live boid its
/// cell's bucket (free slots the largest key) and counts it; the runtime sorts (bucket, slot)
/// pairs with the stable radix sort and scans the counts into `cell_start` (where each bucket's
/// run starts among the sorted boids); `grid_reorder` rewrites `boids` in the sorted order, so
/// that a bucket's boids are contiguous and the boids of one workgroup search the same cells
/// (their reads coalesce and hit the cache). The bucket hash keeps x-neighbouring cells in
/// consecutive buckets. Below [`GRID_SPLIT_SEARCH_BELOW`] boids `flock_grid` (writing to each
/// boid's slot) visits the 27 cells around a boid as 9 runs of 3 buckets, one thread a run
/// (nine threads a boid: more loads in flight than one thread walking ~400 candidates in
/// turn); the boid's first thread adds the nine partial sums in run order. From there on the
/// cells are half as big and one thread a boid walks the rows of them the radius reaches
/// ([`emit_search`]). Either way only entries whose own cell is a visited one count (other
/// cells may share a bucket), and within a run the boids stay in slot order (the sort is
/// stable), so every boid sums its neighbours in the same order every run.
fn emit_grid(w: &mut Writer, cell: f64, split_search: bool) {
    // The one-thread search clips its rows to the radius sphere, which pays on finer cells:
    // half the given cell (still >= radius / 2, so 2 half cells reach the radius).
    let hashed = if split_search { cell } else { cell / 2.0 };
    w.line(format!("const INV_CELL: f32 = {};", f32_lit(1.0 / hashed)));
    w.block("fn cell_of(x: vec3<f32>) -> vec3<i32>", |w| {
        w.comment(
            "Clamped so that far-away boids share the outermost cells instead of overflowing.",
        );
        w.line(
            "return vec3<i32>(clamp(floor(x * INV_CELL), vec3<f32>(-1.0e6), vec3<f32>(1.0e6)));",
        );
    });
    w.comment("The (y, z) hash plus x: cells x - 1, x, x + 1 fall in consecutive buckets.");
    w.block("fn bucket_of(c: vec3<i32>) -> u32", |w| {
        w.line("let u = bitcast<vec3<u32>>(c);");
        w.line("return (((u.y * 19349663u) ^ (u.z * 83492791u)) * 73856093u + u.x) & (GRID_BUCKETS - 1u);");
    });
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::wgsl::emit_thread_index(w, "k", None);
            w.block("if (k <= GRID_BUCKETS)", |w| {
                w.line("atomicStore(&cell_start[k], 0u);");
            });
        },
    );
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_bucket(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::wgsl::emit_thread_index(w, "i", Some("chunk.len"));
            w.line("let b = boids[2u * i];");
            w.line("var key = 0xffffffffu;");
            w.block("if (b.w > 0.0)", |w| {
                w.line("key = bucket_of(cell_of(b.xyz));");
                w.line("atomicAdd(&cell_start[key], 1u);");
            });
            w.line("grid_keys[i] = key;");
            w.line("grid_vals[i] = i;");
        },
    );
    w.comment("The snapshot again, in sorted order: boids[k] is the boid of slot grid_vals[k].");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn grid_reorder(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::wgsl::emit_thread_index(w, "k", Some("chunk.len"));
            w.line("let b = boid_of(grid_vals[k]);");
            w.line("boids[2u * k] = b[0];");
            w.line("boids[2u * k + 1u] = b[1];");
        },
    );
    if split_search {
        emit_split_search(w);
    } else {
        emit_search(w);
    }
}

/// The walk over one run of 3 buckets around cell `c` (x - 1 to x + 1), for boid `k` at
/// (`me`, `me_v`), adding to the running sums.
fn emit_run_walk(w: &mut Writer) {
    w.line("let b0 = bucket_of(c - vec3<i32>(1, 0, 0));");
    emit_bucket_run(w, "3u", "abs(co.x - c.x) > 1");
}

/// The candidates in buckets `b0 .. b0 + len - 1` (mod buckets): one run of sorted boids, or
/// two where the buckets wrap. A candidate counts only if its own cell is in row `c` and not
/// `outside` in x (another cell may share the buckets).
fn emit_bucket_run(w: &mut Writer, len: &str, outside: &str) {
    w.comment("Buckets b0 .. b0 + len - 1 (mod buckets): one run, or two where they wrap.");
    w.line(format!(
        "let wrapped = max(b0 + {len}, GRID_BUCKETS) - GRID_BUCKETS;"
    ));
    w.block("for (var r = 0u; r < 2u; r++)", |w| {
        w.line("let first = atomicLoad(&cell_start[select(0u, b0, r == 0u)]);");
        w.line(format!(
            "let last = atomicLoad(&cell_start[select(wrapped, min(b0 + {len}, GRID_BUCKETS), r == 0u)]);"
        ));
        w.block("for (var m = first; m < last; m++)", |w| {
            w.line("let ox = boids[2u * m];");
            w.line("let co = cell_of(ox.xyz);");
            w.comment("Another cell hashed to these buckets: not a neighbour from here.");
            w.block(format!("if (co.y != c.y || co.z != c.z || {outside})"), |w| {
                w.line("continue;");
            });
            w.line("let ov = boids[2u * m + 1u];");
            emit_accumulate(w, "m == k", "ox", "ov");
        });
    });
}

/// `flock_grid`, one thread a boid, on half cells (`cell_of` uses cell / 2 here, see
/// [`emit_grid`]): the boid walks the 25 rows of half cells within 2 of its own in y and z,
/// skips those whose nearest point is farther than the radius, and in each of the others reads
/// only the x cells the radius sphere's chord reaches. A neighbour is closer than the radius in
/// (y, z), so its row is walked, and in x, so its cell lies in the chord's range: the same
/// neighbours as all pairs. The reach is widened by 1e-5 of itself plus 1e-6 of the boid's
/// coordinate in cells, far more than the f32 rounding of the cell arithmetic, so that a pair at
/// the radius is never lost to it. Against the 27 whole cells this reads about half as many
/// candidates (docs/performance.md).
fn emit_search(w: &mut Writer) {
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn flock_grid(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::wgsl::emit_thread_index(w, "k", Some("chunk.len"));
            w.line("let me = boids[2u * k];");
            w.line("let me_v = boids[2u * k + 1u];");
            emit_accumulators(w);
            w.block("if (me.w > 0.0)", |w| {
                w.line("let home = cell_of(me.xyz);");
                w.comment("The boid in cells, and where it sits in its own cell (0 to 1 a side).");
                w.line("let pc = me.xyz * INV_CELL;");
                w.line("let f = clamp(pc - vec3<f32>(home), vec3<f32>(0.0), vec3<f32>(1.0));");
                w.line("let reach = FLOCK_RADIUS * INV_CELL * 1.00001 + 1e-6 * abs(pc.x);");
                w.block("for (var n = 0; n < 25; n++)", |w| {
                    w.line("let dy = n % 5 - 2;");
                    w.line("let dz = n / 5 - 2;");
                    w.comment("Distance (cells) from the boid to the row's nearest y and z.");
                    w.line("let gy = select(select(0.0, f.y + f32(-dy - 1), dy < 0), f32(dy) - f.y, dy > 0);");
                    w.line("let gz = select(select(0.0, f.z + f32(-dz - 1), dz < 0), f32(dz) - f.z, dz > 0);");
                    w.line("let left = reach * reach - gy * gy - gz * gz;");
                    w.block("if (left < 0.0)", |w| w.line("continue;"));
                    w.line("let chord = sqrt(left);");
                    w.line("let lo = i32(clamp(floor(pc.x - chord), -1.0e6, 1.0e6));");
                    w.line("let hi = i32(clamp(floor(pc.x + chord), -1.0e6, 1.0e6));");
                    w.line("let c = vec3<i32>(lo, home.y + dy, home.z + dz);");
                    w.line("let b0 = bucket_of(c);");
                    w.line("let len = u32(hi - lo + 1);");
                    emit_bucket_run(w, "len", "co.x < lo || co.x > hi");
                });
            });
            emit_store_out(w, "grid_vals[k]");
        },
    );
}

/// `flock_grid`, nine threads a boid (one a run); the boid's first thread adds the nine partial
/// sums in run order (the same order every run).
fn emit_split_search(w: &mut Writer) {
    w.line(format!(
        "const GRID_BOIDS_PER_GROUP: u32 = {};",
        u32_lit(GRID_BOIDS_PER_GROUP)
    ));
    w.comment("Per thread: its run's (push, Σw), (Σw x, count), (Σw v, 0).");
    w.line(format!(
        "var<workgroup> grid_partial: array<vec4<f32>, {}>;",
        27 * GRID_BOIDS_PER_GROUP
    ));
    w.line(format!(
        "@compute @workgroup_size({})",
        9 * GRID_BOIDS_PER_GROUP
    ));
    w.block(
        "fn flock_grid(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32)",
        |w| {
            w.line("let n = i32(lid % 9u);");
            w.line("let k = (wid.x + wid.y * groups.x) * GRID_BOIDS_PER_GROUP + lid / 9u;");
            emit_accumulators(w);
            w.comment("No early return: every thread reaches the barrier.");
            w.block("if (k < chunk.len)", |w| {
                w.line("let me = boids[2u * k];");
                w.line("let me_v = boids[2u * k + 1u];");
                w.block("if (me.w > 0.0)", |w| {
                    w.line("let c = cell_of(me.xyz) + vec3<i32>(0, n % 3 - 1, n / 3 - 1);");
                    emit_run_walk(w);
                });
            });
            w.line("grid_partial[3u * lid] = vec4<f32>(push, sum_w);");
            w.line("grid_partial[3u * lid + 1u] = vec4<f32>(sum_x, count);");
            w.line("grid_partial[3u * lid + 2u] = vec4<f32>(sum_v, 0.0);");
            w.line("workgroupBarrier();");
            w.block("if (n == 0 && k < chunk.len)", |w| {
                w.line("var a = vec4<f32>(0.0);");
                w.line("var b = vec4<f32>(0.0);");
                w.line("var d = vec4<f32>(0.0);");
                w.block("for (var r = 0u; r < 9u; r++)", |w| {
                    w.line("a += grid_partial[3u * (lid + r)];");
                    w.line("b += grid_partial[3u * (lid + r) + 1u];");
                    w.line("d += grid_partial[3u * (lid + r) + 2u];");
                });
                w.line("push = a.xyz;");
                w.line("sum_w = a.w;");
                w.line("sum_x = b.xyz;");
                w.line("count = b.w;");
                w.line("sum_v = d.xyz;");
                emit_store_out(w, "grid_vals[k]");
            });
        },
    );
}
