//! The stateless `evaluate` kernel (see [`crate::stages::passes::stateless`]): thread `slot` of the
//! frame finds the segment that holds it, rebuilds its particle from the same spawn draws as the
//! stateful `spawn` kernel, and writes the closed form at the segment's age into the view.
//! Slots past the frame's threads, and particles whose lifetime has run out, are written free.

use crate::base::writer::Writer;
use crate::ir::EffectIr;
use crate::stages::passes::layout::{Attribute, Layout};

/// Emits the segment table's types. A segment is a run of consecutive ids one emitter spawned at
/// one step: `a` = (first thread, first id, emitter's own counter at the first id, emitter),
/// `b` = (age in steps, spawn step, age in seconds as f32 bits, 0).
pub(crate) fn emit_declarations(w: &mut Writer) {
    w.block("struct Segment", |w| {
        w.line("a: vec4<u32>,");
        w.line("b: vec4<u32>,");
    });
    w.blank();
    w.comment("One frame's bookkeeping, written by the CPU: threads in use, segments, steps done.");
    w.block("struct Frame", |w| {
        w.line("threads: u32,");
        w.line("count: u32,");
        w.line("steps: u32,");
        w.line("pad: u32,");
        w.line("segments: array<Segment>,");
    });
}

/// Emits `struct Evaluated` and `evaluate_at(slot)`: slot `slot` of this frame computed from its
/// spawn draws and its age (whether it is alive, its position and velocity now, its `die_at`,
/// id, spawn step and whole steps lived). Shared by the compute `evaluate` and `depth_keys`
/// kernels and by the draw module's vertex shader, so all three see the same particle.
pub(crate) fn emit_evaluate_at(w: &mut Writer, ir: &EffectIr) {
    w.comment("A slot of this frame: alive or not, and if alive its state now (x, v, die_at), id,");
    w.comment("spawn step and whole steps lived.");
    w.block("struct Evaluated", |w| {
        w.line("now: Spawned,");
        w.line("id: u32,");
        w.line("born: u32,");
        w.line("age: u32,");
        w.line("alive: bool,");
    });
    w.block("fn evaluate_at(slot: u32) -> Evaluated", |w| {
        w.line("var e: Evaluated;");
        w.line("e.alive = false;");
        w.comment("Past the frame's threads (all of them when no segment is live: threads = 0).");
        w.block("if (slot >= frame.threads)", |w| {
            w.line("return e;");
        });
        emit_segment_of(w, "frame", "slot", SegmentSearch::Halves);
        w.line("let j = slot - seg.a.x;");
        w.line("e.id = seg.a.y + j;");
        w.line("e.born = seg.b.y;");
        w.line("e.age = seg.b.x;");
        w.line("let k = seg.a.z + j;");
        emit_spawn_draws(w, ir, "e.id", "seg.b.y", "return e;");
        if ir.has_lifetimes() {
            w.comment("Dead once it has lived its whole steps: die_at - spawn step + 1.");
            w.block(
                "if (s.die_at != DEAD && seg.b.x >= s.die_at - seg.b.y + 1u)",
                |w| w.line("return e;"),
            );
        }
        w.line("e.now = advance(s, bitcast<f32>(seg.b.z));");
        w.line("e.alive = true;");
        w.line("return e;");
    });
}

/// How [`emit_segment_of`] looks a thread's segment up.
#[derive(Clone, Copy)]
enum SegmentSearch {
    /// Halving the range: a load a round, each waiting on the one before.
    Halves,
    /// Eighths: each round loads the starts of seven segments at once (independent loads,
    /// waited for together) and keeps the eighth of the range that holds the thread, three
    /// rounds for a hundred segments where halving takes seven loads in turn. For the `fire`
    /// kernel, a few thousand threads a step whose search is most of their work: on an H100
    /// each load in turn costs an L2 latency.
    Eighths,
}

/// Emits `let seg`: the segment of `table` (a `Frame`) that holds thread `thread`, the last one
/// starting at or before it (their first threads increase), found as `search` says.
fn emit_segment_of(w: &mut Writer, table: &str, thread: &str, search: SegmentSearch) {
    w.comment(match search {
        SegmentSearch::Halves => {
            "The last segment starting at or before this slot (offsets increase)."
        }
        SegmentSearch::Eighths => {
            "The last segment starting at or before this slot (offsets increase), by eighths."
        }
    });
    w.line("var lo = 0u;");
    w.line(format!("var hi = {table}.count;"));
    w.block("while (hi - lo > 1u)", |w| match search {
        SegmentSearch::Halves => {
            w.line("let mid = (lo + hi) / 2u;");
            w.block(format!("if ({table}.segments[mid].a.x <= {thread})"), |w| {
                w.line("lo = mid;")
            });
            w.block("else", |w| w.line("hi = mid;"));
        }
        SegmentSearch::Eighths => {
            w.line("let eighth = (hi - lo + 7u) / 8u;");
            w.line("var next = lo;");
            w.block("for (var q = 1u; q < 8u; q++)", |w| {
                w.line("let m = lo + q * eighth;");
                w.line(format!(
                    "let start = {table}.segments[min(m, hi - 1u)].a.x;"
                ));
                w.block(format!("if (m < hi && start <= {thread})"), |w| {
                    w.line("next = m;")
                });
            });
            w.line("hi = min(next + eighth, hi);");
            w.line("lo = next;");
        }
    });
    w.line(format!("let seg = {table}.segments[lo];"));
}

