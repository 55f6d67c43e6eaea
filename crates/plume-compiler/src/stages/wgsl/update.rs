//! The fused `update` kernel: for every live particle, all substeps of forces + integrator +
//! max speed + swept collisions, then ageing, lifetime and kill volumes, in one pass. A dying
//! particle frees its slot by pushing it on the free list, and a firing particle appends its id
//! and slot to its event's stream, a workgroup's at a time.
//!
//! Each thread updates the particle of its slot, loading and storing its 16-byte words where
//! the word-major layout puts them ([`crate::base::kernel::word_index`]): across a warp every access
//! covers contiguous memory, as in a copy kernel, and no thread waits for another. The update
//! of an earlier version staged a workgroup's particle-major words through workgroup memory
//! to coalesce them, and fell short of the copy kernel's bandwidth, with a barrier on each
//! side of the arithmetic (docs/performance.md, "The update at large sizes").

use crate::base::writer::{f32_lit, vec3_lit, Writer};
use crate::features::events::TriggerIr;
use crate::ir::{EffectIr, KillIr};
use crate::stages::integrators;
use crate::stages::passes::layout::{Attribute, Layout};

/// Emits `update` (see the module doc).
pub(crate) fn emit(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    w.comment("One particle's update: loaded, advanced, stored (or freed) in place. Returns its outcome: bit 0 whether it died, bit 1 + j whether it fired event j; and its id.");
    w.block("fn update_particle(i: u32) -> vec2<u32>", |w| {
        if reads_whole_slots(ir) {
            w.comment("Most slots live: every word loaded at once, no load waiting on another.");
            w.line("var p = load_particle(i);");
            w.block("if (p.id == DEAD)", |w| w.line("return vec2<u32>(0u, 0u);"));
        } else {
            w.comment("A free slot's id word is all the update reads of it.");
            w.block("if (slot_is_free(i))", |w| {
                w.line("return vec2<u32>(0u, 0u);")
            });
            w.line("var p = load_particle(i);");
        }
        emit_body(w, ir, layout);
    });
    w.blank();
    if layout.batched {
        emit_hold(w, layout);
        w.blank();
    }
    if !appends(ir, layout) {
        w.line("@compute @workgroup_size(WORKGROUP)");
        w.block(
            "fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
            |w| {
                if layout.batched {
                    crate::stages::wgsl::batch::emit_instance(w, layout, "gid.z");
                    crate::base::kernel::emit_thread_index(w, "local", Some("CAPACITY"));
                    w.line("let i = inst * CAPACITY + local;");
                    w.block("if (params.batch.x == 0u)", |w| {
                        w.line("hold_particle(i);");
                        w.line("return;");
                    });
                } else {
                    crate::base::kernel::emit_thread_index(w, "i", Some("chunk.len"));
                }
                w.line("_ = update_particle(i);");
            },
        );
        return;
    }
    let counters = crate::stages::wgsl::batch::counters(layout);
    if ir.events.is_empty() && ir.event_inputs.is_empty() && !layout.batched {
        emit_update_freeing_each(w, counters);
        return;
    }
    // A workgroup's deaths and firings are appended together: a workgroup atomic each, then
    // one global atomic a workgroup. One global atomic a death or firing (rain at 10M: 180k
    // deaths and 37k firings a step, each adding to the same few words) serialised them.
    w.comment(
        "This workgroup's deaths and firings, and where they go in the free list and the streams.",
    );
    w.line("var<workgroup> wg_deaths: atomic<u32>;");
    w.line("var<workgroup> wg_death_base: u32;");
    use crate::features::events::{emit_workgroup_appends, AppendPart};
    emit_workgroup_appends(w, &ir.events, AppendPart::Declarations);
    w.blank();
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lane: u32)",
        |w| {
            crate::stages::wgsl::batch::emit_instance(w, layout, "gid.z");
            let bound = match layout.batched {
                true => {
                    crate::base::kernel::emit_thread_index(w, "local", None);
                    w.line("let i = inst * CAPACITY + local;");
                    "local < CAPACITY"
                }
                false => {
                    crate::base::kernel::emit_thread_index(w, "i", None);
                    "i < chunk.len"
                }
            };
            w.block("if (lane == 0u)", |w| {
                w.line("atomicStore(&wg_deaths, 0u);");
                emit_workgroup_appends(w, &ir.events, AppendPart::Reset);
            });
            w.line("workgroupBarrier();");
            w.line("var outcome = vec2<u32>(0u, 0u);");
            w.block(format!("if ({bound})"), |w| {
                if layout.batched {
                    w.comment("A paused instance's particles keep their ages: no update.");
                    w.block("if (params.batch.x == 0u)", |w| w.line("hold_particle(i);"));
                    w.block("else", |w| w.line("outcome = update_particle(i);"));
                } else {
                    w.line("outcome = update_particle(i);");
                }
            });
            w.line("var death_at = 0u;");
            w.block("if ((outcome.x & 1u) != 0u)", |w| {
                w.line("death_at = atomicAdd(&wg_deaths, 1u);")
            });
            emit_workgroup_appends(w, &ir.events, AppendPart::Place);
            w.line("workgroupBarrier();");
            w.block("if (lane == 0u)", |w| {
                w.line("let deaths = atomicLoad(&wg_deaths);");
                w.block("if (deaths > 0u)", |w| {
                    w.line(format!(
                        "wg_death_base = atomicAdd(&{counters}.free_count, deaths);"
                    ));
                    w.line(format!("atomicAdd(&{counters}.died, deaths);"));
                });
                emit_workgroup_appends(w, &ir.events, AppendPart::Reserve);
            });
            w.line("workgroupBarrier();");
            w.block("if ((outcome.x & 1u) != 0u)", |w| {
                w.line(format!(
                    "free_list[{}wg_death_base + death_at] = chunk.base + i;",
                    crate::stages::wgsl::batch::free_list_base(layout)
                ))
            });
            emit_workgroup_appends(w, &ir.events, AppendPart::Write);
        },
    );
}

