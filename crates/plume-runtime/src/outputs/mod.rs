//! Headless outputs, for the `plume` command and tools: images drawn offscreen ([`Offscreen`],
//! through the same [`crate::EffectRenderer`] a host records; or [`ComputeOffscreen`], by the
//! compute renderer), bloomed when the effect glows ([`GlowPasses`] into [`HDR_FORMAT`]), encoded as PNG, contact
//! sheet or GIF ([`Frame8`]), over the meshes the effect names ([`Scene`], shadowed by [`SceneShadow`]); the particle exports (`.csv`, `.ply`) and their [`Summary`].
//! Every file is written atomically ([`write_atomically`]).
//!
//! An embedding application needs none of it: it draws into its own render pass.

pub(crate) mod export;
pub(crate) mod images;
pub(crate) mod offscreen;
pub(crate) mod scene;
pub(crate) mod scene_shadow;

pub use crate::device::readback::read_texture;
pub use crate::draw::glow::{GlowPasses, HDR_FORMAT};
pub use crate::draw::splat::ComputeOffscreen;
pub use export::{
    csv, csv_groups, export, export_groups, ply, ply_groups, summarize, write_atomically, Summary,
};
pub use images::{contact_sheet, gif, png, Frame8};
pub use offscreen::{Offscreen, FORMAT};
pub use scene::{Scene, DEPTH_FORMAT, SCENE_GREY};
pub use scene_shadow::{SceneShadow, SHADOW_MAP_SIZE};
