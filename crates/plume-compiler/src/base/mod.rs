//! The leaves everything shares: diagnostics and spans, value paths and the checker, value
//! types, the WGSL text writer and kernel helpers, the PCG hash, lifetimes in steps, the
//! particle layout's types, naga validation, and meshes read from OBJ and glTF files with
//! their baked signed distance fields.
//!
//! Architecture invariant: nothing here imports anything of the crate outside `base`.

pub(crate) mod check;
pub(crate) mod diagnostics;
pub mod files;
pub(crate) mod gradient_noise;
pub(crate) mod kernel;
pub(crate) mod layout;
pub mod lifetime;
pub(crate) mod locate;
pub(crate) mod mesh;
pub(crate) mod naga_check;
pub(crate) mod path;
pub mod rng;
pub(crate) mod sdf;
pub(crate) mod values;
pub(crate) mod writer;
