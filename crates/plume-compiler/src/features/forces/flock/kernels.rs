//! The flock's WGSL in the main compute module: its declarations, the update's prologue, the
//! per-step snapshot, the Global scope's reduction and the all-pairs pass over shared tiles
//! (the grid's kernels are in `grid`).

use super::accumulate::{emit_accumulate, emit_accumulators, emit_store_out, emit_tree_reduce};
use super::grid::emit_grid;
use super::{FlockIr, Neighbors, Scope};
use crate::base::writer::{f32_lit, u32_lit, Writer};

impl FlockIr {
    /// Module-scope declarations: constants, the per-invocation frozen values and the
    /// acceleration added to `accel`.
    pub(crate) fn emit_declarations(&self, w: &mut Writer, capacity: u32, workgroup: u32) {
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
    pub(crate) fn emit_update_prologue(&self, w: &mut Writer) {
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
    /// and the neighbour pass (`flock_pairs`, or the grid's build kernels; its search is
    /// `emit_search_module`).
    pub(crate) fn emit_kernels(&self, w: &mut Writer, capacity: u32, verlet_h: Option<f64>) {
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
            Neighbors::Grid { cell } => emit_grid(w, cell, Self::x_split(capacity)),
        }
    }

    pub(super) fn emit_snapshot(&self, w: &mut Writer, verlet_h: Option<f64>) {
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
}

/// `flock_reduce`: one workgroup sums the partials in a fixed order and writes the means.
pub(super) fn emit_reduce(w: &mut Writer) {
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

/// `flock_pairs`: every boid against every slot, 256 at a time through workgroup memory. Every
/// thread takes part in loading each tile (barriers need uniform control flow); only live boids
/// accumulate.
pub(super) fn emit_all_pairs(w: &mut Writer) {
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
