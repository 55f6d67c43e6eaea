//! The CPU f64 reference simulator: it executes the same IR as the GPU kernels, with the same
//! spawn schedule, the same integer-hash random draws and the same integer death steps, in f64.
//! Written for clarity, not speed; it is the oracle of every numeric test.

pub mod calibrate;
pub mod closed_form;
pub mod sim;
pub mod spawn;
pub mod step;

pub use sim::{Fired, ReferenceSim};

use glam::DVec3;

/// One live particle as exported (GPU readback and reference alike), velocity as the integrator
/// knows it (Verlet's derived as displacement / h).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleRecord {
    /// Global spawn index.
    pub id: u32,
    /// Position (m).
    pub position: DVec3,
    /// Velocity (m/s).
    pub velocity: DVec3,
    /// Seconds since spawn.
    pub age: f64,
    /// Seconds it lives in all (whole steps), or None when it never dies of age.
    pub lifetime: Option<f64>,
    /// The colour its colour over life is multiplied by (`tint.rs`; white for none).
    pub tint: DVec3,
    /// Its kept attributes' words (`features::attributes`), in the layout's order: each
    /// number, and a vec3's three components in turn; 0 past the last.
    pub attributes: crate::features::attributes::Words,
}

/// Totals of a run so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    /// Steps done.
    pub steps: u64,
    /// Particles alive now.
    pub alive: u64,
    /// Particles spawned (requested and given a slot).
    pub spawned: u64,
    /// Particles that died (lifetime or kill volume).
    pub died: u64,
    /// Spawns dropped because capacity was full.
    pub dropped: u64,
}
