//! The effect graph: several particle groups in one effect, connected by events
//! ([`crate::features::events`]). The top-level fields of an effect are its first group (named by the
//! effect's `name`); `groups` adds more, each with its own capacity, emitters, forces,
//! integrator, collisions, kills and look, sharing the file's `dt`, `seed`, `params` and
//! `camera`. Each group compiles to a [`CompiledEffect`] of its own, with the bindings its
//! events need; [`CompiledGraph`] ties them together with the event streams.

mod inherit;
pub mod reference;
mod totals;

pub use reference::ReferenceGraph;

use crate::base::check::Checker;
use crate::base::diagnostics::{Diagnostic, Diagnostics};
use crate::base::locate::SourceMap;
use crate::base::path::ValuePath;
pub use crate::compile::graph_field;
use crate::compile::{CompileError, CompileOptions, CompiledEffect, GroupLinks};
use crate::features::events::{
    Event, EventInputIr, EventIr, Ordering, Trigger, TriggerIr, MAX_COUNT, MAX_EVENTS,
};
use crate::stages::schema::EffectSpec;

/// One event stream between two groups.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stream {
    /// How its firings are put in order (by the firing group's capacity).
    pub ordering: Ordering,
    /// The firing group.
    pub parent: usize,
    /// The event's index among the parent's events (its bindings there).
    pub out_slot: usize,
    /// The group its particles join.
    pub child: usize,
    /// The event's index among the child's inputs (its bindings there).
    pub in_slot: usize,
    /// Particles per firing.
    pub count: u32,
}

/// A compiled group.
#[derive(Clone, Debug)]
pub struct CompiledGroup {
    /// The group's name.
    pub name: String,
    /// Its compiled effect (IR, layout, modules, warnings).
    pub effect: CompiledEffect,
}

/// A compiled effect of one or more groups and the events between them.
#[derive(Clone, Debug)]
pub struct CompiledGraph {
    /// The groups, the top-level one first.
    pub groups: Vec<CompiledGroup>,
    /// Every event, in the order children are spawned each step (groups in order, each
    /// group's events in order).
    pub streams: Vec<Stream>,
    /// Warnings about the graph itself (events that never fire, targets that overflow).
    pub warnings: Diagnostics,
}

impl CompiledGraph {
    /// Every warning: the graph's and each group's.
    pub fn all_warnings(&self) -> Diagnostics {
        let mut items = self.warnings.items.clone();
        for g in &self.groups {
            items.extend(g.effect.warnings.items.iter().cloned());
        }
        Diagnostics { items }
    }

    /// A graph of one group (an effect without `groups` or `events`).
    pub fn single(name: &str, effect: CompiledEffect) -> Self {
        Self {
            groups: vec![CompiledGroup {
                name: name.to_string(),
                effect,
            }],
            streams: Vec::new(),
            warnings: Diagnostics::default(),
        }
    }
}

/// The prefix of group `g`'s paths: empty for the top level, `groups[g - 1].` for the others.
fn group_prefix(g: usize) -> String {
    if g == 0 {
        String::new()
    } else {
        format!("groups[{}].", g - 1)
    }
}

/// The seed of group `g`: the file's for the top level, a different one for each other group
/// (every group numbers its particles from 0, and draws are keyed by id).
fn group_seed(seed: u32, g: usize) -> u32 {
    seed.wrapping_add((g as u32).wrapping_mul(0x9e37_79b9))
}

/// Each group as an effect of its own: the file's shared fields with the group's.
pub fn group_effects(effect: &EffectSpec) -> Vec<EffectSpec> {
    let mut root = effect.clone();
    root.groups.clear();
    let mut out = vec![root.clone()];
    for (i, g) in effect.groups.iter().enumerate() {
        let mut e = root.clone();
        e.name.clone_from(&g.name);
        e.capacity = g.capacity;
        e.seed = group_seed(effect.seed, i + 1);
        e.emitters.clone_from(&g.emitters);
        e.forces.clone_from(&g.forces);
        e.attributes.clone_from(&g.attributes);
        e.max_speed = g.max_speed;
        e.integrator = g.integrator;
        e.substeps = g.substeps;
        e.collide.clone_from(&g.collide);
        e.kill.clone_from(&g.kill);
        // The scene is the file's, drawn once: it stays with the first group.
        e.scene.clear();
        e.sort = g.sort;
        e.field = g.field.clone();
        e.state = g.state;
        e.render = g.render.clone();
        e.events.clone_from(&g.events);
        out.push(e);
    }
    out
}

