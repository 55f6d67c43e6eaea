//! An effect as an entity: [`PlumeEffect`], the component that names an effect file and says
//! how this instance of it plays.

use bevy::camera::visibility::{self, VisibilityClass};
use bevy::prelude::*;
use bevy::render::sync_world::SyncToRenderWorld;

use crate::asset::PlumeEffectAsset;

/// Where an effect's particles live.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
pub enum SimulationSpace {
    /// In the world: each particle starts where the entity was when it was emitted, then
    /// moves on its own, so a moving emitter leaves its particles behind (a rocket's smoke, a
    /// running character's dust). The effect's forces, colliders and kill volumes are in world
    /// coordinates. Such an effect is always stateful.
    #[default]
    World,
    /// In the entity's own space: the particles move, turn and scale with the entity (a
    /// flame on a torch that is carried, a trail of sparks on a spinning wheel's rim).
    Local,
}

/// A Plume effect playing at this entity's [`Transform`]: the effect file's handle and how
/// this instance plays. Every instance simulates on its own, on Bevy's render device, and is
/// drawn in Bevy's transparent 3D phase for every camera that sees it.
///
/// ```no_run
/// use bevy::prelude::*;
/// use bevy_plume::{PlumeEffect, PlumeEffectAsset};
///
/// fn spawn_fountain(mut commands: Commands, assets: Res<AssetServer>) {
///     let fountain: Handle<PlumeEffectAsset> = assets.load("fountain.plume.ron");
///     commands.spawn((PlumeEffect::new(fountain), Transform::from_xyz(0.0, 0.5, 0.0)));
/// }
/// ```
#[derive(Component, Clone, Debug)]
#[require(Transform, Visibility, VisibilityClass, SyncToRenderWorld)]
#[component(on_add = visibility::add_visibility_class::<PlumeEffect>)]
pub struct PlumeEffect {
    /// The effect file.
    pub handle: Handle<PlumeEffectAsset>,
    /// Where the particles live (default: the world, left behind by a moving entity).
    pub space: SimulationSpace,
    /// Whether time runs for this effect (false: it freezes, still drawn).
    pub playing: bool,
    /// How fast the effect's time runs against the app's (1: real time).
    pub time_scale: f32,
    /// Replaces the file's `seed` for this instance (the effect is compiled again for it,
    /// once per distinct seed), so two instances of one file need not look alike.
    pub seed: Option<u32>,
    /// Seconds of the effect's life simulated at once when it starts (or restarts), so that
    /// it appears already running.
    pub warm_up: f32,
    /// Bumped by [`Self::restart`]: each change starts the effect again from nothing.
    pub generation: u32,
}

impl PlumeEffect {
    /// The effect file `handle`, playing at real time from its start, the file's seed.
    pub fn new(handle: Handle<PlumeEffectAsset>) -> Self {
        Self {
            handle,
            space: SimulationSpace::World,
            playing: true,
            time_scale: 1.0,
            seed: None,
            warm_up: 0.0,
            generation: 0,
        }
    }

    /// With its particles in `space`.
    pub fn with_space(self, space: SimulationSpace) -> Self {
        Self { space, ..self }
    }

    /// With `seed` instead of the file's.
    pub fn with_seed(self, seed: u32) -> Self {
        Self {
            seed: Some(seed),
            ..self
        }
    }

    /// Starting as if it had already run for `seconds`.
    pub fn with_warm_up(self, seconds: f32) -> Self {
        Self {
            warm_up: seconds,
            ..self
        }
    }

    /// With its time running `scale` times as fast as the app's.
    pub fn with_time_scale(self, scale: f32) -> Self {
        Self {
            time_scale: scale,
            ..self
        }
    }

    /// Starts the effect again from nothing (its warm-up included) on the next frame.
    pub fn restart(&mut self) {
        self.generation = self.generation.wrapping_add(1);
    }
}
