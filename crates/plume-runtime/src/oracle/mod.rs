//! Test oracles: what the tests compare the GPU's results against, and the readbacks they
//! compare. The CPU-fed reference drawing ([`ReferenceRenderer`] of [`sprites`], with
//! [`trail_strips`] for trails, [`ribbon_strips`] for ribbons joining particles and [`mesh_triangles`] for mesh particles: particles read back, coloured and sized in f64, drawn by a fixed
//! shader) is to the GPU draw what the f64 reference simulator (`plume_compiler::reference`)
//! is to the kernels. The readbacks ([`records_by_slot`], [`draw_order`], [`read_trails`],
//! [`read_flock_buffer`], [`chunk_count`], ...) expose what the public [`crate::Effect`]
//! keeps to itself.
//!
//! Nothing here serves a command or an embedding application.

pub(crate) mod inspect;
pub(crate) mod joined;
pub(crate) mod meshes;
pub(crate) mod sprites;
pub(crate) mod strips;
pub(crate) mod trails;

pub use inspect::{
    chunk_count, draw_order, group_renderer, particle_buffer_bytes, read_flock_buffer,
    records_by_slot,
};
pub use joined::{read_ribbon_table, ribbon_strips};
pub use meshes::mesh_triangles;
pub use sprites::{sprites, sprites_at, ReferenceRenderer, Sprite};
pub use strips::{trail_strips, StripVertex};
pub use trails::read_trails;
