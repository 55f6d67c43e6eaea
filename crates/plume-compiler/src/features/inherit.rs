//! Attributes children take from their parent: an attribute a group fed by events declares
//! with `inherit: true` starts, in a child, as the firing particle's attribute of the same
//! name (hanabi's `InheritAttributeModifier` and `parent_attr`), not as its `spawn` value.
//! The parent's value is the one it had as the step that fired began (what its update read).
//!
//! A stream that passes attributes gets a buffer of its own beside its records: three f32
//! words per passed attribute per parent slot (a number in the first), written by the parent's
//! update where it writes the record and read by the child's spawn at the record's index. A
//! stream that passes none has no buffer and its kernels are unchanged.

use crate::base::layout::{Binding, Role, Space};
use crate::base::writer::{u32_lit, Writer};
use crate::features::events::{EventInputIr, EventIr};

/// Words a passed attribute takes in the buffer, whatever its type.
pub(crate) const WORDS: u32 = 3;

/// Binding of the passed attributes of the `j`-th event a group fires.
pub fn out_binding(j: usize) -> u32 {
    72 + j as u32
}

/// Binding of the passed attributes of the `j`-th event a group receives.
pub fn in_binding(j: usize) -> u32 {
    76 + j as u32
}

/// Words per parent slot of a stream passing `count` attributes.
pub fn stride(count: usize) -> u32 {
    WORDS * count as u32
}

/// A parent's attribute (its index) and the child's that inherits it.
pub type Pair = (usize, usize);

/// The attributes a group keeps because it passes them or inherits them (a bit set): both
/// sides keep them, whatever else reads them.
pub(crate) fn kept(events: &[EventIr], inputs: &[EventInputIr]) -> u64 {
    let passed = events.iter().flat_map(|e| e.passes.iter().copied());
    let inherited = inputs.iter().flat_map(|i| i.inherits.iter().map(|p| p.1));
    passed.chain(inherited).fold(0, |set, a| set | (1u64 << a))
}

/// The bindings the passed attributes add to a group's compute module.
pub(crate) fn bindings(events: &[EventIr], inputs: &[EventInputIr], capacity: u32) -> Vec<Binding> {
    let mut out = Vec::new();
    for (j, e) in events
        .iter()
        .enumerate()
        .filter(|(_, e)| !e.passes.is_empty())
    {
        out.push(Binding {
            binding: out_binding(j),
            role: Role::AttrsOut(j as u8),
            space: Space::ReadWrite,
            bytes: u64::from(capacity) * u64::from(stride(e.passes.len())) * 4,
            meaning: "the attributes this event passes to its children (inherit: true), three words each, per slot, as the step that fired began",
        });
    }
    for (j, input) in inputs
        .iter()
        .enumerate()
        .filter(|(_, i)| !i.inherits.is_empty())
    {
        out.push(Binding {
            binding: in_binding(j),
            role: Role::AttrsIn(j as u8),
            space: Space::ReadWrite,
            bytes: u64::from(input.parent_capacity) * u64::from(stride(input.inherits.len())) * 4,
            meaning: "the parent's attributes its children inherit (inherit: true), three words each, per parent slot",
        });
    }
    out
}

/// The WGSL type of a binding of this module's, or None for another's.
pub(crate) fn binding_type(role: Role) -> Option<&'static str> {
    matches!(role, Role::AttrsOut(_) | Role::AttrsIn(_)).then_some("array<f32>")
}

/// Emits, where the parent's update writes event `j`'s record for the particle in slot
/// `chunk.base + i`, the words of the attributes it passes; `words(a)` is attribute a's three
/// words as the step began (WGSL; a number's last two 0.0).
pub(crate) fn emit_pass(
    w: &mut Writer,
    j: usize,
    event: &EventIr,
    words: &dyn Fn(usize) -> [String; 3],
) {
    if event.passes.is_empty() {
        return;
    }
    let at = format!("(chunk.base + i) * {}", u32_lit(stride(event.passes.len())));
    for (k, &a) in event.passes.iter().enumerate() {
        for (c, word) in words(a).iter().enumerate() {
            w.line(format!(
                "{}[{at} + {}] = {word};",
                Role::AttrsOut(j as u8).name(),
                u32_lit(WORDS * k as u32 + c as u32)
            ));
        }
    }
}

/// Emits, in the child spawn of an input (with `rank`, the firing's place, in scope; `order`
/// the input's slot order), where the firing's words start.
pub(crate) fn emit_find(w: &mut Writer, input: &EventInputIr, order: &str) {
    if !input.inherits.is_empty() {
        w.line(format!(
            "let inherited_at = {order}[rank] * {};",
            u32_lit(stride(input.inherits.len()))
        ));
    }
}

/// The WGSL value child attribute `child` (of type `vec3` when `vec3`) takes from the parent
/// in input `j`, or None when it does not inherit there.
pub(crate) fn taken(j: usize, input: &EventInputIr, child: usize, vec3: bool) -> Option<String> {
    let k = input.inherits.iter().position(|&(_, c)| c == child)? as u32;
    let word = |c: u32| {
        format!(
            "{}[inherited_at + {}]",
            Role::AttrsIn(j as u8).name(),
            u32_lit(WORDS * k + c)
        )
    };
    Some(match vec3 {
        true => format!("vec3<f32>({}, {}, {})", word(0), word(1), word(2)),
        false => word(0),
    })
}
