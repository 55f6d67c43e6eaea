//! The fused `update` kernel: for every live particle, all substeps of forces + integrator +
//! max speed + swept collisions, then ageing, lifetime and kill volumes, in one pass. A dying
//! particle frees its slot by pushing it on the free list.
//!
//! The update is *staged*: the workgroup first copies its particles' words into workgroup
//! memory with consecutive lanes reading consecutive 16-byte words (the copy kernel's
//! access pattern), each lane updates its particle there, and the words of the particles that
//! changed are written back the same way. Before, each lane read its own particle's words, so a
//! warp's load touched every other 16 bytes of a 1 KiB span: 0.86 of the copy kernel from 10M
//! particles up on an H100, 0.88 staged (docs/performance.md, "The update at large sizes").

use crate::events::TriggerIr;
use crate::integrators;
use crate::ir::{EffectIr, KillIr};
use crate::passes::layout::{Attribute, Layout};
use crate::wgsl::writer::{f32_lit, vec3_lit, Writer};

/// The largest particle (in 16-byte words) the staged update holds: 256 lanes x 4 words x 16
/// bytes is WebGPU's default limit of 16 KiB of workgroup memory. Every layout fits today (the
/// largest has 9 four-byte fields, 3 words); `layout_fits_the_staged_update` checks it.
pub const MAX_STAGED_VEC4S: u32 = 4;

/// Emits `update` (see the module doc).
pub fn emit(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    assert!(
        layout.vec4s() <= MAX_STAGED_VEC4S,
        "a particle of {} words does not fit the staged update",
        layout.vec4s()
    );
    w.comment("The workgroup's particles, as the update reads and writes them.");
    w.line("var<workgroup> staged: array<vec4<u32>, WORKGROUP * VEC4S>;");
    w.line("var<workgroup> staged_dirty: array<u32, WORKGROUP>;");
    crate::wgsl::emit_staged_access(w, layout);
    w.blank();
    w.comment("One particle's update on its staged words; true when they changed.");
    w.block("fn update_particle(i: u32, lane: u32) -> bool", |w| {
        w.block("if (i >= chunk.len)", |w| w.line("return false;"));
        crate::events::emit_update_reset(w, &ir.events);
        w.line("var p = load_staged(lane);");
        emit_body(w, ir, layout);
    });
    w.blank();
    w.line("@compute @workgroup_size(WORKGROUP)");
    w.block(
        "fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lane: u32)",
        |w| {
            crate::wgsl::emit_thread_index(w, "i", None);
            w.line("let words = chunk.len * VEC4S;");
            w.line("let first = (i - lane) * VEC4S;");
            w.comment("Consecutive lanes move consecutive words, as the copy kernel does.");
            w.block("for (var r = 0u; r < VEC4S; r++)", |w| {
                w.line("let k = r * WORKGROUP + lane;");
                w.block("if (first + k < words)", |w| {
                    w.line("staged[k] = particles[first + k];")
                });
            });
            w.line("workgroupBarrier();");
            w.line("staged_dirty[lane] = select(0u, 1u, update_particle(i, lane));");
            w.line("workgroupBarrier();");
            w.block("for (var r = 0u; r < VEC4S; r++)", |w| {
                w.line("let k = r * WORKGROUP + lane;");
                w.block("if (first + k < words && staged_dirty[k / VEC4S] != 0u)", |w| {
                    w.line("particles[first + k] = staged[k];")
                });
            });
        },
    );
}

/// The update of the particle `p` (already loaded), from the dead check to the store.
fn emit_body(w: &mut Writer, ir: &EffectIr, layout: &Layout) {
    let verlet = layout.has(Attribute::Displacement);
    let lifetimes = layout.has(Attribute::DeathStep);
    w.block("if (p.id == DEAD)", |w| w.line("return false;"));
    if let Some(flock) = &ir.flock {
        flock.emit_update_prologue(w);
    }
    if ir.custom_terms().any(|c| c.needs_context()) {
        crate::forces::custom::emit_set_context(
            w,
            ir.dt,
            "p.id",
            layout.has(Attribute::SpawnStep).then_some("p.born"),
            lifetimes.then_some("p.die_at"),
        );
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
    let body = |w: &mut Writer| {
        if !ir.colliders.is_empty() {
            w.line("let x_start = x;");
        }
        integrators::emit_step(w, ir);
        if !ir.colliders.is_empty() {
            crate::colliders::emit_resolve(
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
    if collide_events && !ir.colliders.is_empty() {
        w.block("if (collided)", |w| {
            crate::events::emit_fire(w, &ir.events, |t| t == TriggerIr::Collide, "x", &vel)
        });
    }
    crate::events::emit_fire(
        w,
        &ir.events,
        |t| matches!(t, TriggerIr::Every(_)),
        "x",
        &vel,
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
            crate::events::emit_fire(w, &ir.events, |t| t == TriggerIr::Death, "x", &vel);
            w.line("mark_staged_free(lane);");
            w.line("let top = atomicAdd(&counters.free_count, 1u);");
            w.line("free_list[top] = chunk.base + i;");
            w.line("atomicAdd(&counters.died, 1u);");
            w.line("return true;");
        });
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
    w.line("store_staged(lane, p);");
    w.line("return true;");
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

#[cfg(test)]
mod tests {
    use super::MAX_STAGED_VEC4S;
    use crate::passes::layout::Attribute;

    #[test]
    fn layout_fits_the_staged_update() {
        let every = [
            Attribute::Position,
            Attribute::Velocity,
            Attribute::Displacement,
            Attribute::DeathStep,
            Attribute::Id,
            Attribute::SpawnStep,
        ];
        let bytes: u32 = every.iter().map(|a| a.bytes()).sum();
        assert!(bytes.div_ceil(16) <= MAX_STAGED_VEC4S, "{bytes} bytes");
    }
}
