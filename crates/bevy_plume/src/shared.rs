//! Maps by main-world entity that the render world writes after the frame's steps and the
//! main world reads (measured bounds, lights given off, particle counts, GPU times): each a
//! resource that both worlds hold a clone of, the same map behind one `Arc`. One resource per
//! value type, so two maps never share a value type.

use std::sync::{Arc, Mutex, MutexGuard};

use bevy::ecs::entity::EntityHashMap;
use bevy::prelude::*;

/// A map by main-world entity held by both worlds.
#[derive(Resource)]
pub(crate) struct EntityShared<T: Send + Sync + 'static>(Arc<Mutex<EntityHashMap<T>>>);

impl<T: Send + Sync + 'static> Clone for EntityShared<T> {
    fn clone(&self) -> Self {
        Self(self.0.clone())
    }
}

impl<T: Send + Sync + 'static> Default for EntityShared<T> {
    fn default() -> Self {
        Self(Arc::default())
    }
}

impl<T: Send + Sync + 'static> EntityShared<T> {
    /// The map, even if a panicking thread left it poisoned.
    pub(crate) fn lock(&self) -> MutexGuard<'_, EntityHashMap<T>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}
