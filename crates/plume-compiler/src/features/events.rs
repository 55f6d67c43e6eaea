//! Events: particles of one group spawning particles of another (sub-emitters). This module
//! owns the event's schema, its IR, the WGSL that records events in the parent's update and
//! spawns them in the child, and the f64 twin of when an event fires.
//!
//! The contract (docs/effect-format.md, "Groups and events"): the parent's update of step k
//! decides, per particle, whether an event fires (death, a collision during the step, or the
//! end of every `Every` period of its life), appends its id and slot (and, for
//! [`Ordering::Bucketed`], widens the firings' id range) and records its position and
//! velocity at the end of the step in its slot. At the start of step k + 1, before any group
//! updates, the runtime puts the firing slots in id order (the order is the ids', not the
//! threads'), and the child group spawns `count` particles per firing in that order: child ids
//! are handed out consecutively (first id + rank · count + c), and when the child group lacks
//! room, the last ones in that order are dropped and counted. Nothing depends on which slots
//! the GPU had free, so two runs give the same particles.

use serde::Deserialize;

use crate::base::layout::{Binding, Role, Space};
use crate::base::values::{Range, Vec3};
use crate::base::writer::{f32_lit, u32_lit, Writer};
use crate::features::emitter::{Shape, Velocity};

/// The most events a group may fire, and the most it may be fed by: each takes bindings of the
/// compute module (three per event fired, two per event received).
pub(crate) const MAX_EVENTS: usize = 4;

/// The most particles one event may spawn per firing particle.
pub(crate) const MAX_COUNT: u32 = 65_536;

/// When a particle fires an event.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub(crate) enum Trigger {
    /// When it dies (end of its lifetime or a kill volume), where it died.
    Death,
    /// When it hits a collider during a step, where the step leaves it.
    Collide,
    /// At the end of every period of this many seconds of its life (rounded to whole steps,
    /// at least one), wherever it is.
    Every(f64),
}

/// An event: `count` particles spawned in group `target` each time a particle fires it, placed
/// by `shape` around the parent's position, moving by `velocity` plus `inherit_velocity` times
/// the parent's velocity, and living `lifetime`; and, with a `report` bound, its firings handed
/// to the host (`event_report.rs`). An event names a target, reports, or both.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Event {
    /// What fires it.
    pub(crate) on: Trigger,
    /// The name of the group the new particles join; None for an event that only reports.
    #[serde(default, deserialize_with = "crate::features::event_report::some_name")]
    pub target: Option<String>,
    /// Particles spawned per firing (1 unless given; unused without a target).
    #[serde(default = "one")]
    pub count: u32,
    /// The most firings kept for the host between two readbacks (0: not reported).
    #[serde(default)]
    pub report: u32,
    /// Where they start, relative to the parent's position.
    #[serde(default = "origin")]
    pub shape: Shape,
    /// How they start moving (before the parent's share is added).
    #[serde(default = "at_rest")]
    pub velocity: Velocity,
    /// Lifetime range in seconds; `None` lives forever.
    #[serde(default)]
    pub lifetime: Option<Range>,
    /// Fraction of the parent's velocity added to theirs.
    #[serde(default)]
    pub inherit_velocity: f64,
    /// Whether they take on the parent's colour (its tint: `tint.rs`).
    #[serde(default)]
    pub inherit_color: bool,
}

fn one() -> u32 {
    1
}

fn origin() -> Shape {
    Shape::Point(Vec3(0.0, 0.0, 0.0))
}

fn at_rest() -> Velocity {
    Velocity::Constant(Vec3(0.0, 0.0, 0.0))
}

impl Event {
    /// The spawn rule as an emitter of the target group that never spawns on its own.
    pub fn as_emitter(&self) -> crate::features::emitter::Emitter {
        crate::features::emitter::Emitter::idle(
            self.shape.clone(),
            self.velocity.clone(),
            self.lifetime,
        )
    }
}

