//! Headless outputs, for the `plume` command and tools: images drawn offscreen ([`Offscreen`],
//! the same draw a host records, or the compute [`Splat`]), bloomed when the effect glows
//! ([`GlowPasses`]), encoded as PNG, contact sheet or GIF; particle exports (`.csv`, `.ply`)
//! and their summary. Every file is written atomically
//! ([`write_atomically`]).
//!
//! An embedding application needs none of it: it draws into its own render pass.

pub(crate) mod export;
pub(crate) mod images;
pub(crate) mod offscreen;