/// `update` for an effect that runs alone (not batched), fires no events and is fed by none:
/// each dying particle pushes its slot on the free list with a global atomic of its own. No
/// barrier holds a workgroup's threads together, so a thread that finishes early makes room
/// for the next; appending a workgroup's deaths together takes three barriers, which slow an
/// update with much arithmetic (docs/performance.md, "The update at large sizes"). Groups
/// with events keep that: their firings go to few words, and the particles events spawn die
/// in crowds, whose atomics on one word would queue.
fn emit_update_freeing_each(w: &mut Writer, counters: &str) {
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::base::kernel::emit_thread_index(w, "i", Some("chunk.len"));
            w.line("let outcome = update_particle(i);");
            w.block("if ((outcome.x & 1u) != 0u)", |w| {
                w.line(format!("let top = atomicAdd(&{counters}.free_count, 1u);"));
                w.line("free_list[top] = chunk.base + i;");
                w.line(format!("atomicAdd(&{counters}.died, 1u);"));
            });
        },
    );
}

/// Whether the update loads a slot's every word at once, then tests its id: where most slots
/// hold a live particle (the emitters keep at least half the capacity alive) and the group
/// has no events (an event-fed group's count nobody knows, and a graph's steps were measured
/// as they are), so that no load waits on the id word's. Elsewhere it reads the id word first
/// and a free slot's other words not at all
/// (docs/performance.md, "The update at large sizes", has what each costs where).
fn reads_whole_slots(ir: &EffectIr) -> bool {
    ir.events.is_empty()
        && ir.event_inputs.is_empty()
        && 2 * ir.expected_alive() >= u64::from(ir.capacity)
}