/// When an event fires, in the IR.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TriggerIr {
    /// At death.
    Death,
    /// After a step with a collision.
    Collide,
    /// At the end of step k when (k + 1 − born) is a multiple of this many steps.
    Every(u32),
}

impl TriggerIr {
    /// Whether an `Every(period)` event fires at the end of step `step` for a particle born at
    /// `born` (the f64 reference and the kernel use the same u32 arithmetic).
    pub(crate) fn every_fires(period: u32, born: u64, step: u64) -> bool {
        (step as u32)
            .wrapping_add(1)
            .wrapping_sub(born as u32)
            .is_multiple_of(period)
    }
}

/// The most slots a firing group may have for its firings to be put in order by counting: each
/// firing counts the firings with smaller ids, one dispatch, at most 8,192² comparisons a step.
/// Larger groups count their firings by id in a bitmap (or buckets), whose three dispatches
/// cost more than counting a few thousand firings (docs/performance.md, "Events").
pub const COUNTED_MAX: u32 = 8192;

/// How a stream's firings are put in parent id order at the step's start. Either way the
/// update appends (id, slot) per firing, and the work is proportional to the firings, not to
/// the firing group's slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ordering {
    /// The runtime ranks the firings by counting, each against all (one dispatch).
    Counted,
    /// The update also notes the smallest and largest firing id; the runtime sets each firing's
    /// bit in a bitmap of the ids' range (a bucket of ids counted, past 32 ids a slot), counts
    /// it per group of words, and places each firing at its group's start plus the firings
    /// before it in the group (a stream compaction in id order in three dispatches; no sort).
    Bucketed,
}

impl Ordering {
    /// The ordering of the events of a firing group of `capacity` slots.
    pub(crate) fn for_capacity(capacity: u32) -> Self {
        if capacity <= COUNTED_MAX {
            Ordering::Counted
        } else {
            Ordering::Bucketed
        }
    }
}

/// An event this group fires.
#[derive(Clone, Debug, PartialEq)]
pub struct EventIr {
    /// What fires it.
    pub(crate) trigger: TriggerIr,
    /// How its firings are put in order.
    pub ordering: Ordering,
    /// The index of the target group (None: the event only reports).
    pub target: Option<usize>,
    /// The event's stream, its index among every event with a target (the order children are
    /// spawned in); None for an event that only reports.
    pub stream: Option<usize>,
    /// The most firings kept for the host between two readbacks (0: not reported).
    pub report: u32,
    /// Whether the record passes the firing particle's id (in its velocity's w): its target
    /// group joins children by their parent (`render.ribbon`).
    pub passes_id: bool,
    /// The attributes (indices) it passes to its children, which inherit them
    /// ([`crate::features::inherit`]).
    pub passes: Vec<usize>,
}

/// An event this group receives: its spawns come from another group's records.
#[derive(Clone, Debug, PartialEq)]
pub struct EventInputIr {
    /// The event's index among every event of the effect.
    pub stream: usize,
    /// The emitter (of this group's IR) that holds the event's spawn rule.
    pub emitter: usize,
    /// Particles per firing.
    pub count: u32,
    /// Fraction of the parent's velocity added.
    pub inherit_velocity: f64,
    /// Whether the children's tint includes the parent's.
    pub inherit_color: bool,
    /// The parent group's capacity (how many records there can be).
    pub(crate) parent_capacity: u32,
    /// Steps between a parent's firings (`Every`), else 1: a ribbon's children's ordinals
    /// count in them (`ribbon.rs`).
    pub period: u32,
    /// The attributes children take from the parent, as (parent's index, child's index), in
    /// the order the parent passes them ([`crate::features::inherit`]).
    pub inherits: Vec<(usize, usize)>,
}

/// Bytes of one event record: position and velocity, each padded to a vec4.
pub const RECORD_BYTES: u64 = 32;
/// Bytes before the records: the count of records this step, padded to 16.
pub const RECORDS_HEADER_BYTES: u64 = 16;