/// Compiles effect source text of any number of groups (with `options` applied to each).
///
/// ```
/// let source = r#"Effect(
///     name: "rockets",
///     capacity: 10,
///     emitters: [Emitter(rate: 2.0, shape: Point((0.0, 0.0, 0.0)),
///                        velocity: Constant((0.0, 12.0, 0.0)), lifetime: Some((1.0, 1.5)))],
///     events: [Event(on: Death, target: "sparks", count: 50, velocity: Radial(speed: (2.0, 4.0)),
///                    lifetime: Some((0.5, 1.0)))],
///     groups: [Group(name: "sparks", capacity: 2000)],
/// )"#;
/// let graph = plume_compiler::graph::compile_graph_str(source, &Default::default()).unwrap();
/// assert_eq!(graph.groups[1].name, "sparks");
/// assert_eq!((graph.streams[0].parent, graph.streams[0].child), (0, 1));
/// // Each group is a compiled effect; the one fed by events spawns in `event_spawn_0`.
/// assert!(graph.groups[1].effect.wgsl.contains("fn event_spawn_0"));
///
/// // A target that does not exist is an error located at its name.
/// let typo = source.replace(r#"target: "sparks""#, r#"target: "sparkz""#);
/// let error = plume_compiler::graph::compile_graph_str(&typo, &Default::default()).unwrap_err();
/// assert!(error.render("rockets.ron", &typo).contains("rockets.ron:6:39: error: events[0].target"));
/// ```
pub fn compile_graph_str(
    source: &str,
    options: &CompileOptions,
) -> Result<CompiledGraph, CompileError> {
    let effect = crate::compile::parse_with(source, options)?;
    compile_graph(&effect, source)
}

/// Compiles a parsed effect of any number of groups; `source` locates diagnostics.
pub fn compile_graph(effect: &EffectSpec, source: &str) -> Result<CompiledGraph, CompileError> {
    crate::base::files::with_source(effect.files.clone(), || compile_all(effect, source))
}

/// [`compile_graph`] with the effect's files being read from its source.
fn compile_all(effect: &EffectSpec, source: &str) -> Result<CompiledGraph, CompileError> {
    let map = SourceMap::build(source);
    let locate =
        |items: Vec<(Diagnostic, String)>| crate::compile::locate_items(&map, source, items);
    let mut effects = group_effects(effect);
    // The events' spawn shapes may name meshes: read before the checks, as the emitters' are.
    let mut read = Checker::default();
    for (g, group) in effects.iter_mut().enumerate() {
        let base_dir = group.base_dir.clone();
        for (i, ev) in group.events.iter_mut().enumerate() {
            let at = match g {
                0 => ValuePath::root(),
                _ => ValuePath::root().field("groups").index(g - 1),
            };
            let path = at.field("events").index(i).field("shape");
            ev.shape.read_mesh(&path, base_dir.as_deref(), &mut read);
        }
    }
    if !read.errors.is_empty() {
        return Err(CompileError::Invalid(locate(read.errors)));
    }
    let (streams, checker, warnings) = check_graph(&effects);
    if !checker.errors.is_empty() {
        return Err(CompileError::Invalid(locate(checker.errors)));
    }
    let mut links: Vec<GroupLinks> = vec![GroupLinks::default(); effects.len()];
    let inherits =
        inherit::wire(&effects, &streams).map_err(|e| CompileError::Invalid(locate(e)))?;
    let trigger_of = |event: &Event| match event.on {
        Trigger::Death => TriggerIr::Death,
        Trigger::Collide => TriggerIr::Collide,
        Trigger::Every(seconds) => TriggerIr::Every(every_steps(seconds, effect.dt)),
    };
    // Every event a group fires, in file order (its bindings' order), with its stream if it
    // has a target.
    for (g, group) in effects.iter().enumerate() {
        for (j, event) in group.events.iter().enumerate() {
            let s = streams
                .iter()
                .position(|s| s.parent == g && s.out_slot == j);
            let child = s.map(|s| streams[s].child);
            links[g].events.push(EventIr {
                trigger: trigger_of(event),
                ordering: Ordering::for_capacity(group.capacity),
                target: child,
                stream: s,
                report: event.report,
                passes_id: child.is_some_and(|c| effects[c].render.ribbon.is_some()),
                passes: s.map_or_else(Vec::new, |s| inherits[s].iter().map(|p| p.0).collect()),
            });
        }
    }
    for (s, stream) in streams.iter().enumerate() {
        let event = &effects[stream.parent].events[stream.out_slot];
        let trigger = trigger_of(event);
        let child = &mut links[stream.child];
        child.inputs.push(EventInputIr {
            stream: s,
            emitter: effects[stream.child].emitters.len() + child.input_emitters.len(),
            count: event.count,
            inherit_velocity: event.inherit_velocity,
            inherit_color: event.inherit_color,
            parent_capacity: effects[stream.parent].capacity,
            period: match trigger {
                TriggerIr::Every(steps) => steps,
                _ => 1,
            },
            inherits: inherits[s].clone(),
        });
        child.input_emitters.push(event.as_emitter());
    }
    let mut groups = Vec::with_capacity(effects.len());
    let mut errors = Vec::new();
    for (g, (e, l)) in effects.iter().zip(&links).enumerate() {
        match crate::compile::compile_group(e, l, &group_prefix(g), &locate) {
            Ok(effect) => groups.push(CompiledGroup {
                name: e.name.clone(),
                effect,
            }),
            Err(CompileError::Invalid(d)) => errors.extend(d.items),
            Err(other) => return Err(other),
        }
    }
    if !errors.is_empty() {
        return Err(CompileError::Invalid(Diagnostics { items: errors }));
    }
    inherit::check_types(&effects, &streams, &inherits, &groups)
        .map_err(|e| CompileError::Invalid(locate(e)))?;
    let mut graph = CompiledGraph {
        groups,
        streams,
        warnings: locate(warnings),
    };
    // A group fed by events alone has no particles of its own to calibrate a budget on: it is
    // compiled again with a sample burst, its spawn rule where its parent first fires in f64.
    for (g, (e, l)) in effects.iter().zip(&links).enumerate() {
        if e.accuracy.is_none() || !e.emitters.is_empty() {
            continue;
        }
        let Some(burst) = reference::sample_burst(&graph, g, crate::reference::calibrate::SAMPLES)
        else {
            continue;
        };
        let mut sampled = e.clone();
        sampled.sample_burst = Some(burst);
        graph.groups[g].effect =
            crate::compile::compile_group(&sampled, l, &group_prefix(g), &locate)?;
    }
    Ok(graph)
}

