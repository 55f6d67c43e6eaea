//! The leaves everything shares: diagnostics and spans, value paths and the checker, value
//! types, the WGSL text writer and kernel helpers, the PCG hash, lifetimes in steps, the
//! particle layout's types, naga validation, and meshes read from OBJ and glTF files with
//! their baked signed distance fields.
//!
//! Architecture invariant: nothing here imports anything of the crate outside `base`.

pub mod check;
pub mod diagnostics;
pub mod files;
pub(crate) mod gradient_noise;
pub mod kernel;
pub mod layout;
pub mod lifetime;
pub mod locate;
pub mod mesh;
pub(crate) mod naga_check;
pub mod path;
pub mod rng;
pub(crate) mod sdf;
pub mod values;
pub mod writer;
