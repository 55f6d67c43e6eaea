//! Features: the forces, colliders, fields, events, emitters and looks an effect is made of.
//! Each owns its schema, its checks, its lowered form, its WGSL and its f64 twin in one place.
//!
//! Architecture invariant: a feature imports only `base`, `expr` and features below it
//! (never `ir`, `stages` or the drivers); the stages above gather features through the small
//! interfaces they expose (`ForceTerm`, the collider functions, `Event`'s kernels).

pub mod accuracy;
pub mod attributes;
pub mod bursts;
pub mod colliders;
pub mod emitter;
pub mod event_report;
pub mod events;
pub mod field;
pub mod forces;
pub mod inherit;
pub mod lights;
pub(crate) mod looks;
pub(crate) mod mesh_emission;
pub mod placement;
pub(crate) mod scene;
pub mod shadow;
