//! The layout pass: the particle struct holds only the attributes this effect needs, as scalar
//! f32/u32 fields (no vec3 padding), so bytes per particle are the fewest the kernels read and
//! write. The types live in `base::layout`, below the features that read them.

use std::fmt;

pub use crate::base::layout::{Attribute, Binding, Layout, Planes, Role, Space, COUNTERS_BYTES};
use crate::ir::EffectIr;
use crate::stages::schema::Integrator;

/// The one lifetime draw that every emitter with a lifetime shares, when there is one: then a
/// particle's whole-step lifetime is a function of its id alone (the draw of stream
/// [`crate::base::rng::stream::LIFETIME`]), and with `die_at` it gives the spawn step.
pub fn shared_lifetime(ir: &EffectIr) -> Option<crate::base::lifetime::LifetimeSteps> {
    let mut draws = ir.emitters.iter().filter_map(|e| e.lifetime_steps);
    let first = draws.next()?;
    draws.all(|d| d == first).then_some(first)
}

/// Whether a stateful particle stores its spawn step (`born`): only when the draw needs a life
/// fraction (gradients, a flipbook played over life) and cannot derive the spawn step from
/// `die_at` and the shared lifetime draw, or needs every particle's age (a flipbook played at
/// a rate, a spin) and some particles never die.
pub(crate) fn needs_spawn_step(ir: &EffectIr) -> bool {
    if ir.stateless.is_some() {
        return false;
    }
    let flipbook = ir.render.texture.as_ref().filter(|t| t.animated());
    let life = (ir.render.varies_over_life() || flipbook.is_some()) && ir.has_lifetimes();
    let age = flipbook.is_some_and(|t| t.needs_age_of_immortals())
        || ir.render.rotation.is_some_and(|r| r.spins())
        || ir.render.by.reads_age_or_life();
    let all_mortal = ir.emitters.iter().all(|e| e.lifetime.is_some());
    let shared = shared_lifetime(ir).is_some();
    (life && !shared) || (age && !(all_mortal && shared))
}

/// Whether a group fed by events can leave its spawn step out: every particle dies
/// (`die_at`) and all draw their lifetimes from one range, so a particle's spawn step is
/// `die_at + 1` less the lifetime its id draws (rain's splashes: 32 bytes a particle, not 48,
/// and a third fewer bytes scattered by each event spawn).
pub fn fed_ages_derived(ir: &EffectIr) -> bool {
    ir.has_lifetimes()
        && ir.emitters.iter().all(|e| e.lifetime.is_some())
        && shared_lifetime(ir).is_some()
}