/// Binding of the keys (the firing particles' ids, appended) of the `j`-th event a group fires;
/// the values (their slots) and the records follow it.
pub fn out_binding(j: usize) -> u32 {
    48 + 3 * j as u32
}

/// Binding of the sorted parent slots of the `j`-th event a group receives; the records follow.
pub fn in_binding(j: usize) -> u32 {
    64 + 2 * j as u32
}

/// The bindings events add to a group's compute module.
pub(crate) fn bindings(events: &[EventIr], inputs: &[EventInputIr], capacity: u32) -> Vec<Binding> {
    let cap = u64::from(capacity);
    let mut out = Vec::new();
    for j in 0..events.len() {
        out.extend([
            Binding {
                binding: out_binding(j),
                role: Role::EventKeys(j as u8),
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "the ids of the particles that fired this event in the last update, appended (the first `count`)",
            },
            Binding {
                binding: out_binding(j) + 1,
                role: Role::EventVals(j as u8),
                space: Space::ReadWrite,
                bytes: cap * 4,
                meaning: "the slot of each id in event_keys, appended with it",
            },
            Binding {
                binding: out_binding(j) + 2,
                role: Role::EventOut(j as u8),
                space: Space::ReadWrite,
                bytes: RECORDS_HEADER_BYTES + cap * RECORD_BYTES,
                meaning: "the number of firings, the complement of the smallest firing id and the largest, then per slot the position and velocity it fired with",
            },
        ]);
    }
    for (j, input) in inputs.iter().enumerate() {
        let parent = u64::from(input.parent_capacity);
        out.extend([
            Binding {
                binding: in_binding(j),
                role: Role::EventOrder(j as u8),
                space: Space::ReadWrite,
                bytes: parent * 4,
                meaning:
                    "the parent group's firing slots in parent id order (ordered by the runtime at the step's start)",
            },
            Binding {
                binding: in_binding(j) + 1,
                role: Role::EventIn(j as u8),
                space: Space::ReadWrite,
                bytes: RECORDS_HEADER_BYTES + parent * RECORD_BYTES,
                meaning: "the parent group's event records (count, then per parent slot)",
            },
        ]);
    }
    out
}

/// The WGSL type of an event binding; None for other bindings.
pub(crate) fn binding_type(role: Role) -> Option<&'static str> {
    match role {
        Role::EventKeys(_) | Role::EventVals(_) | Role::EventOrder(_) => Some("array<u32>"),
        Role::EventOut(_) | Role::EventIn(_) => Some("EventRecords"),
        _ => None,
    }
}

/// The WGSL name of the `j`-th received event's slot order (the parent's firing slots).
pub(crate) fn in_order(j: usize) -> &'static str {
    Role::EventOrder(j as u8).name()
}

/// Emits the record structs (when the group fires or receives events).
pub(crate) fn emit_declarations(w: &mut Writer) {
    w.comment("An event's record: the firing particle's position, its tint (tint.rs, packed) and velocity.");
    w.block("struct EventRecord", |w| {
        w.line("x: vec3<f32>,");
        w.line("tint: u32,");
        w.line("v: vec4<f32>,");
    });
    w.comment("The firings' count, the complement of their smallest id (zero is none, as cleared) and their largest id.");
    w.block("struct EventRecords", |w| {
        w.line("count: atomic<u32>,");
        w.line("not_min_id: atomic<u32>,");
        w.line("max_id: atomic<u32>,");
        w.line("pad: u32,");
        w.line("records: array<EventRecord>,");
    });
}

/// The bit of an update's outcome (`update.rs`) that says the particle fired its group's
/// `j`-th event; bit 0 says it died.
pub(crate) fn fired_bit(j: usize) -> u32 {
    2 << j
}

/// The record's fourth velocity word: the firing particle's id (`id`, WGSL) as f32 bits when
/// the event passes it, else 0.
fn passed_id(e: &EventIr, id: &str) -> String {
    match e.passes_id {
        true => format!("bitcast<f32>({id})"),
        false => "0.0".into(),
    }
}

