//! An on-screen overlay of the plugin's diagnostics ([`PlumeOverlayPlugin`], behind the crate's
//! `overlay` feature): an egui window (bevy_egui) with what [`PlumeDiagnosticsPlugin`]
//! measures, Bevy's frame time where `FrameTimeDiagnosticsPlugin` is added, and each effect
//! entity's [`PlumeParticleCounts`].

use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::prelude::*;
use bevy_egui::{egui, EguiContexts, EguiPlugin, EguiPrimaryContextPass};

use crate::diagnostics::{PlumeDiagnosticsPlugin, PlumeParticleCounts};

/// Adds the overlay window to the primary window, and [`PlumeDiagnosticsPlugin`] when it is not
/// added yet. Add it after bevy_egui's `EguiPlugin` when the game adds that itself; otherwise
/// it adds `EguiPlugin` too. [`PlumeOverlay`] shows and hides the window.
///
/// ```no_run
/// use bevy::diagnostic::FrameTimeDiagnosticsPlugin;
/// use bevy::prelude::*;
/// use bevy_plume::{PlumeOverlay, PlumeOverlayPlugin, PlumePlugin};
///
/// App::new()
///     .add_plugins((DefaultPlugins, PlumePlugin))
///     .add_plugins((FrameTimeDiagnosticsPlugin::default(), PlumeOverlayPlugin))
///     // F3 shows and hides the window.
///     .add_systems(Update, |keys: Res<ButtonInput<KeyCode>>, mut overlay: ResMut<PlumeOverlay>| {
///         if keys.just_pressed(KeyCode::F3) {
///             overlay.shown = !overlay.shown;
///         }
///     })
///     .run();
/// ```
#[derive(Default)]
pub struct PlumeOverlayPlugin;

/// Whether the overlay window is shown (true unless set otherwise).
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq, Reflect)]
#[reflect(Resource)]
pub struct PlumeOverlay {
    /// The window is drawn.
    pub shown: bool,
}

impl Default for PlumeOverlay {
    fn default() -> Self {
        Self { shown: true }
    }
}

impl Plugin for PlumeOverlayPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        if !app.is_plugin_added::<PlumeDiagnosticsPlugin>() {
            app.add_plugins(PlumeDiagnosticsPlugin);
        }
        app.init_resource::<PlumeOverlay>()
            .register_type::<PlumeOverlay>()
            .add_systems(EguiPrimaryContextPass, overlay_window);
    }
}

/// The rows of the diagnostics table: label, path, digits after the point.
const ROWS: [(&str, DiagnosticPath, usize); 8] = [
    ("frame", FrameTimeDiagnosticsPlugin::FRAME_TIME, 2),
    ("live particles", PlumeDiagnosticsPlugin::LIVE_PARTICLES, 0),
    ("instances", PlumeDiagnosticsPlugin::INSTANCES, 0),
    ("batches", PlumeDiagnosticsPlugin::BATCHES, 0),
    ("draws", PlumeDiagnosticsPlugin::DRAWS, 0),
    ("of them computed", PlumeDiagnosticsPlugin::COMPUTE_DRAWS, 0),
    ("particle state", PlumeDiagnosticsPlugin::PARTICLE_MIB, 1),
    ("steps' GPU time", PlumeDiagnosticsPlugin::STEP_GPU_MS, 3),
];

/// The window: each diagnostic's smoothed value with its suffix (a row whose diagnostic has no
/// measurement yet, such as the GPU time on a device without timestamp queries, is left out),
/// then a row per effect entity with counts, named by its `Name` where it has one.
fn overlay_window(
    mut contexts: EguiContexts,
    overlay: Res<PlumeOverlay>,
    store: Res<DiagnosticsStore>,
    effects: Query<(Entity, Option<&Name>, &PlumeParticleCounts)>,
) -> Result {
    if !overlay.shown {
        return Ok(());
    }
    let context = contexts.ctx_mut()?;
    egui::Window::new("Plume")
        .anchor(egui::Align2::RIGHT_TOP, (-8.0, 8.0))
        .resizable(false)
        .show(context, |ui| {
            egui::Grid::new("plume diagnostics")
                .num_columns(2)
                .show(ui, |ui| {
                    for (label, path, digits) in &ROWS {
                        let Some(diagnostic) = store.get(path) else {
                            continue;
                        };
                        let Some(value) = diagnostic.smoothed() else {
                            continue;
                        };
                        ui.label(*label);
                        ui.label(format!("{value:.digits$}{}", diagnostic.suffix));
                        ui.end_row();
                    }
                });
            let mut rows: Vec<(String, PlumeParticleCounts)> = effects
                .iter()
                .map(|(entity, name, counts)| {
                    (name.map_or(entity.to_string(), Name::to_string), *counts)
                })
                .collect();
            if rows.is_empty() {
                return;
            }
            rows.sort_by(|a, b| a.0.cmp(&b.0));
            ui.separator();
            egui::Grid::new("plume effects")
                .num_columns(4)
                .striped(true)
                .show(ui, |ui| {
                    for heading in ["effect", "alive", "spawned", "dropped"] {
                        ui.strong(heading);
                    }
                    ui.end_row();
                    for (name, counts) in rows {
                        ui.label(name);
                        ui.label(counts.alive.to_string());
                        ui.label(counts.spawned.to_string());
                        ui.label(counts.dropped.to_string());
                        ui.end_row();
                    }
                });
        });
    Ok(())
}