/// Decides the layout for a resolved IR.
pub(crate) fn decide(ir: &EffectIr) -> Layout {
    let half_motion = ir.stateless.is_none() && ir.accuracy.as_ref().is_some_and(|a| a.half_motion);
    let motion = if ir.integrator == Integrator::Verlet {
        Attribute::Displacement
    } else {
        Attribute::Velocity
    };
    // The id sits beside the position, in the first 16-byte word: what reads only where live
    // particles are (the depth keys, the live bounds, the live list, freeing a slot) touches
    // that word alone. With the id in the second word, the depth keys read both words, twice
    // the bytes at the copy kernel's bandwidth (docs/performance.md, "Depth sort and the radix
    // sort").
    let mut attributes = vec![Attribute::Position, Attribute::Id, motion];
    if ir.has_lifetimes() {
        attributes.push(Attribute::DeathStep);
    }
    // `Every` events count from each particle's spawn. A group fed by events cannot derive
    // ages from ids and its schedule (only the GPU knows when each id spawned), unless every
    // particle dies and draws its lifetime from one range: then `die_at` and the lifetime
    // drawn from the id give the spawn step, as they do for the draw (`fed_ages_derived`).
    let every = ir
        .events
        .iter()
        .any(|e| matches!(e.trigger, crate::features::events::TriggerIr::Every(_)));
    let kept = ir.kept_attributes();
    if needs_spawn_step(ir)
        || (ir.has_start_ages() && ir.stateless.is_none())
        || ir.custom_terms().any(|c| c.reads_age_or_life())
        || ir.attributes.reads_age_or_life(kept)
        || (ir.stateless.is_none()
            && (every || (!ir.event_inputs.is_empty() && !fed_ages_derived(ir))))
    {
        attributes.push(Attribute::SpawnStep);
    }
    if ir.stores_tint() {
        attributes.push(Attribute::Tint);
    }
    let mut first = 0;
    for (index, a) in ir.attributes.iter_kept(kept) {
        attributes.push(Attribute::User {
            index: index as u8,
            first,
            width: a.width(),
            changes: a.changes(),
        });
        first += a.width();
    }
    // Padded to a multiple of 16 bytes so kernels move the state as whole vec4 words: scalar
    // accesses at a 28- or 32-byte stride fell far short of the copy kernel's bandwidth
    // (docs/performance.md, "The update at large sizes"). Motion in halves exists to save
    // bytes, so its layout keeps its last words in planes of 8 and 4 bytes a slot instead
    // (`Layout::planes`): word-major, every access stays coalesced.
    let words = attributes.iter().map(|a| a.bytes(half_motion)).sum::<u32>();
    let bytes_per_particle = if half_motion {
        words
    } else {
        words.next_multiple_of(16)
    };
    let cap = u64::from(ir.capacity);
    let emitter_slots = ir.emitters.len().max(1) as u32;
    let mut layout = Layout {
        attributes,
        half_motion,
        bytes_per_particle,
        bindings: Vec::new(),
        emitter_slots,
        placed: ir.placed,
        bursts: ir.bursts,
        live_params: ir.live_params.len() as u32,
        trail_bytes_per_particle: ir
            .render
            .trail
            .as_ref()
            .map_or(0, |t| t.bytes_per_particle()),
        batched: false,
        instance_slots: 0,
    };
    // Binding 0 holds the particles: their state, or for a stateless effect the view that
    // `evaluate` writes; binding 4 names the slots of this dispatch's buffer.
    let (particles, chunk) = match ir.stateless {
        Some(_) => (
            "the view: array<Particle> written afresh by `evaluate` for each frame read or drawn; no kernel reads it back, so it is not state",
            "the slots this dispatch's view buffer holds: first global slot, count",
        ),
        None => (
            "array<Particle>, one slot per capacity (split into chunks past the binding limit)",
            "the slots this dispatch's particle buffer holds: first global slot, count",
        ),
    };
    layout.bindings.push(Binding {
        binding: 0,
        role: Role::Particles,
        space: Space::ReadWrite,
        bytes: layout.buffer_bytes(cap),
        meaning: particles,
    });
    match &ir.stateless {
        Some(plan) => layout.bindings.push(Binding {
            binding: 1,
            role: Role::Frame,
            space: Space::Read,
            bytes: plan.table_bytes(),
            meaning: "bookkeeping, written by the CPU per frame: threads, segment count, steps done; per spawning (step, emitter) with live particles: first thread, first id, emitter counter, emitter, age in steps, spawn step, age in s",
        }),
        None => layout.bindings.extend([
            Binding {
                binding: 1,
                role: Role::FreeList,
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "stack of free slot indices (pushed on death, popped on spawn)",
            },
            Binding {
                binding: 2,
                role: Role::Counters,
                space: Space::ReadWrite,
                bytes: COUNTERS_BYTES + if ir.event_inputs.is_empty() { 0 } else { 8 },
                meaning: "free count, this step's spawn base and count, totals spawned, dropped, died",
            },
            Binding {
                binding: 3,
                role: Role::Params,
                space: Space::Uniform,
                bytes: layout.params_bytes(),
                meaning: if ir.wraps_kernel_time() {
                    "per step: first id, spawns requested, time mod 256 s, step index, per-emitter counts"
                } else {
                    "per step: first id, spawns requested, whole time (s: a force reads it unwrapped), step index, per-emitter counts"
                },
            },
        ]),
    }
    layout.bindings.push(Binding {
        binding: 4,
        role: Role::Chunk,
        space: Space::Uniform,
        bytes: 16,
        meaning: chunk,
    });
    if let Some(trail) = &ir.render.trail {
        layout.bindings.push(Binding {
            binding: 16,
            role: Role::Trail,
            space: Space::ReadWrite,
            bytes: cap * u64::from(trail.bytes_per_particle()),
            meaning: "trail ring, points - 1 entries per slot (entry r of slot i at i * (points - 1) + r; split into chunks with the particles): the position's f32 bits and id + 1 (0: never written)",
        });
    }
    if let Some(ribbon) = &ir.render.ribbon {
        layout.bindings.push(Binding {
            binding: crate::features::looks::ribbon::RIBBON_TABLE_BINDING,
            role: Role::RibbonTable,
            space: Space::ReadWrite,
            bytes: ribbon.table_bytes(),
            meaning: "the ribbon table (render.ribbon), points entries per ribbon: per particle spawned, its slot, id + 1 (0: never written), key and ordinal, at entry (key mod ribbons) * points + ordinal mod points",
        });
    }
    if let Some(field) = &ir.field {
        layout.bindings.push(Binding {
            binding: 13,
            role: Role::Field,
            space: Space::ReadWrite,
            bytes: field.nodes() * 16,
            meaning: "the baked force field: one (a, 0) per node, x fastest",
        });
    }
    if let Some(data) = crate::features::forces::force_data(&ir.terms) {
        layout.bindings.push(Binding {
            binding: 21,
            role: Role::ForceData,
            space: Space::Read,
            bytes: data.len() as u64 * 4,
            meaning: "the vector field's samples: x, y, z of each node, x fastest, then y, then z",
        });
    }
    if let Some(data) = crate::features::emitter::spawn_data(&ir.emitters) {
        layout.bindings.push(Binding {
            binding: 22,
            role: Role::SpawnData,
            space: Space::Read,
            bytes: data.len() as u64 * 4,
            meaning: "the mesh emitters' surfaces: per emitter, a 32-bit area threshold per triangle, then its a, b - a, c - a and normal (f32 bits)",
        });
    }
    if ir.has_collider_data() {
        layout.bindings.push(Binding {
            binding: 15,
            role: Role::ColliderData,
            space: Space::Read,
            bytes: crate::features::colliders::data(&ir.colliders).len() as u64 * 4,
            meaning: "the height fields' samples (row by row, x fastest) and the mesh colliders' distance fields (x fastest, then y, then z), in collider order",
        });
    }
    if ir.collides_with_scene_depth() {
        layout.bindings.push(Binding {
            binding: 23,
            role: Role::SceneDepth,
            space: Space::Read,
            bytes: 0,
            meaning: "the depth image SceneDepth collides with, row by row from the top: the runtime's copy of the host's depth texture, sized when it is given",
        });
        layout.bindings.push(Binding {
            binding: 24,
            role: Role::SceneCamera,
            space: Space::Uniform,
            bytes: crate::features::colliders::scene_depth::CAMERA_WORDS as u64 * 4,
            meaning: "the depth image's size (width, height, 0, 0; width 0: no image yet) and camera: view-projection, the view's row 2, the inverse projection, the inverse view and the view, column-major",
        });
    }
    if let Some(flock) = &ir.flock {
        let groups = u64::from(ir.capacity.div_ceil(crate::base::kernel::WORKGROUP));
        layout.bindings.push(Binding {
            binding: 7,
            role: Role::Boids,
            space: Space::ReadWrite,
            bytes: (cap + u64::from(crate::features::forces::flock::GRID_SPARE)) * 32,
            meaning: "flock snapshot at the step's start: (x, alive), (v, 0) per slot; the grid's: per boid in bucket order, (x, row key), (v, 0), then spare entries that a search's last round reads past its run",
        });
        layout.bindings.push(Binding {
            binding: 8,
            role: Role::FlockOut,
            space: Space::ReadWrite,
            bytes: cap * 48,
            meaning: "per slot: (separation + avoidance, total weight), (weighted position sum, neighbours), (weighted velocity sum, 0)",
        });
        if flock.scope == crate::features::forces::flock::Scope::Global {
            layout.bindings.push(Binding {
                binding: 9,
                role: Role::FlockSums,
                space: Space::ReadWrite,
                bytes: (2 * groups + 2) * 16,
                meaning: "per-workgroup sums of x and v, then the global means",
            });
        }
        if let crate::features::forces::flock::Neighbors::Grid { .. } = flock.neighbors {
            let buckets = crate::features::forces::flock::FlockIr::grid_buckets(ir.capacity);
            layout.bindings.push(Binding {
                binding: 10,
                role: Role::GridKeys,
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "each slot's grid bucket (free slots: 0xffffffff)",
            });
            layout.bindings.push(Binding {
                binding: 11,
                role: Role::GridVals,
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "the live boids' slots sorted by bucket, then by slot (before the scatter: each slot's place among its bucket's boids)",
            });
            layout.bindings.push(Binding {
                binding: 18,
                role: Role::GridPlaced,
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "the live boids' slots by bucket, in the order their threads counted them (ranked into grid_vals)",
            });
            layout.bindings.push(Binding {
                binding: 25,
                role: Role::CellCounts,
                space: Space::ReadWrite,
                bytes: (buckets + 1) * 4,
                meaning: "per bucket: its live boids this step (zeroed by the scan that reads them into cell_start)",
            });
            layout.bindings.push(Binding {
                binding: 12,
                role: Role::CellStart,
                space: Space::ReadWrite,
                bytes: (buckets + 1) * 4,
                meaning: "per bucket: where its run starts in the sorted slots (the scan of cell_counts); one past the last: the live boids",
            });
        }
    }
    if ir.sort {
        // Room for a power-of-two padded sort (the bitonic baseline needs it).
        let padded = cap.next_power_of_two() * 4;
        layout.bindings.push(Binding {
            binding: 5,
            role: Role::SortKeys,
            space: Space::ReadWrite,
            bytes: padded,
            meaning: "depth keys, farthest first; free slots sort last",
        });
        layout.bindings.push(Binding {
            binding: 6,
            role: Role::SortVals,
            space: Space::ReadWrite,
            bytes: padded,
            meaning: "slot indices, in draw order after the sort",
        });
        layout.bindings.push(Binding {
            binding: 14,
            role: Role::DepthAxis,
            space: Space::Uniform,
            bytes: 16,
            meaning: "the camera's forward axis and offset: depth = dot(axis.xyz, x) + axis.w, written before each sort",
        });
    }
    layout.bindings.extend(crate::features::events::bindings(
        &ir.events,
        &ir.event_inputs,
        ir.capacity,
    ));
    layout.bindings.extend(crate::features::inherit::bindings(
        &ir.events,
        &ir.event_inputs,
        ir.capacity,
    ));
    if let (Some(plan), false) = (&ir.stateless, ir.events.is_empty()) {
        // A stateless group that fires events: its `fire` kernel's table and step.
        layout.bindings.extend([
            Binding {
                binding: 19,
                role: Role::FireFrame,
                space: Space::Read,
                bytes: plan.fire_table_bytes(),
                meaning: "written by the CPU per submission of steps: the segments that may hold live particles at any of its steps (as `frame`), for the `fire` kernel",
            },
            Binding {
                binding: 20,
                role: Role::FireState,
                space: Space::Read,
                bytes: 16,
                meaning: "the step `fire` fires for: the CPU writes each step of the submission at an offset of its own and binds it at that dynamic offset",
            },
        ]);
    }
    layout.bindings.sort_by_key(|b| b.binding);
    layout
}