/// Emits the firing of every event whose trigger `fires_here` accepts, by the particle being
/// updated, with its position `x`, velocity `vel` and packed tint `tint` (WGSL expressions),
/// and what `passed` writes beside event j's record (the attributes it passes):
/// its record, in its slot, and its bit in `fired` (the kernel appends its id and slot with
/// the rest of its workgroup's: [`emit_workgroup_appends`]). An `Every` event's firing is
/// guarded by its period.
pub(crate) fn emit_fire(
    w: &mut Writer,
    events: &[EventIr],
    fires_here: impl Fn(TriggerIr) -> bool,
    (x, vel, tint): (&str, &str, &str),
    passed: &dyn Fn(&mut Writer, usize),
) {
    for (j, e) in events.iter().enumerate() {
        if !fires_here(e.trigger) {
            continue;
        }
        let body = |w: &mut Writer| {
            w.line(format!("fired = fired | {};", u32_lit(fired_bit(j))));
            w.line(format!(
                "{}.records[chunk.base + i] = EventRecord({x}, {tint}, vec4<f32>({vel}, {}));",
                Role::EventOut(j as u8).name(),
                passed_id(e, "p.id")
            ));
            passed(w, j);
        };
        match e.trigger {
            TriggerIr::Every(period) => w.block(
                format!(
                    "if ((params.step + 1u - p.born) % {} == 0u)",
                    u32_lit(period)
                ),
                body,
            ),
            _ => body(w),
        }
    }
}

/// The update kernel's appends of a workgroup's firings, in three parts around its barriers
/// (`update.rs` emits the deaths' the same way): each firing takes a place among its
/// workgroup's (a workgroup atomic), one thread adds the workgroup's count to the stream's (one
/// global atomic a workgroup, not one a firing: thousands of firings a step adding to one word
/// wait on each other), and each firing writes its id and slot at the workgroup's base plus
/// its place. A [`Ordering::Bucketed`] stream's id range is widened the same way.
pub(crate) enum AppendPart {
    /// The workgroup's counters (module scope).
    Declarations,
    /// Their reset, by thread 0 before the first barrier.
    Reset,
    /// Each firing's place, from `outcome` (bits, id), after the update.
    Place,
    /// The workgroup's share of the stream's counts, by thread 0 after the second barrier.
    Reserve,
    /// The appends, after the third barrier.
    Write,
}

/// Emits `part` of the appends of the firings of `events` (see [`AppendPart`]).
pub(crate) fn emit_workgroup_appends(w: &mut Writer, events: &[EventIr], part: AppendPart) {
    for (j, e) in events.iter().enumerate() {
        let bucketed = e.ordering == Ordering::Bucketed;
        let out = Role::EventOut(j as u8).name();
        let fired = format!("(outcome.x & {}) != 0u", u32_lit(fired_bit(j)));
        match part {
            AppendPart::Declarations => {
                w.line(format!("var<workgroup> wg_fired_{j}: atomic<u32>;"));
                w.line(format!("var<workgroup> wg_fired_base_{j}: u32;"));
                if bucketed {
                    w.line(format!("var<workgroup> wg_not_min_id_{j}: atomic<u32>;"));
                    w.line(format!("var<workgroup> wg_max_id_{j}: atomic<u32>;"));
                }
            }
            AppendPart::Reset => {
                w.line(format!("atomicStore(&wg_fired_{j}, 0u);"));
                if bucketed {
                    w.line(format!("atomicStore(&wg_not_min_id_{j}, 0u);"));
                    w.line(format!("atomicStore(&wg_max_id_{j}, 0u);"));
                }
            }
            AppendPart::Place => {
                w.line(format!("var fired_at_{j} = 0u;"));
                w.block(format!("if ({fired})"), |w| {
                    w.line(format!("fired_at_{j} = atomicAdd(&wg_fired_{j}, 1u);"));
                    if bucketed {
                        // The ids' range sets the buckets' width.
                        w.line(format!("atomicMax(&wg_not_min_id_{j}, ~outcome.y);"));
                        w.line(format!("atomicMax(&wg_max_id_{j}, outcome.y);"));
                    }
                });
            }
            AppendPart::Reserve => {
                w.line(format!("let fired_{j} = atomicLoad(&wg_fired_{j});"));
                w.block(format!("if (fired_{j} > 0u)"), |w| {
                    w.line(format!(
                        "wg_fired_base_{j} = atomicAdd(&{out}.count, fired_{j});"
                    ));
                    if bucketed {
                        w.line(format!(
                            "atomicMax(&{out}.not_min_id, atomicLoad(&wg_not_min_id_{j}));"
                        ));
                        w.line(format!(
                            "atomicMax(&{out}.max_id, atomicLoad(&wg_max_id_{j}));"
                        ));
                    }
                });
            }
            AppendPart::Write => {
                w.block(format!("if ({fired})"), |w| {
                    w.line(format!("let at_{j} = wg_fired_base_{j} + fired_at_{j};"));
                    let (keys, vals) = (
                        Role::EventKeys(j as u8).name(),
                        Role::EventVals(j as u8).name(),
                    );
                    w.line(format!("{keys}[at_{j}] = outcome.y;"));
                    w.line(format!("{vals}[at_{j}] = chunk.base + i;"));
                });
            }
        }
    }
}

