//! The spawn kernels. `spawn_prepare` (one thread) pops this step's slots off the free list:
//! n = min(requested, free), the rest counted as dropped (live particles are never
//! overwritten). `spawn` then initialises particle `first_id + i` in slot
//! `free_list[spawn_base + i]`: its emitter, position, velocity and lifetime come from the
//! IR and the integer hash of (seed, id, stream), so the CPU reference draws the same.

use crate::base::rng::stream;
use crate::base::writer::{f32_lit, Writer};
use crate::ir::{EffectIr, EmitterIr};
use crate::stages::passes::layout::{Attribute, Layout};

/// Emits `spawn_prepare` and `spawn`.
pub(crate) fn emit(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    w.comment(
        "Pops this step's slots: never more than are free; the rest are dropped and counted.",
    );
    let counters = crate::stages::wgsl::batch::counters(layout);
    w.line("@compute @workgroup_size(1)");
    let prepare_args = match layout.batched {
        true => "@builtin(global_invocation_id) gid: vec3<u32>",
        false => "",
    };
    w.block(format!("fn spawn_prepare({prepare_args})"), |w| {
        crate::stages::wgsl::batch::emit_instance(w, layout, "gid.z");
        w.line(format!("let free = atomicLoad(&{counters}.free_count);"));
        w.line("let n = min(params.requested, free);");
        w.line(format!("atomicStore(&{counters}.free_count, free - n);"));
        w.line(format!("{counters}.spawn_base = free - n;"));
        w.line(format!("{counters}.spawn_count = n;"));
        w.line(format!("{counters}.spawned = {counters}.spawned + n;"));
        w.line(format!(
            "{counters}.dropped = {counters}.dropped + (params.requested - n);"
        ));
    });
    w.blank();
    emit_emitter_fns(w, ir);
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn spawn(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            crate::stages::wgsl::batch::emit_instance(w, layout, "gid.z");
            let bound = format!("{counters}.spawn_count");
            crate::base::kernel::emit_thread_index(w, "i", Some(&bound));
            w.line(format!(
                "let slot = free_list[{}{counters}.spawn_base + i];",
                crate::stages::wgsl::batch::free_list_base(layout)
            ));
            w.comment("Dispatched once per chunk: only the chunk that holds the slot writes it.");
            w.block("if (slot < chunk.base || slot - chunk.base >= chunk.len)", |w| w.line("return;"));
            w.line("let id = params.first_id + i;");
            w.comment("Find the emitter: ids are handed out to emitters in the order they are listed.");
            w.line("var e = 0u;");
            w.line("var local = i;");
            w.block(format!("for (; e < {}u; e++)", layout.emitter_slots), |w| {
                w.block("if (local < params.emitters[e].x)", |w| w.line("break;"));
                w.line("local = local - params.emitters[e].x;");
            });
            if layout.bursts {
                w.line(format!("var burst = {}u;", crate::features::bursts::SLOTS));
                w.line("var k = 0u;");
                w.block(format!("if (e < {}u)", layout.emitter_slots), |w| {
                    w.line("k = params.emitters[e].y + local;");
                });
                w.block("else", crate::features::bursts::emit_find);
            } else {
                w.line("let k = params.emitters[e].y + local;");
            }
            w.line("var s: Spawned;");
            if ir.emitters.is_empty() {
                w.line("return;");
            } else {
                w.block("switch e", |w| {
                    for e in 0..ir.emitters.len() {
                        let label = if e + 1 == ir.emitters.len() {
                            format!("case {e}u, default")
                        } else {
                            format!("case {e}u")
                        };
                        w.block(label, |w| {
                            w.line(format!("s = emit_{e}(id, k, params.step);"))
                        });
                    }
                });
                if layout.bursts {
                    crate::features::bursts::emit_apply(w);
                }
                if ir.placed {
                    crate::features::placement::emit_apply(w);
                }
                if layout.has(Attribute::Tint) {
                    w.line(format!(
                        "let tint = pack4x8unorm(vec4<f32>({}, 1.0));",
                        crate::features::looks::tint::own_wgsl(ir.tint(), "id")
                    ));
                }
                emit_store_spawned(w, ir, layout, None);
                if let Some(ribbon) = &ir.render.ribbon {
                    let (key, ordinal) = ribbon.emitted_wgsl(ir.emitters.len() as u32);
                    ribbon.emit_write(w, &key, &ordinal);
                }
            }
        },
    );
    if !ir.event_inputs.is_empty() {
        w.blank();
        let own = crate::features::looks::tint::own_wgsl(ir.tint(), "id");
        crate::features::events::emit_kernels(
            w,
            &ir.event_inputs,
            layout.has(Attribute::Tint).then_some(own.as_str()),
            &|j| ir.emitters[ir.event_inputs[j].emitter].reads_origin(),
            &|w, j| {
                crate::features::inherit::emit_find(
                    w,
                    &ir.event_inputs[j],
                    crate::features::events::in_order(j),
                );
                emit_store_spawned(w, ir, layout, Some(j))
            },
            ir.render.ribbon.as_ref(),
        );
    }
}