impl fmt::Display for Layout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.stateless() {
            writeln!(
                f,
                "state: none, 0 bytes per particle (stateless: `evaluate` computes each particle from its id and age)"
            )?;
            writeln!(
                f,
                "struct Particle (the evaluated view, {} bytes per slot; written, never read back)",
                self.bytes_per_particle
            )?;
        } else {
            writeln!(
                f,
                "state: {} bytes per particle",
                self.state_bytes_per_particle() + self.trail_bytes_per_particle
            )?;
            if self.trail_bytes_per_particle > 0 {
                writeln!(
                    f,
                    "  of which trail history: {} bytes ({} past positions x {} bytes, binding 16)",
                    self.trail_bytes_per_particle,
                    self.trail_bytes_per_particle / crate::features::looks::trail::ENTRY_BYTES,
                    crate::features::looks::trail::ENTRY_BYTES
                )?;
            }
            writeln!(
                f,
                "struct Particle ({} bytes per particle)",
                self.bytes_per_particle
            )?;
        }
        writeln!(
            f,
            "  (offsets within the struct; stored word-major: its 16-byte word k of slot i at k * slots + i of the slot's particle buffer)"
        )?;
        let mut offset = 0;
        for a in &self.attributes {
            let (names, ty) = a.fields();
            let half = self.half_motion && a.is_motion();
            writeln!(
                f,
                "  {:<14} {:<4} offset {:>2}  {}{}",
                names.join(", "),
                if half { "f16" } else { ty },
                offset,
                a.meaning(),
                if half {
                    " in 16-bit floats (x and y in one word, z in the low half of the next): the accuracy budget allows it"
                } else {
                    ""
                }
            )?;
            offset += a.bytes(self.half_motion);
        }
        if self.half_motion {
            let p = self.planes();
            writeln!(
                f,
                "  (planes: {} of 16 bytes{}{}: no padding)",
                p.full,
                if p.pair { ", one of 8" } else { "" },
                if p.single { ", one of 4" } else { "" }
            )?;
        }
        let pad = self.bytes_per_particle - 4 * self.words().len() as u32;
        if pad > 0 {
            writeln!(
                f,
                "  {:<14} {:<4} offset {:>2}  padding to whole 16-byte words",
                "(pad)", "", offset
            )?;
        }
        writeln!(f, "bindings (group 0)")?;
        for b in &self.bindings {
            writeln!(
                f,
                "  @binding({}) {:<10} var<{}>  {} bytes  {}",
                b.binding,
                b.name(),
                b.space.wgsl(),
                b.bytes,
                b.meaning
            )?;
        }
        Ok(())
    }
}
