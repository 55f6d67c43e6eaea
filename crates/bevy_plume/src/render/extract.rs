//! What the render world copies from the main world each frame: every effect entity with its
//! compiled effect, transform and controls, and the frame's time step.

use bevy::prelude::*;
use bevy::render::sync_world::RenderEntity;
use bevy::render::Extract;

use crate::asset::PlumeEffectAsset;
use crate::effect::{PlumeBurst, PlumeEffect, PlumeGpuTime, PlumeThinning};

/// One effect entity as the render world sees it this frame.
#[derive(Clone)]
pub(crate) struct ExtractedEffect {
    /// The entity in the main world (the key of its instance).
    pub main: Entity,
    /// Its twin in the render world (what phase items name).
    pub render: Entity,
    /// The effect file's current version (a new `graph` after a hot reload; cheap to clone).
    pub asset: PlumeEffectAsset,
    /// The entity's world transform.
    pub world_from_local: Mat4,
    /// The component's controls.
    pub control: PlumeEffect,
    /// Whether a camera saw the entity in the main world's last frame.
    pub visible: bool,
    /// The fraction of its spawns it keeps ([`crate::PlumeThinning::scale`]).
    pub spawn_scale: f32,
    /// Whether its steps' GPU time is asked for ([`crate::PlumeGpuTime`]).
    pub timed: bool,
    /// Whether the budget's GPU time pauses its steps ([`crate::PlumeThinning::paused`]).
    pub paused: bool,
}

impl ExtractedEffect {
    /// Seconds of the effect's time this frame of `delta` app seconds: scaled, and none while
    /// paused (by game code or the budget), or unseen when it simulates only while visible.
    pub(crate) fn effect_time(&self, delta: f64) -> f64 {
        let runs = !self.paused && self.control.steps_when(self.visible);
        match runs {
            true => delta * f64::from(self.control.time_scale.max(0.0)),
            false => 0.0,
        }
    }
}

/// Every effect entity whose file has loaded, and the app's time step, this frame.
#[derive(Resource, Default)]
pub(crate) struct ExtractedEffects {
    /// The effects, in no particular order.
    pub effects: Vec<ExtractedEffect>,
    /// Seconds of app time since the last frame.
    pub delta: f64,
}

/// What [`extract_effects`] reads of each effect entity.
type EffectItem = (
    Entity,
    RenderEntity,
    &'static PlumeEffect,
    &'static GlobalTransform,
    &'static ViewVisibility,
    &'static PlumeThinning,
    Has<PlumeGpuTime>,
);

/// Copies the effect entities and the time step into [`ExtractedEffects`]. Entities whose
/// file has not loaded (or never compiled), or not yet with their Bevy mesh, are left out:
/// they simulate nothing yet.
pub(crate) fn extract_effects(
    mut extracted: ResMut<ExtractedEffects>,
    effects: Extract<Query<EffectItem>>,
    assets: Extract<Res<Assets<PlumeEffectAsset>>>,
    meshed: Extract<Res<crate::mesh_particles::MeshedEffects>>,
    time: Extract<Res<Time>>,
) {
    extracted.effects.clear();
    extracted.delta = time.delta_secs_f64();
    for (main, render, control, transform, seen, thinning, timed) in &effects {
        // Drawn as a Bevy mesh: the file compiled with it, once that is done.
        let handle = match &control.mesh {
            Some(mesh) => match meshed.get(&control.handle, mesh) {
                Some(handle) => handle,
                None => continue,
            },
            None => &control.handle,
        };
        let Some(asset) = assets.get(handle) else {
            continue;
        };
        extracted.effects.push(ExtractedEffect {
            main,
            render,
            asset: asset.clone(),
            world_from_local: transform.to_matrix(),
            control: control.clone(),
            visible: seen.get(),
            spawn_scale: thinning.scale,
            timed,
            paused: thinning.paused,
        });
    }
}

/// The bursts game code fired since the last frame, by main-world entity.
#[derive(Resource, Default)]
pub(crate) struct ExtractedBursts(pub Vec<(Entity, Vec<PlumeBurst>)>);

/// Copies the bursts the main world took from its effects this frame
/// ([`crate::PlumeSystems::Bursts`]): read, never written, as extraction should.
pub(crate) fn extract_bursts(
    fired: Extract<Res<crate::effect::FiredBursts>>,
    mut taken: ResMut<ExtractedBursts>,
) {
    taken.0.clone_from(&fired.0);
}
