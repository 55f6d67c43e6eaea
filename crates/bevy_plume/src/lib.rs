//! # bevy_plume
//!
//! Plume particle effects in Bevy. Effect files (any file `plume check` accepts: a single
//! system, or a graph of groups and events) are assets ([`PlumeEffectAsset`], hot-reloaded);
//! an effect is an entity with a [`PlumeEffect`]; it simulates on Bevy's own render device,
//! before the cameras draw, and is drawn in Bevy's transparent 3D phase by every camera that
//! sees it, depth-tested against the scene.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_plume::{PlumeEffect, PlumePlugin};
//!
//! fn main() {
//!     App::new()
//!         .add_plugins((DefaultPlugins, PlumePlugin))
//!         .add_systems(Startup, |mut commands: Commands, assets: Res<AssetServer>| {
//!             commands.spawn((Camera3d::default(), Transform::from_xyz(0.0, 2.0, 8.0)));
//!             commands.spawn(PlumeEffect::new(assets.load("fountain.plume.ron")));
//!         })
//!         .run();
//! }
//! ```
//!
//! See docs/bevy.md in the Plume repository for what is supported and what is measured.

// An item no path from the crate's root reaches is `pub(crate)`, so the public API reads as
// what it is and the dead-code lint sees the rest.
#![warn(unreachable_pub)]

mod asset;
mod bounds;
mod diagnostics;
mod effect;
mod event_reports;
pub mod headless;
mod mesh_particles;
#[cfg(feature = "overlay")]
mod overlay;
mod particle_lights;
mod render;
mod shared;
mod thinning;

pub use asset::{PlumeEffectAsset, PlumeEffectLoader, PlumeLoadError};
pub use diagnostics::{PlumeDiagnosticsPlugin, PlumeParticleCounts};
pub use effect::{
    PlumeBurst, PlumeDraw, PlumeEffect, PlumeGpuTime, PlumeSimulate, PlumeThinning,
    SimulationSpace, AUTO_COMPUTE_CAPACITY,
};
pub use event_reports::{PlumeEventFired, PlumeEventsMissed};
pub use mesh_particles::obj_of;
#[cfg(feature = "overlay")]
pub use overlay::{PlumeOverlay, PlumeOverlayPlugin};
pub use particle_lights::PlumeLightOf;
pub use plume_compiler;
pub use plume_runtime;
pub use render::batches::BATCH_FROM;
pub use render::instances::PlumeRenderStats;
pub use render::read::{read_particles, read_totals};
pub use thinning::{PlumeBudget, PlumeLod};

use bevy::camera::visibility::VisibilitySystems;
use bevy::prelude::*;

/// What the plugin does in the main world each frame, for game systems to order against. Game
/// code that fires bursts or sets params does so in `Update` (or anywhere before
/// [`PlumeSystems::Bursts`]); the render world steps and draws what the frame leaves.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PlumeSystems {
    /// `PostUpdate`, inside `VisibilitySystems::CalculateBounds`: each effect entity's `Aabb`,
    /// from its file's `bounds` or from the bounds the GPU measured.
    Bounds,
    /// `PostUpdate`: the cameras' depth made bindable while an effect may be drawn by the
    /// compute renderer.
    Cameras,
    /// `PostUpdate`: effect files compiled again with the Bevy mesh their entities draw
    /// particles as ([`PlumeEffect::with_mesh`]), on the async compute pool.
    Meshes,
    /// `PreUpdate`: the firings of reported events that the render world read back, written as
    /// [`PlumeEventFired`] (and [`PlumeEventsMissed`]) messages for `Update` to read.
    Reports,
    /// `PostUpdate`, after Bevy's visibility checks: each effect entity's [`PlumeThinning`],
    /// the fraction of its spawns it keeps from its spawn scale, its level of detail
    /// ([`PlumeLod`]) and the game's [`PlumeBudget`].
    Thinning,
    /// `Last`: the bursts fired this frame ([`PlumeEffect::burst`]) are taken from the effect
    /// entities into the queue the render world reads at extraction, so each spawns once.
    Bursts,
}

/// Adds Plume to an app: the effect asset and its loader (`*.plume.ron`, `*.plume`), and the
/// render-world systems that step and draw every [`PlumeEffect`]. Add it after
/// `DefaultPlugins` (it needs the asset, render and core pipeline plugins).
#[derive(Default)]
pub struct PlumePlugin;

impl Plugin for PlumePlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<PlumeEffectAsset>()
            .register_asset_loader(PlumeEffectLoader)
            .register_type::<PlumeEffect>()
            .register_type::<PlumeBurst>()
            .register_type::<SimulationSpace>()
            .register_type::<PlumeDraw>()
            .register_type::<PlumeSimulate>()
            .register_type::<PlumeLightOf>()
            .register_type::<PlumeLod>()
            .register_type::<PlumeThinning>()
            .register_type::<PlumeGpuTime>()
            .register_type::<PlumeBudget>()
            .init_resource::<thinning::MeasuredSteps>()
            .init_resource::<effect::FiredBursts>()
            .init_resource::<mesh_particles::MeshedEffects>()
            .add_message::<PlumeEventFired>()
            .add_message::<PlumeEventsMissed>()
            .add_systems(
                PreUpdate,
                event_reports::send_fired_events.in_set(PlumeSystems::Reports),
            )
            .configure_sets(
                PostUpdate,
                PlumeSystems::Bounds.in_set(VisibilitySystems::CalculateBounds),
            )
            .add_systems(
                PostUpdate,
                (bounds::bounds_from_files, bounds::bounds_from_gpu)
                    .chain()
                    .in_set(PlumeSystems::Bounds),
            )
            .add_systems(
                PostUpdate,
                effect::bindable_camera_depth.in_set(PlumeSystems::Cameras),
            )
            .add_systems(
                PostUpdate,
                mesh_particles::compile_meshed_effects.in_set(PlumeSystems::Meshes),
            )
            .configure_sets(
                PostUpdate,
                PlumeSystems::Thinning.after(VisibilitySystems::CheckVisibility),
            )
            .add_systems(
                PostUpdate,
                thinning::thin_effects.in_set(PlumeSystems::Thinning),
            )
            .add_systems(Last, effect::take_bursts.in_set(PlumeSystems::Bursts))
            .add_systems(PostUpdate, particle_lights::given_lights_to_point_lights);
        render::build(app);
    }

    fn finish(&self, app: &mut App) {
        render::finish(app);
    }
}
