//! The WGSL both neighbour passes share: the pair function (one neighbour's push and weight,
//! the f32 twin of `FlockIr::pair`), the accumulators and their tree reduction, and storing a
//! boid's sums.

use super::FlockIr;
use super::MIN_HEADING_SPEED;
use crate::base::writer::{f32_lit, Writer};

impl FlockIr {
    pub(super) fn emit_pair_fn(&self, w: &mut Writer) {
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
pub(super) fn emit_tree_reduce(w: &mut Writer) {
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
pub(super) fn emit_accumulators(w: &mut Writer) {
    w.line("var push = vec3<f32>(0.0);");
    w.line("var sum_x = vec3<f32>(0.0);");
    w.line("var sum_v = vec3<f32>(0.0);");
    w.line("var sum_w = 0.0;");
    w.line("var count = 0.0;");
}

/// Writes slot `slot`'s accumulated pass results: (separation + avoidance, Σ w), (Σ w x,
/// count), (Σ w v, 0).
pub(super) fn emit_store_out(w: &mut Writer, slot: &str) {
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
pub(super) fn emit_accumulate(w: &mut Writer, is_self: &str, ox: &str, ov: &str) {
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
/// sums, and counts it.
pub(super) fn emit_add_neighbour(w: &mut Writer, ox: &str, ov: &str) {
    emit_add_pair(w, ox, ov);
    w.line("count += 1.0;");
}

/// [`emit_add_neighbour`] but for the count, which a masked round adds once for all of its
/// neighbours (the same whole number: counts stay far below 2^24).
pub(super) fn emit_add_pair(w: &mut Writer, ox: &str, ov: &str) {
    w.line("push += f.xyz;");
    w.line(format!("sum_x += f.w * {ox}.xyz;"));
    w.line(format!("sum_v += f.w * {ov}.xyz;"));
    w.line("sum_w += f.w;");
}
