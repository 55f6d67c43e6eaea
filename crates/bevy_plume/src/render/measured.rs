//! Bounds measured on the GPU for effects whose file declares none: each frame the render
//! world records the live particles' box after the steps (`Effect::watch_live_bounds`, read
//! back without waiting) and puts each reading into [`MeasuredBounds`], a map both worlds
//! hold; the main world turns it into the entity's `Aabb` (`crate::effect::bounds_from_gpu`),
//! so Bevy's frustum culling skips an effect whose particles are all out of view.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bevy::prelude::*;

/// One effect's latest measured box, in its simulation space (the world for a world-space
/// effect, the entity's own space for a local one); None when no particle was alive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MeasuredBox {
    pub corners: Option<(Vec3, Vec3)>,
    /// Whether the box is in world coordinates (a world-space effect).
    pub in_world: bool,
}

/// The latest measured box of every running effect without declared bounds, by main-world
/// entity: written by the render world, read by the main world.
#[derive(Resource, Clone, Default)]
pub(crate) struct MeasuredBounds(pub Arc<Mutex<HashMap<Entity, MeasuredBox>>>);

impl MeasuredBounds {
    /// The map, even if a panicking thread left it poisoned.
    pub fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<Entity, MeasuredBox>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}