/// Emits, in a stateless group's `fire` kernel, the firing of every event by particle `id`
/// at the end of the step in `fire_state`: `dies` (WGSL bool) whether it dies in it, `lived`
/// (u32) its whole steps lived at its end, `x`, `vel` and `tint` (packed) as for
/// [`emit_fire`]. The firings are appended with their records, the record's index standing
/// for the firing's slot (and, for [`Ordering::Bucketed`], the id range widened).
pub(crate) fn emit_fire_appended(
    w: &mut Writer,
    events: &[EventIr],
    id: &str,
    x: &str,
    vel: &str,
    tint: &str,
) {
    for (j, e) in events.iter().enumerate() {
        let fires = match e.trigger {
            TriggerIr::Death => "dies".to_string(),
            TriggerIr::Every(period) => format!("lived % {} == 0u", u32_lit(period)),
            // Colliders rule out the closed form a stateless group needs.
            TriggerIr::Collide => continue,
        };
        let bucketed = e.ordering == Ordering::Bucketed;
        let slot = j as u8;
        let (out, keys, vals) = (
            Role::EventOut(slot).name(),
            Role::EventKeys(slot).name(),
            Role::EventVals(slot).name(),
        );
        w.block(format!("if ({fires})"), |w| {
            w.line(format!("let at_{j} = atomicAdd(&{out}.count, 1u);"));
            w.line(format!("{keys}[at_{j}] = {id};"));
            w.line(format!("{vals}[at_{j}] = at_{j};"));
            if bucketed {
                // The ids' range sets the buckets' width.
                w.line(format!("atomicMax(&{out}.not_min_id, ~{id});"));
                w.line(format!("atomicMax(&{out}.max_id, {id});"));
            }
            w.line(format!(
                "{out}.records[at_{j}] = EventRecord({x}, {tint}, vec4<f32>({vel}, {}));",
                passed_id(e, id)
            ));
        });
    }
}