/// `hold_particle(i)`: a batched instance's particle on a step its instance sits out (paused,
/// or slower than the batch): the batch's step index goes on, so its death step and spawn step
/// move on with it, and its age, which the kernels and the draw reckon from them, stays.
fn emit_hold(w: &mut Writer, layout: &Layout) {
    w.comment("A paused instance's particle: its steps move on with the batch's, its age stays.");
    w.block("fn hold_particle(i: u32)", |w| {
        w.line("var p = load_particle(i);");
        w.block("if (p.id == DEAD)", |w| w.line("return;"));
        if layout.has(Attribute::DeathStep) {
            w.comment("0xffffffff: a particle that never dies.");
            w.block("if (p.die_at != 0xffffffffu)", |w| {
                w.line("p.die_at = p.die_at + 1u;")
            });
        }
        if layout.has(Attribute::SpawnStep) {
            w.line("p.born = p.born + 1u;");
        }
        w.line("store_particle(i, p);");
    });
}

/// Whether the update appends anything: deaths to the free list, firings to their streams.
fn appends(ir: &EffectIr, layout: &Layout) -> bool {
    layout.has(Attribute::DeathStep) || !ir.kills.is_empty() || !ir.events.is_empty()
}

/// The update of the live particle `p` (already loaded), from the forces to the store.
fn emit_body(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    let verlet = layout.has(Attribute::Displacement);
    let lifetimes = layout.has(Attribute::DeathStep);
    if let Some(flock) = &ir.flock {
        flock.emit_update_prologue(w);
    }
    let kept = ir.kept_attributes();
    // Attribute i's value before the step, from its stored words.
    let stored = |i: usize| {
        let fields = layout.user_fields(i).unwrap_or(&[]);
        match fields.len() {
            1 => format!("p.{}", fields[0]),
            _ => format!(
                "vec3<f32>({})",
                fields
                    .iter()
                    .map(|f| format!("p.{f}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    };
    let changes = ir.attributes.iter_kept(kept).any(|(_, a)| a.changes());
    if ir.custom_terms().any(|c| c.needs_context()) || changes {
        crate::features::forces::custom::emit_set_context(
            w,
            ir.dt,
            "p.id",
            layout.has(Attribute::SpawnStep).then_some("p.born"),
            lifetimes.then_some("p.die_at"),
        );
        ir.attributes
            .emit_set_context(w, ir.attributes_forces_read(), stored);
    }
    w.line("var x = vec3<f32>(p.px, p.py, p.pz);");
    if verlet {
        w.line("var d = vec3<f32>(p.dx, p.dy, p.dz);");
    } else {
        w.line("var v = vec3<f32>(p.vx, p.vy, p.vz);");
    }
    if let Some(trail) = &ir.render.trail {
        trail.emit_record(w);
    }
    let collide_events = ir.events.iter().any(|e| e.trigger == TriggerIr::Collide);
    if collide_events && !ir.colliders.is_empty() {
        w.line("var collided = false;");
    }
    // The events fired (bits 1 + j), where there are events.
    let fired = if ir.events.is_empty() {
        "0u"
    } else {
        w.line("var fired = 0u;");
        "fired"
    };
    let body = |w: &mut Writer| {
        if !ir.colliders.is_empty() {
            w.line("let x_start = x;");
        }
        integrators::emit_step(w, ir);
        if !ir.colliders.is_empty() {
            crate::features::colliders::emit_resolve(
                w,
                &ir.colliders,
                ir.rest_speed(),
                ir.h(),
                verlet,
                collide_events.then_some("collided"),
            );
        }
    };
    if ir.substeps == 1 {
        w.line("let t = params.time;");
        body(w);
    } else {
        w.block(
            format!("for (var s = 0u; s < {}u; s++)", ir.substeps),
            |w| {
                w.line(format!(
                    "let t = params.time + f32(s) * {};",
                    f32_lit(ir.h())
                ));
                body(w);
            },
        );
    }
    // Events fire with the position and velocity the step leaves.
    let vel = if verlet {
        format!("d * {}", f32_lit(1.0 / ir.h()))
    } else {
        "v".to_string()
    };
    // ...and the tint their children may inherit.
    let tint = crate::features::looks::tint::packed_wgsl(ir.tint(), "p");
    // ...and the attributes their children inherit, as the step began.
    let words = |a: usize| {
        let fields = layout.user_fields(a).unwrap_or(&[]);
        let word = |c: usize| {
            fields
                .get(c)
                .map_or("0.0".to_string(), |f| format!("p.{f}"))
        };
        [word(0), word(1), word(2)]
    };
    let passed = |w: &mut Writer, j: usize| {
        crate::features::inherit::emit_pass(w, j, &ir.events[j], &words);
    };
    if collide_events && !ir.colliders.is_empty() {
        w.block("if (collided)", |w| {
            crate::features::events::emit_fire(
                w,
                &ir.events,
                |t| t == TriggerIr::Collide,
                ("x", &vel, &tint),
                &passed,
            )
        });
    }
    crate::features::events::emit_fire(
        w,
        &ir.events,
        |t| matches!(t, TriggerIr::Every(_)),
        ("x", &vel, &tint),
        &passed,
    );
    // Only effects with lifetimes or kill volumes get the death code.
    if lifetimes || !ir.kills.is_empty() {
        w.line("var dies = false;");
        if lifetimes {
            w.line("dies = params.step >= p.die_at;");
        }
        for k in &ir.kills {
            emit_kill(w, k);
        }
        w.block("if (dies)", |w| {
            crate::features::events::emit_fire(
                w,
                &ir.events,
                |t| t == TriggerIr::Death,
                ("x", &vel, &tint),
                &passed,
            );
            w.line("mark_free(i);");
            let died = if ir.events.is_empty() {
                "1u".to_string()
            } else {
                format!("{fired} | 1u")
            };
            w.line(format!("return vec2<u32>({died}, p.id);"));
        });
    }
    if changes {
        w.comment("The attributes change once a step, all from their values before it (a dying particle's are not needed).");
        let args = ir.attributes.args_wgsl(kept, |i| {
            let fields = layout.user_fields(i).unwrap_or(&[]);
            fields.iter().map(|f| format!("p.{f}")).collect()
        });
        for (i, _) in ir.attributes.iter_kept(kept).filter(|(_, a)| a.changes()) {
            w.line(format!(
                "let na{i} = attr_change_{i}(x, {vel}, params.time, ctx_age0, ctx_life, p.id{args});"
            ));
        }
        for (i, a) in ir.attributes.iter_kept(kept).filter(|(_, a)| a.changes()) {
            let fields = layout.user_fields(i).unwrap_or(&[]);
            match a.width() {
                1 => w.line(format!("p.{} = na{i};", fields[0])),
                _ => {
                    for (f, c) in fields.iter().zip(["x", "y", "z"]) {
                        w.line(format!("p.{f} = na{i}.{c};"));
                    }
                }
            }
        }
    }
    w.line("p.px = x.x;");
    w.line("p.py = x.y;");
    w.line("p.pz = x.z;");
    if verlet {
        w.line("p.dx = d.x;");
        w.line("p.dy = d.y;");
        w.line("p.dz = d.z;");
    } else {
        w.line("p.vx = v.x;");
        w.line("p.vy = v.y;");
        w.line("p.vz = v.z;");
    }
    w.line("store_moved(i, p);");
    w.line(format!("return vec2<u32>({fired}, p.id);"));
}

fn emit_kill(w: &mut Writer, k: &KillIr) {
    match *k {
        KillIr::InsideBox(min, max) => w.line(format!(
            "dies = dies || (all(x >= {}) && all(x <= {}));",
            vec3_lit(min),
            vec3_lit(max)
        )),
        KillIr::OutsideBox(min, max) => w.line(format!(
            "dies = dies || !(all(x >= {}) && all(x <= {}));",
            vec3_lit(min),
            vec3_lit(max)
        )),
        KillIr::InsideSphere(c, r) => w.line(format!(
            "dies = dies || dot(x - {c}, x - {c}) < {};",
            f32_lit(r * r),
            c = vec3_lit(c)
        )),
        KillIr::OutsideSphere(c, r) => w.line(format!(
            "dies = dies || dot(x - {c}, x - {c}) > {};",
            f32_lit(r * r),
            c = vec3_lit(c)
        )),
    }
}