/// An `Every` period in whole steps (at least one).
pub(crate) fn every_steps(seconds: f64, dt: f64) -> u32 {
    (seconds / dt).round().clamp(1.0, f64::from(u32::MAX)) as u32
}

/// The graph's own checks: names, targets, loops, counts; returns the streams (in spawn order),
/// the errors and the warnings.
fn check_graph(effects: &[EffectSpec]) -> (Vec<Stream>, Checker, Vec<(Diagnostic, String)>) {
    let mut c = Checker::default();
    let mut warnings = Vec::new();
    let group_path = |g: usize| {
        if g == 0 {
            ValuePath::root()
        } else {
            ValuePath::root().field("groups").index(g - 1)
        }
    };
    for g in 1..effects.len() {
        if let Some(first) = (0..g).find(|&h| effects[h].name == effects[g].name) {
            c.error(
                &group_path(g).field("name"),
                format!(
                    "{:?} already names {}: group names must be unique",
                    effects[g].name,
                    if first == 0 {
                        "the top-level group (the effect's name)".to_string()
                    } else {
                        format!("groups[{}]", first - 1)
                    }
                ),
            );
        }
    }
    let names: Vec<&str> = effects.iter().map(|e| e.name.as_str()).collect();
    let mut streams = Vec::new();
    let mut in_slots = vec![0usize; effects.len()];
    for (g, e) in effects.iter().enumerate() {
        let events = group_path(g).field("events");
        if e.events.len() > MAX_EVENTS {
            c.error(
                &events,
                format!(
                    "has {} events, more than the {MAX_EVENTS} a group may fire (each takes three bindings of its kernels)",
                    e.events.len()
                ),
            );
            continue;
        }
        for (j, ev) in e.events.iter().enumerate() {
            let path = events.index(j);
            check_event(&mut c, &path, ev, e);
            crate::features::event_report::check(&mut c, &path, ev.report, ev.target.is_some());
            // An event without a target only reports: no stream.
            let Some(name) = ev.target.as_deref() else {
                warnings.extend(never_fires(&path, ev, e));
                continue;
            };
            let Some(target) = names.iter().position(|n| *n == name) else {
                c.error(
                    &path.field("target"),
                    format!(
                        "no group is named {:?} (the groups are {})",
                        name,
                        names
                            .iter()
                            .map(|n| format!("{n:?}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                );
                continue;
            };
            if target == g {
                c.error(
                    &path.field("target"),
                    format!(
                        "{:?} fires into itself: each firing would spawn particles that fire again, without bound (spawn into another group)",
                        name
                    ),
                );
                continue;
            }
            if u64::from(e.capacity) * u64::from(ev.count) > u64::from(u32::MAX) {
                c.error(
                    &path.field("count"),
                    format!(
                        "{} per firing times the group's capacity {} could spawn more than 4294967295 particles in one step",
                        ev.count, e.capacity
                    ),
                );
            }
            warnings.extend(never_fires(&path, ev, e));
            streams.push(Stream {
                ordering: Ordering::for_capacity(e.capacity),
                parent: g,
                out_slot: j,
                child: target,
                in_slot: in_slots[target],
                count: ev.count,
            });
            in_slots[target] += 1;
        }
    }
    for (g, &inputs) in in_slots.iter().enumerate() {
        if inputs == 0 {
            continue;
        }
        let path = group_path(g);
        if inputs > MAX_EVENTS {
            c.error(
                &path.field("name"),
                format!(
                    "is fed by {inputs} events, more than the {MAX_EVENTS} a group may receive"
                ),
            );
        }
        if !effects[g].emitters.is_empty() {
            c.error(
                &path.field("emitters"),
                "a group fed by events spawns only from them (its ids are counted on the GPU): move these emitters to a group of their own",
            );
        }
    }
    if let Some((stream, cycle)) = find_cycle(effects.len(), &streams) {
        let s = &streams[stream];
        let names: Vec<&str> = cycle.iter().map(|&g| effects[g].name.as_str()).collect();
        c.error(
            &group_path(s.parent)
                .field("events")
                .index(s.out_slot)
                .field("target"),
            format!(
                "events form a cycle ({}): particles could spawn each other without bound",
                names.join(" -> ")
            ),
        );
    }
    if c.errors.is_empty() {
        warnings.extend(overflow_warnings(effects, &streams));
        warnings.extend(inherit::colourless_inheritance(effects, &streams));
    }
    (streams, c, warnings)
}

fn check_event(c: &mut Checker, path: &ValuePath, ev: &Event, group: &EffectSpec) {
    if ev.count == 0 || ev.count > MAX_COUNT {
        c.error(
            &path.field("count"),
            format!("must be in 1..={MAX_COUNT}, got {}", ev.count),
        );
    }
    if let Trigger::Every(seconds) = ev.on {
        c.positive(&path.field("on").variant("Every").inner(), seconds);
    }
    c.finite(&path.field("inherit_velocity"), ev.inherit_velocity);
    let (defines, _) = crate::expr::define::parse_all(&group.define);
    let names = crate::expr::Names {
        params: &group.params,
        dt: group.dt,
        live: group.live_params,
        attrs: &[],
        defines: &defines,
    };
    ev.as_emitter().check(c, path, names);
}

/// A warning when `ev` can never fire in `group`.
fn never_fires(path: &ValuePath, ev: &Event, group: &EffectSpec) -> Option<(Diagnostic, String)> {
    let why = match ev.on {
        Trigger::Death
            if group.kill.is_empty() && group.emitters.iter().all(|e| e.lifetime.is_none()) =>
        {
            "fires on death, but the group's particles never die (no lifetime, no kill volume)"
        }
        Trigger::Collide if group.collide.is_empty() => {
            "fires on collision, but the group has no colliders"
        }
        _ => return None,
    };
    let at = path.field("on");
    Some((Diagnostic::warning(at.display, why), at.lookup))
}

/// Warnings when an event's expected children exceed its target's capacity. The estimate:
/// a group with emitters has up to (bursts + rate x longest lifetime) alive; a group fed by
/// events has what its events are expected to keep alive. An event keeps alive `count` times
/// one wave of firings for the child's longest lifetime: on death or collision, the parent's
/// bursts plus its rate over that lifetime (a fed parent: all of it at once); every period,
/// each live parent once per period.
fn overflow_warnings(effects: &[EffectSpec], streams: &[Stream]) -> Vec<(Diagnostic, String)> {
    // A repeating burst counts as a rate of burst / every.
    let steady_rate = |e: &crate::stages::schema::Emitter, params| {
        let burst = f64::from(e.burst.value(params));
        e.rate.value(params) + e.every.map_or(0.0, |every| burst / every.mean())
    };
    let longest = |life: Option<crate::stages::schema::Range>| life.map_or(f64::INFINITY, |r| r.1);
    let fed: Vec<bool> = (0..effects.len())
        .map(|g| streams.iter().any(|s| s.child == g))
        .collect();
    let expected_children = |s: &Stream, alive: &[f64]| {
        let parent = &effects[s.parent];
        let ev = &parent.events[s.out_slot];
        let params = &parent.params;
        let bursts: f64 = parent
            .emitters
            .iter()
            .map(|e| f64::from(e.burst.value(params)))
            .sum();
        let rate: f64 = parent.emitters.iter().map(|e| steady_rate(e, params)).sum();
        let child_life = longest(ev.lifetime);
        let firings = match ev.on {
            Trigger::Death | Trigger::Collide if fed[s.parent] => alive[s.parent],
            Trigger::Death | Trigger::Collide => bursts + rate * child_life,
            Trigger::Every(period) => alive[s.parent] * (child_life / period).ceil().max(1.0),
        };
        firings * f64::from(ev.count)
    };
    // Groups in any order: the graph is acyclic, so as many passes as groups settle it.
    let mut alive: Vec<f64> = effects
        .iter()
        .map(|e| {
            let own: f64 = e
                .emitters
                .iter()
                .map(|em| {
                    f64::from(em.burst.value(&e.params))
                        + steady_rate(em, &e.params) * longest(em.lifetime)
                })
                .sum();
            own.min(f64::from(e.capacity))
        })
        .collect();
    for _ in 0..effects.len() {
        for g in (0..effects.len()).filter(|&g| fed[g]) {
            let total: f64 = streams
                .iter()
                .filter(|s| s.child == g)
                .map(|s| expected_children(s, &alive))
                .sum();
            alive[g] = total.min(f64::from(effects[g].capacity));
        }
    }
    let mut out = Vec::new();
    for s in streams {
        let expected = expected_children(s, &alive);
        let capacity = f64::from(effects[s.child].capacity);
        if expected > capacity {
            let path = ValuePath::root();
            let path = if s.parent == 0 {
                path
            } else {
                path.field("groups").index(s.parent - 1)
            }
            .field("events")
            .index(s.out_slot)
            .field("count");
            let expected = if expected.is_finite() {
                format!("about {expected:.0}")
            } else {
                "an unbounded number of".to_string()
            };
            out.push((
                Diagnostic::warning(
                    path.display,
                    format!(
                        "{expected} children may be alive at once, more than {:?}'s capacity {}: the excess is dropped (and counted)",
                        effects[s.child].name, effects[s.child].capacity
                    ),
                ),
                path.lookup,
            ));
        }
    }
    out
}

/// The first stream that closes a cycle of groups, and the cycle's groups (first repeated).
fn find_cycle(groups: usize, streams: &[Stream]) -> Option<(usize, Vec<usize>)> {
    // Depth-first search from every group, following streams in order.
    fn visit(
        g: usize,
        streams: &[Stream],
        on_path: &mut Vec<usize>,
        done: &mut [bool],
    ) -> Option<(usize, Vec<usize>)> {
        on_path.push(g);
        for (k, s) in streams.iter().enumerate().filter(|(_, s)| s.parent == g) {
            if let Some(at) = on_path.iter().position(|&h| h == s.child) {
                let mut cycle = on_path[at..].to_vec();
                cycle.push(s.child);
                return Some((k, cycle));
            }
            if !done[s.child] {
                if let Some(found) = visit(s.child, streams, on_path, done) {
                    return Some(found);
                }
            }
        }
        on_path.pop();
        done[g] = true;
        None
    }
    let mut done = vec![false; groups];
    for g in 0..groups {
        if !done[g] {
            if let Some(found) = visit(g, streams, &mut Vec::new(), &mut done) {
                return Some(found);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stream(parent: usize, child: usize) -> Stream {
        Stream {
            ordering: Ordering::Counted,
            parent,
            out_slot: 0,
            child,
            in_slot: 0,
            count: 1,
        }
    }

    #[test]
    fn cycles_are_found_and_chains_are_not() {
        assert_eq!(find_cycle(3, &[stream(0, 1), stream(1, 2)]), None);
        assert_eq!(
            find_cycle(3, &[stream(0, 1), stream(0, 2), stream(1, 2)]),
            None
        );
        let (k, cycle) = find_cycle(3, &[stream(0, 1), stream(1, 2), stream(2, 1)]).unwrap();
        assert_eq!((k, cycle), (2, vec![1, 2, 1]));
    }

    #[test]
    fn every_period_rounds_to_whole_steps() {
        assert_eq!(every_steps(0.05, 0.01), 5);
        assert_eq!(every_steps(0.001, 0.01), 1);
        assert!(TriggerIr::every_fires(5, 3, 7));
        assert!(!TriggerIr::every_fires(5, 3, 6));
    }
}