/// Emits `event_spawn_J` for every event the group receives. The stream's ordering (a runtime
/// kernel, `crate::events` in plume-runtime) has already taken the firings' count and popped
/// the children's slots: the spawn's first thread clears the parent's records header for the
/// firings of the step to come, and the threads of a fixed grid (the runtime sizes it by the
/// group's slots, [`SPAWN_WORKGROUPS`] at most) stride over the children, each spawned by
/// `event_child_J`. (A direct dispatch: an indirect one, its workgroups written by the
/// ordering, starts later after the kernel that writes them: docs/performance.md, "Events".)
/// `reads_origin(j)` says whether input j's spawn reads `origin` (set from the record first).
/// `store` emits (for input j) the store of the spawned particle `s` with id `id` (and packed tint `tint`,
/// when the group stores tints) in `slot`: the same code as the group's own spawn. `own` is
/// the WGSL of the group's own tint for the particle `id` when it stores tints (`tint.rs`).
pub(crate) fn emit_kernels(
    w: &mut Writer,
    inputs: &[EventInputIr],
    own: Option<&str>,
    reads_origin: &dyn Fn(usize) -> bool,
    store: &dyn Fn(&mut Writer, usize),
    ribbon: Option<&crate::features::looks::ribbon::Ribbon>,
) {
    for (j, input) in inputs.iter().enumerate() {
        let records = Role::EventIn(j as u8).name();
        w.comment(format!(
            "Event {}: child i of the parent's firings of the last step ({} particles each), in parent id order, spawned into the slot the ordering popped for it (the children past the free slots were dropped and counted; ids consumed either way).",
            input.stream, input.count
        ));
        w.block(format!("fn event_child_{j}(i: u32)"), |w| {
            w.line("let slot = free_list[counters.spawn_base + i];");
            w.line(format!("let rank = i / {};", u32_lit(input.count)));
            w.line(format!("let c = i % {};", u32_lit(input.count)));
            // Loaded before the slot is tested, so that the free list's load and the order's
            // wait together (a test between them made them two latencies in turn).
            w.line(format!(
                "let r = {records}.records[{}[rank]];",
                Role::EventOrder(j as u8).name()
            ));
            w.block(
                "if (slot < chunk.base || slot - chunk.base >= chunk.len)",
                |w| w.line("return;"),
            );
            w.line("let id = counters.event_first_id + i;");
            if reads_origin(j) {
                w.line("spawn_origin = r.x;");
            }
            w.line(format!(
                "var s = emit_{}(id, c, params.step);",
                input.emitter
            ));
            w.line("s.x = s.x + r.x;");
            if input.inherit_velocity != 0.0 {
                w.line(format!(
                    "s.v = s.v + {} * r.v.xyz;",
                    f32_lit(input.inherit_velocity)
                ));
            }
            match own {
                Some(own) if input.inherit_color => w.line(format!(
                    "let tint = pack4x8unorm(vec4<f32>({own} * unpack4x8unorm(r.tint).rgb, 1.0));"
                )),
                Some(own) => w.line(format!("let tint = pack4x8unorm(vec4<f32>({own}, 1.0));")),
                None => {}
            }
            store(w, j);
            if let Some(ribbon) = ribbon {
                let (key, ordinal) = ribbon.child_wgsl(input.period, input.count);
                ribbon.emit_write(w, &key, &ordinal);
            }
        });
        w.blank();
        w.comment(format!(
            "Event {}: the children of the parent's firings, spawned by a fixed grid whose threads stride over them.",
            input.stream
        ));
        w.line("@compute @workgroup_size(WORKGROUP)");
        w.block(
            format!("fn event_spawn_{j}(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)"),
            |w| {
                crate::base::kernel::emit_thread_index(w, "first", None);
                w.comment("The header was read by the ordering; the parent's next firings count from zero.");
                w.block("if (first == 0u)", |w| {
                    w.line(format!("atomicStore(&{records}.count, 0u);"));
                    w.line(format!("atomicStore(&{records}.not_min_id, 0u);"));
                    w.line(format!("atomicStore(&{records}.max_id, 0u);"));
                });
                w.line("let stride = groups.x * groups.y * WORKGROUP;");
                w.line("let children = counters.spawn_count;");
                w.block(
                    "for (var i = first; i < children; i = i + stride)",
                    |w| w.line(format!("event_child_{j}(i);")),
                );
            },
        );
        w.blank();
    }
}

/// The most workgroups of an event spawn's grid (of `WORKGROUP` threads each): about the
/// threads an H100 holds at once; a group of fewer slots gets one workgroup per `WORKGROUP`
/// slots (at least one: its first thread clears the header). 256 made rain's splashes (four
/// children a firing) slower (docs/performance.md, "Events").
pub const SPAWN_WORKGROUPS: u32 = 1024;