/// Emits `var s: Spawned`: particle `id`'s spawn draws from its segment's emitter (`seg`, the
/// emitter's counter `k`) at spawn step `born`, the same as the stateful `spawn` kernel's;
/// `none` ends the function when the effect has no emitter.
fn emit_spawn_draws(w: &mut Writer, ir: &EffectIr, id: &str, born: &str, none: &str) {
    w.line("var s: Spawned;");
    w.block("switch seg.a.w", |w| {
        if ir.emitters.is_empty() {
            w.block("default", |w| w.line(none));
        }
        for e in 0..ir.emitters.len() {
            let label = if e + 1 == ir.emitters.len() {
                format!("case {e}u, default")
            } else {
                format!("case {e}u")
            };
            w.block(label, |w| w.line(format!("s = emit_{e}({id}, k, {born});")));
        }
    });
}

/// Emits `evaluate_slot` (one particle of the view) and `evaluate`, which writes the view: each
/// thread stores its own particle's words, which the word-major layout puts where a warp's
/// stores cover contiguous memory ([`crate::base::kernel::word_index`]). (With particle-major words,
/// a thread storing its own particle left every store half-coalesced, well short of a
/// write-only kernel's bandwidth, and staging them through workgroup memory cost a barrier
/// that CPU adapters pay dearly for: docs/performance.md, "Stateless effects".)
pub(crate) fn emit(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    let dead_fields: Vec<&str> = layout
        .words()
        .iter()
        .map(|(name, ty)| match (*name, *ty) {
            ("id", _) => "DEAD",
            (_, "f32") => "0.0",
            _ => "0u",
        })
        .collect();
    emit_evaluate_at(w, ir);
    w.blank();
    w.comment("The particle in global slot `slot` of this frame, or a free slot.");
    w.block("fn evaluate_slot(slot: u32) -> Particle", |w| {
        w.line("let e = evaluate_at(slot);");
        w.block("if (!e.alive)", |w| {
            w.line(format!("return Particle({});", dead_fields.join(", ")));
        });
        // In the struct's order (the layout's: the id beside the position).
        let fields: Vec<&str> = layout
            .attributes
            .iter()
            .flat_map(|a| match a {
                Attribute::Position => vec!["e.now.x.x", "e.now.x.y", "e.now.x.z"],
                Attribute::DeathStep => vec!["e.now.die_at"],
                Attribute::Id => vec!["e.id"],
                // A closed form's motion is its velocity.
                Attribute::Velocity | Attribute::Displacement => {
                    vec!["e.now.v.x", "e.now.v.y", "e.now.v.z"]
                }
                // A view stores no spawn step or tint (`needs_spawn_step` and `stores_tint` are
                // for stateful groups only).
                // ...nor declared attributes (an effect that keeps any is stateful).
                Attribute::SpawnStep | Attribute::Tint | Attribute::User { .. } => vec![],
            })
            .collect();
        w.line(format!("return Particle({});", fields.join(", ")));
    });
    w.blank();
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn evaluate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "local", Some("chunk.len"));
            w.line("store_particle(local, evaluate_slot(chunk.base + local));");
        },
    );
}

/// Emits a firing stateless group's `fire` kernel. It runs once a step over
/// `fire_frame`, the segments that may hold live particles at any step of the submission: a
/// particle spawned by the step in `fire_state` and not dead before it fires, at the end of
/// the step, what its events' triggers say (`Death` in the step its lifetime ends, `Every(P)`
/// after every P steps lived), with its closed form at that moment. `fire_state` holds the
/// step: the runtime writes every step of the submission at an offset of its own and binds the
/// step's at a dynamic offset (a one-thread kernel advancing it cost a dispatch a step). The
/// same contract as the stateful update's firings (`events.rs`): the f64 reference steps the
/// same particles.
pub(crate) fn emit_fire(w: &mut Writer, ir: &EffectIr) {
    if ir.events.is_empty() {
        return;
    }
    w.comment("Fires this step's events of the particles in fire_frame (see wgsl/stateless.rs).");
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn fire(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "t", Some("fire_frame.threads"));
            emit_segment_of(w, "fire_frame", "t", SegmentSearch::Eighths);
            w.line("let step = fire_state[0];");
            w.line("let born = seg.b.y;");
            w.comment("Spawned by a later step of the submission: nothing yet.");
            w.block("if (born > step)", |w| w.line("return;"));
            w.line("let j = t - seg.a.x;");
            w.line("let id = seg.a.y + j;");
            w.line("let k = seg.a.z + j;");
            emit_spawn_draws(w, ir, "id", "born", "return;");
            if ir.has_lifetimes() {
                w.comment("It dies in the update of step die_at (the stateful update's `step >= die_at`).");
                w.block("if (s.die_at != DEAD && step > s.die_at)", |w| {
                    w.line("return;")
                });
                w.line("let dies = s.die_at != DEAD && step == s.die_at;");
            } else {
                // The spawn draws set no death step then (`die_at` stays 0): read as one, it
                // ended every particle at its spawn step, firing `Every` once and `Death` then.
                w.comment("No emitter sets a lifetime: every particle lives forever.");
                w.line("let dies = false;");
            }
            w.line("let lived = step + 1u - born;");
            w.line(format!(
                "let now = advance(s, f32(lived) * {});",
                crate::base::writer::f32_lit(ir.dt)
            ));
            crate::features::events::emit_fire_appended(
                w,
                &ir.events,
                "id",
                "now.x",
                "now.v",
                &crate::features::looks::tint::packed_wgsl_of_id(ir.tint(), "id"),
            );
        },
    );
}