/// Emits the store of the spawned particle `s` (a `Spawned`) with id `id` into `slot` (a
/// global slot this chunk holds), as every spawn kernel ends: Verlet's first displacement,
/// the lifetime, the id and the spawn step as the layout has them.
pub(crate) fn emit_store_spawned(
    w: &mut Writer,
    ir: &EffectIr,
    layout: &Layout,
    input: Option<usize>,
) {
    let kept = ir.kept_attributes();
    // The step its age counts from.
    let born = match ir.has_start_ages() {
        true => "s.born",
        false => "params.step",
    };
    for (i, a) in ir.attributes.iter_kept(kept) {
        // A child of an event takes what it inherits from its parent (`inherit.rs`).
        let inherited = input.and_then(|j| {
            crate::features::inherit::taken(j, &ir.event_inputs[j], i, a.width() == 3)
        });
        match inherited {
            Some(value) => w.line(format!("let sa{i} = {value};")),
            None => w.line(format!(
                "let sa{i} = attr_spawn_{i}(s.x, s.v, params.time, id);"
            )),
        }
    }
    let motion = if layout.has(Attribute::Displacement) {
        // Verlet: store the displacement that makes step one x0 + v0 h + a h²/2.
        let h = ir.h();
        if ir.custom_terms().any(|c| c.needs_context()) {
            crate::features::forces::custom::emit_set_context(
                w,
                ir.dt,
                "id",
                layout.has(Attribute::SpawnStep).then_some(born),
                layout.has(Attribute::DeathStep).then_some("s.die_at"),
            );
            ir.attributes
                .emit_set_context(w, ir.attributes_forces_read(), |i| format!("sa{i}"));
        }
        w.line(format!(
            "let d = s.v * {} - accel(s.x, s.v, params.time) * {};",
            f32_lit(h),
            f32_lit(0.5 * h * h)
        ));
        ["d.x", "d.y", "d.z"]
    } else {
        ["s.v.x", "s.v.y", "s.v.z"]
    };
    // In the layout's attribute order.
    let fields: Vec<String> = layout
        .attributes
        .iter()
        .flat_map(|a| match *a {
            Attribute::Position => vec!["s.x.x".into(), "s.x.y".into(), "s.x.z".into()],
            Attribute::Velocity | Attribute::Displacement => {
                motion.iter().map(|m| m.to_string()).collect()
            }
            Attribute::DeathStep => vec!["s.die_at".into()],
            Attribute::Id => vec!["id".into()],
            Attribute::SpawnStep => vec![born.into()],
            Attribute::Tint => vec!["tint".into()],
            Attribute::User {
                index, width: 1, ..
            } => vec![format!("sa{index}")],
            Attribute::User { index, .. } => ["x", "y", "z"]
                .iter()
                .map(|c| format!("sa{index}.{c}"))
                .collect(),
        })
        .collect();
    w.line(format!(
        "store_particle(slot - chunk.base, Particle({}));",
        fields.join(", ")
    ));
}

/// Emits `emit_E(id, k, step) -> Spawned` for every emitter (shared by `spawn` and the
/// stateless `evaluate`), each followed by a blank line.
pub(crate) fn emit_emitter_fns(w: &mut Writer, ir: &EffectIr) {
    if ir.emitters.iter().any(|e| e.reads_origin()) {
        w.comment("Where the spawn's frame sits (`origin`): an event spawn sets the firing particle's position before emit_E; zero for an emitter's.");
        w.line("var<private> spawn_origin: vec3<f32>;");
        w.blank();
    }
    for (e, em) in ir.emitters.iter().enumerate() {
        emit_emitter_fn(w, ir, e, em);
        w.blank();
    }
}

/// A function per emitter: `emit_E(id, k, step) -> Spawned`, k the emitter's own spawn counter
/// and `step` the step it spawns at.
fn emit_emitter_fn(w: &mut Writer, ir: &EffectIr, e: usize, em: &EmitterIr) {
    em.emit_items(
        w,
        e,
        crate::features::emitter::spawn_data_offset(&ir.emitters, e),
    );
    w.block(
        format!("fn emit_{e}(id: u32, k: u32, step: u32) -> Spawned"),
        |w| {
            w.line("var s: Spawned;");
            em.emit_wgsl(w, e);
            // With starting ages, the step a particle's age and lifetime count from.
            let from = match (ir.has_start_ages(), em.age_steps) {
                (false, _) => "step",
                (true, None) => {
                    w.line("s.born = step;");
                    "s.born"
                }
                (true, Some(ages)) => {
                    w.comment("Its starting age in whole steps, drawn as a lifetime is.");
                    w.line(format!(
                        "let lu_age = rand_u32(id, {}u);",
                        stream::START_AGE
                    ));
                    w.line(format!("s.born = step - ({});", ages.wgsl_of("lu_age")));
                    "s.born"
                }
            };
            match em.lifetime_steps {
                Some(steps) => {
                    w.comment(
                        "Whole steps lived, drawn with integer arithmetic (see lifetime.rs).",
                    );
                    w.line(format!("let lu = rand_u32(id, {}u);", stream::LIFETIME));
                    w.line(format!("s.die_at = {from} + ({}) - 1u;", steps.wgsl()));
                }
                None if ir.has_lifetimes() => {
                    w.comment("Lives forever.");
                    w.line("s.die_at = DEAD;");
                }
                None => {}
            }
            w.line("return s;");
        },
    );
}
