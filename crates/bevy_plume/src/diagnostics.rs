//! Bevy diagnostics of the plugin ([`PlumeDiagnosticsPlugin`]): what the render world's
//! [`PlumeRenderStats`] counts each frame, as measurements in Bevy's `DiagnosticsStore`, where
//! `LogDiagnosticsPlugin` or an on-screen overlay of the game's finds them; and each effect
//! entity's particle counts as its [`PlumeParticleCounts`] component.

use std::sync::{Arc, Mutex};

use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderSystems};

use crate::effect::PlumeGpuTime;
use crate::render::counts::{SharedCounts, SharedGpuTimes, WatchedCounts};
use crate::render::instances::PlumeRenderStats;
use crate::thinning::MeasuredSteps;

/// An effect entity's particles, as last read back from the GPU without waiting (a frame or
/// two old), kept up to date while [`PlumeDiagnosticsPlugin`] is added. A batched entity has
/// none (its batch's particles count in [`PlumeDiagnosticsPlugin::LIVE_PARTICLES`]).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Eq, Reflect)]
#[reflect(Component)]
pub struct PlumeParticleCounts {
    /// Steps done when they were read.
    pub steps: u64,
    /// Particles alive.
    pub alive: u64,
    /// Particles spawned since the start.
    pub spawned: u64,
    /// Particles that died.
    pub died: u64,
    /// Particles dropped for want of room.
    pub dropped: u64,
}

impl From<plume_compiler::reference::Totals> for PlumeParticleCounts {
    fn from(t: plume_compiler::reference::Totals) -> Self {
        Self {
            steps: t.steps,
            alive: t.alive,
            spawned: t.spawned,
            died: t.died,
            dropped: t.dropped,
        }
    }
}

/// Adds Plume's diagnostics (add it beside [`crate::PlumePlugin`]): effect instances, batches,
/// camera draws (and of them the compute renderer's), particle state on the GPU, live
/// particles and the GPU time of the steps, measured every frame from the render world's
/// [`PlumeRenderStats`] of the frame before; each effect entity's [`PlumeParticleCounts`]; and
/// the steps' GPU time of each entity that asks for it with a [`crate::PlumeGpuTime`].
/// The live counts and the timestamps are read back without waiting (a copy of a few bytes per
/// effect a frame), only while this plugin is added.
#[derive(Default)]
pub struct PlumeDiagnosticsPlugin;

impl PlumeDiagnosticsPlugin {
    /// Effect instances running.
    pub const INSTANCES: DiagnosticPath = DiagnosticPath::const_new("plume/instances");
    /// Batches of instances running.
    pub const BATCHES: DiagnosticPath = DiagnosticPath::const_new("plume/batches");
    /// Camera draws of an effect queued in the frame.
    pub const DRAWS: DiagnosticPath = DiagnosticPath::const_new("plume/draws");
    /// Of those, the compute renderer's.
    pub const COMPUTE_DRAWS: DiagnosticPath = DiagnosticPath::const_new("plume/compute_draws");
    /// Particle state on the GPU, in MiB.
    pub const PARTICLE_MIB: DiagnosticPath = DiagnosticPath::const_new("plume/particle_mib");
    /// Particles alive in every effect, as last read back.
    pub const LIVE_PARTICLES: DiagnosticPath = DiagnosticPath::const_new("plume/live_particles");
    /// GPU time of a frame's steps (every effect's), in ms; not measured where the device has
    /// no timestamp queries.
    pub const STEP_GPU_MS: DiagnosticPath = DiagnosticPath::const_new("plume/step_gpu_ms");
}

/// The render world's last counts, shared with the main world.
#[derive(Resource, Clone, Default)]
struct SharedStats(Arc<Mutex<PlumeRenderStats>>);

impl Plugin for PlumeDiagnosticsPlugin {
    fn build(&self, app: &mut App) {
        let shared = SharedStats::default();
        app.insert_resource(shared.clone())
            .register_diagnostic(Diagnostic::new(Self::INSTANCES))
            .register_diagnostic(Diagnostic::new(Self::BATCHES))
            .register_diagnostic(Diagnostic::new(Self::DRAWS))
            .register_diagnostic(Diagnostic::new(Self::COMPUTE_DRAWS))
            .register_diagnostic(Diagnostic::new(Self::PARTICLE_MIB).with_suffix(" MiB"))
            .register_diagnostic(Diagnostic::new(Self::LIVE_PARTICLES))
            .register_diagnostic(Diagnostic::new(Self::STEP_GPU_MS).with_suffix(" ms"))
            .register_type::<PlumeParticleCounts>()
            .add_systems(Update, (measure, particle_counts, gpu_times));
        let watched = WatchedCounts::default();
        app.insert_resource(watched.shared.clone())
            .insert_resource(watched.gpu_times.clone());
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .insert_resource(watched)
                .insert_resource(shared)
                .add_systems(Render, share_stats.in_set(RenderSystems::Cleanup));
        }
    }
}

/// Copies the frame's counts for the main world (after the draws are queued).
fn share_stats(stats: Res<PlumeRenderStats>, shared: Res<SharedStats>) {
    if let Ok(mut s) = shared.0.lock() {
        *s = *stats;
    }
}

/// Adds the last counts to Bevy's diagnostics, and the steps' GPU time to what the budget
/// reads.
fn measure(
    mut diagnostics: Diagnostics,
    shared: Res<SharedStats>,
    measured: Option<ResMut<MeasuredSteps>>,
) {
    let Ok(s) = shared.0.lock().map(|s| *s) else {
        return;
    };
    if let Some(mut measured) = measured {
        measured.gpu_ms = s.step_gpu_ns.map(|ns| ns as f32 * 1e-6);
    }
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::INSTANCES, || s.instances as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::BATCHES, || s.batches as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::DRAWS, || s.draws as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::COMPUTE_DRAWS, || {
        s.compute_draws as f64
    });
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::PARTICLE_MIB, || {
        s.particle_bytes as f64 / f64::from(1 << 20)
    });
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::LIVE_PARTICLES, || {
        s.live_particles as f64
    });
    if let Some(ns) = s.step_gpu_ns {
        diagnostics.add_measurement(&PlumeDiagnosticsPlugin::STEP_GPU_MS, || ns as f64 * 1e-6);
    }
}

/// Gives each effect entity its last counts.
fn particle_counts(
    mut commands: Commands,
    shared: Res<SharedCounts>,
    mut counted: Query<(Entity, &mut PlumeParticleCounts)>,
) {
    let shared = shared.lock();
    for (entity, mut counts) in &mut counted {
        if !shared.contains_key(&entity) {
            commands.entity(entity).remove::<PlumeParticleCounts>();
        } else {
            counts.set_if_neq(shared[&entity].into());
        }
    }
    for (entity, t) in shared.iter() {
        if counted.contains(*entity) {
            continue;
        }
        if let Ok(mut e) = commands.get_entity(*entity) {
            e.insert(PlumeParticleCounts::from(*t));
        }
    }
}

/// Gives each timed effect entity its steps' and draws' last GPU times.
fn gpu_times(shared: Res<SharedGpuTimes>, mut timed: Query<(Entity, &mut PlumeGpuTime)>) {
    let shared = shared.lock();
    let ms = |ns: Option<u64>| ns.map(|ns| ns as f32 * 1e-6);
    for (entity, mut time) in &mut timed {
        let times = shared.get(&entity).copied().unwrap_or_default();
        let now = PlumeGpuTime {
            steps_ms: ms(times.steps_ns),
            draw_ms: ms(times.draw_ns),
        };
        if *time != now {
            *time = now;
        }
    }
}
