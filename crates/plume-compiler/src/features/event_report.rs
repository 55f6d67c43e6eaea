//! Reported events: the firings of an event handed to the host (a game's code) with the firing
//! particle's id, step, position and velocity (`Event(.., report: N)`). This module owns the
//! report's bound, its check and the layout of the buffer the runtime gathers firings into;
//! the firings themselves are the event's (`events.rs`: the update appends each firing's id and
//! slot and writes its record), so a reported event fires exactly when the f64 twin's
//! `ReferenceSim::fired` says it does.
//!
//! The contract: after every step, the runtime's gather kernel appends the step's firings of
//! each reported event (in the order the update appended them) to the event's report buffer,
//! up to `report` firings between two readbacks, and counts every firing; a readback copies
//! the buffer and starts it again. Firings past the bound are counted, not kept: which of the
//! step that crosses the bound are kept is the GPU's order, the count is exact.

use crate::base::check::Checker;
use crate::base::path::ValuePath;

/// The most firings one reported event may keep between two readbacks.
pub(crate) const MAX_REPORT: u32 = 65_536;

/// Bytes of a report buffer's header: the firings counted since the last readback, the steps
/// gathered since the effect started, the bound, and a word of padding.
pub const REPORT_HEADER_BYTES: u64 = 16;

/// Bytes of one reported firing: position and id, velocity and step (two vec4 words).
pub const REPORT_BYTES: u64 = 32;

/// The bytes of the report buffer of an event keeping at most `most` firings.
pub fn buffer_bytes(most: u32) -> u64 {
    REPORT_HEADER_BYTES + u64::from(most) * REPORT_BYTES
}

/// Checks an event's `report` bound (at `path`): at most `MAX_REPORT`; and that an event
/// without a `target` reports (else it would do nothing).
pub(crate) fn check(c: &mut Checker, path: &ValuePath, report: u32, has_target: bool) {
    if report > MAX_REPORT {
        c.error(
            &path.field("report"),
            format!("must be at most {MAX_REPORT} firings a readback, got {report}"),
        );
    }
    if !has_target && report == 0 {
        c.error(
            &path.field("target"),
            "an event needs a `target` (the group its particles spawn into) or a `report` bound (firings handed to the host), and has neither",
        );
    }
}

/// Deserializes an optional group name written as a plain string (`target: "sparks"`).
pub(crate) fn some_name<'de, D>(deserializer: D) -> Result<Option<String>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    <String as serde::Deserialize>::deserialize(deserializer).map(Some)
}
