//! Bevy diagnostics of the plugin ([`PlumeDiagnosticsPlugin`]): what the render world's
//! [`PlumeRenderStats`] counts each frame, as measurements in Bevy's `DiagnosticsStore`, where
//! `LogDiagnosticsPlugin` or an on-screen overlay of the game's finds them.

use std::sync::{Arc, Mutex};

use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderSystems};

use crate::render::instances::PlumeRenderStats;

/// Adds Plume's diagnostics (add it beside [`crate::PlumePlugin`]): effect instances, batches,
/// camera draws (and of them the compute renderer's) and particle state on the GPU, measured
/// every frame from the render world's [`PlumeRenderStats`] of the frame before.
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
            .add_systems(Update, measure);
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
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

/// Adds the last counts to Bevy's diagnostics.
fn measure(mut diagnostics: Diagnostics, shared: Res<SharedStats>) {
    let Ok(s) = shared.0.lock().map(|s| *s) else {
        return;
    };
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::INSTANCES, || s.instances as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::BATCHES, || s.batches as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::DRAWS, || s.draws as f64);
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::COMPUTE_DRAWS, || {
        s.compute_draws as f64
    });
    diagnostics.add_measurement(&PlumeDiagnosticsPlugin::PARTICLE_MIB, || {
        s.particle_bytes as f64 / f64::from(1 << 20)
    });
}
