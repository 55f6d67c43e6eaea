//! Which attributes each stream passes from parent to child (`inherit: true` on the child's
//! attribute; `features::inherit` writes and reads them), and the graph's checks of what
//! children inherit: attributes, and colour (`inherit_color`).

use super::{CompiledGroup, Stream};
use crate::base::check::Checker;
use crate::base::diagnostics::Diagnostic;
use crate::base::path::ValuePath;
use crate::features::inherit::Pair;
use crate::stages::schema::EffectSpec;

/// Errors, located by the graph.
type Errors = Vec<(Diagnostic, String)>;

/// Per stream, the attributes its children inherit ([`pairs`]); the errors of [`pairs`] and
/// [`check_fed`] otherwise.
pub(super) fn wire(effects: &[EffectSpec], streams: &[Stream]) -> Result<Vec<Vec<Pair>>, Errors> {
    let mut c = Checker::default();
    let mut fed = vec![false; effects.len()];
    let pairs: Vec<Vec<Pair>> = streams
        .iter()
        .map(|s| {
            fed[s.child] = true;
            pairs(effects, s.parent, s.child, &mut c)
        })
        .collect();
    check_fed(effects, &fed, &mut c);
    match c.errors.is_empty() {
        true => Ok(pairs),
        false => Err(c.errors),
    }
}

/// The path of group `g`'s fields (the top level's for 0).
fn group_path(g: usize) -> ValuePath {
    match g {
        0 => ValuePath::root(),
        _ => ValuePath::root().field("groups").index(g - 1),
    }
}

/// The path of group `g`'s attribute `name`'s `inherit`.
fn inherit_path(g: usize, name: &str) -> ValuePath {
    group_path(g)
        .field("attributes")
        .field(name)
        .field("inherit")
}

/// For a stream from group `parent` into group `child`: the attributes the child inherits, as
/// (the parent's index, the child's index), in the child's name order. A name the parent does
/// not declare is an error at the child's `inherit`.
fn pairs(effects: &[EffectSpec], parent: usize, child: usize, c: &mut Checker) -> Vec<Pair> {
    let names: Vec<&String> = effects[parent].attributes.keys().collect();
    let mut out = Vec::new();
    for (ci, (name, a)) in effects[child].attributes.iter().enumerate() {
        if !a.inherit {
            continue;
        }
        match names.iter().position(|n| *n == name) {
            Some(pi) => out.push((pi, ci)),
            None => c.error(
                &inherit_path(child, name),
                format!(
                    "the group's events come from {:?}, which declares no attribute `{name}` to inherit (its attributes: {})",
                    effects[parent].name,
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                    }
                ),
            ),
        }
    }
    out
}

/// An attribute that inherits in a group no event feeds is an error at its `inherit`.
fn check_fed(effects: &[EffectSpec], fed: &[bool], c: &mut Checker) {
    for (g, e) in effects.iter().enumerate() {
        for (name, a) in &e.attributes {
            if a.inherit && !fed[g] {
                c.error(
                    &inherit_path(g, name),
                    "no event feeds this group, so no particle has a parent to inherit from; leave inherit out, or spawn the group from another's events",
                );
            }
        }
    }
}

/// After the groups compiled: an inherited attribute whose type is not its parent's is an
/// error at the child's `inherit`.
pub(super) fn check_types(
    effects: &[EffectSpec],
    streams: &[Stream],
    pairs: &[Vec<Pair>],
    groups: &[CompiledGroup],
) -> Result<(), Errors> {
    let mut c = Checker::default();
    let ty = |g: usize, a: usize| groups[g].effect.ir.attributes.list[a].ty.name();
    for (s, pairs) in streams.iter().zip(pairs) {
        for &(pa, ca) in pairs {
            let (pt, ct) = (ty(s.parent, pa), ty(s.child, ca));
            if pt != ct {
                let name = effects[s.child]
                    .attributes
                    .keys()
                    .nth(ca)
                    .cloned()
                    .unwrap_or_default();
                c.error(
                    &inherit_path(s.child, &name),
                    format!(
                        "`{name}` is of type {ct} here but {pt} in {:?}, which passes it: declare it with one type in both",
                        effects[s.parent].name
                    ),
                );
            }
        }
    }
    match c.errors.is_empty() {
        true => Ok(()),
        false => Err(c.errors),
    }
}

/// Warnings for events that pass on the colour of particles that have none: no palette, and no
/// colour inherited from a group that has one.
pub(super) fn colourless_inheritance(
    effects: &[EffectSpec],
    streams: &[Stream],
) -> Vec<(Diagnostic, String)> {
    let passes = |s: &Stream| effects[s.parent].events[s.out_slot].inherit_color;
    let mut tinted: Vec<bool> = effects.iter().map(|e| e.render.palette.is_some()).collect();
    // The graph is acyclic: as many passes as groups settle it.
    for _ in 0..effects.len() {
        for s in streams.iter().filter(|s| passes(s)) {
            tinted[s.child] |= tinted[s.parent];
        }
    }
    streams
        .iter()
        .filter(|s| passes(s) && !tinted[s.parent])
        .map(|s| {
            let at = group_path(s.parent)
                .field("events")
                .index(s.out_slot)
                .field("inherit_color");
            (
                Diagnostic::warning(
                    at.display,
                    format!(
                        "passes on the colour of {:?}'s particles, which have none (no render.palette, and none inherited): {:?}'s particles keep their own",
                        effects[s.parent].name, effects[s.child].name
                    ),
                ),
                at.lookup,
            )
        })
        .collect()
}
