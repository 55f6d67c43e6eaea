//! A stateful effect's `Counters` struct: its fields in order, a 32-bit word each, which the
//! runtime's event ordering also writes by word (it prepares a stream's spawn in the child's
//! counters: plume-runtime's `sim/event_prepare.wgsl`).

use crate::base::writer::Writer;

/// The fields of `Counters`, in order, a 32-bit word each: the last two only where the group
/// is fed by events.
pub const COUNTER_FIELDS: [(&str, &str); 8] = [
    ("free_count", "atomic<u32>"),
    ("spawn_base", "u32"),
    ("spawn_count", "u32"),
    ("spawned", "u32"),
    ("dropped", "u32"),
    ("died", "atomic<u32>"),
    ("next_id", "u32"),
    ("event_first_id", "u32"),
];

/// The fields a group not fed by events declares.
const OWN_FIELDS: usize = 6;

/// The word of the counter `name` in `Counters` ([`COUNTER_FIELDS`]).
pub fn counter_word(name: &str) -> Option<u32> {
    COUNTER_FIELDS
        .iter()
        .position(|(field, _)| *field == name)
        .map(|at| at as u32)
}

/// Emits `struct Counters`, with the event fields where the group is `fed` by events.
pub(crate) fn emit_struct(w: &mut Writer, fed: bool) {
    let fields = match fed {
        true => &COUNTER_FIELDS[..],
        false => &COUNTER_FIELDS[..OWN_FIELDS],
    };
    w.block("struct Counters", |w| {
        for (name, ty) in fields {
            w.line(format!("{name}: {ty},"));
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_words_follow_the_declared_order() {
        assert_eq!(counter_word("free_count"), Some(0));
        assert_eq!(counter_word("died"), Some(5));
        assert_eq!(counter_word("event_first_id"), Some(7));
        assert_eq!(counter_word("nothing"), None);
        let mut w = Writer::new();
        emit_struct(&mut w, false);
        let text = w.finish();
        assert!(
            text.contains("died: atomic<u32>,") && !text.contains("next_id"),
            "{text}"
        );
    }
}
