//! An on-screen overlay of the plugin's diagnostics ([`PlumeOverlayPlugin`], behind the crate's
//! `overlay` feature): an egui window (bevy_egui) with what [`PlumeDiagnosticsPlugin`]
//! measures, Bevy's frame time where `FrameTimeDiagnosticsPlugin` is added, and each effect
//! entity's [`PlumeParticleCounts`] (and its steps' GPU time where it has a
//! [`crate::PlumeGpuTime`]).

use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::prelude::*;
use bevy_egui::{egui, EguiContexts, EguiPlugin, EguiPrimaryContextPass};

use crate::diagnostics::{PlumeDiagnosticsPlugin, PlumeParticleCounts};
use crate::effect::PlumeGpuTime;

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

/// The diagnostics table: each diagnostic of [`ROWS`] with a measurement, as (label, its
/// smoothed value with its suffix). A diagnostic not added, or with no measurement yet (the
/// GPU time on a device without timestamp queries), has no row.
fn diagnostic_rows(store: &DiagnosticsStore) -> Vec<(&'static str, String)> {
    ROWS.iter()
        .filter_map(|(label, path, digits)| {
            let diagnostic = store.get(path)?;
            let value = diagnostic.smoothed()?;
            Some((*label, format!("{value:.digits$}{}", diagnostic.suffix)))
        })
        .collect()
}

/// The effects table's headings: the steps' and draws' GPU times only where an entity asks
/// for them.
fn effect_headings(timed: bool) -> &'static [&'static str] {
    match timed {
        true => &[
            "effect",
            "alive",
            "spawned",
            "dropped",
            "steps' GPU ms",
            "draws' GPU ms",
        ],
        false => &["effect", "alive", "spawned", "dropped"],
    }
}

/// What the effects table reads of an entity.
type EffectItem<'a> = (
    Entity,
    Option<&'a Name>,
    &'a PlumeParticleCounts,
    Option<&'a PlumeGpuTime>,
);

/// The effects table: a row per effect entity with counts, by its `Name` where it has one
/// (else its entity), sorted by that; the GPU time columns (when `timed`) show an entity's
/// [`PlumeGpuTime`], "-" where it has none or no reading yet.
fn effect_rows<'a>(effects: impl Iterator<Item = EffectItem<'a>>, timed: bool) -> Vec<Vec<String>> {
    let mut rows: Vec<Vec<String>> = effects
        .map(|(entity, name, counts, time)| {
            let mut row = vec![
                name.map_or(entity.to_string(), Name::to_string),
                counts.alive.to_string(),
                counts.spawned.to_string(),
                counts.dropped.to_string(),
            ];
            if timed {
                let cell = |ms: Option<f32>| ms.map_or("-".to_string(), |ms| format!("{ms:.3}"));
                row.push(cell(time.and_then(|t| t.steps_ms)));
                row.push(cell(time.and_then(|t| t.draw_ms)));
            }
            row
        })
        .collect();
    rows.sort_by(|a, b| a[0].cmp(&b[0]));
    rows
}

/// The window: the diagnostics table ([`diagnostic_rows`]), then the effects table
/// ([`effect_rows`]).
fn overlay_window(
    mut contexts: EguiContexts,
    overlay: Res<PlumeOverlay>,
    store: Res<DiagnosticsStore>,
    effects: Query<EffectItem>,
    timed: Query<(), With<PlumeGpuTime>>,
) -> Result {
    if !overlay.shown {
        return Ok(());
    }
    let timed = !timed.is_empty();
    let context = contexts.ctx_mut()?;
    egui::Window::new("Plume")
        .anchor(egui::Align2::RIGHT_TOP, (-8.0, 8.0))
        .resizable(false)
        .show(context, |ui| {
            egui::Grid::new("plume diagnostics")
                .num_columns(2)
                .show(ui, |ui| {
                    for (label, value) in diagnostic_rows(&store) {
                        ui.label(label);
                        ui.label(value);
                        ui.end_row();
                    }
                });
            let rows = effect_rows(effects.iter(), timed);
            if rows.is_empty() {
                return;
            }
            ui.separator();
            let headings = effect_headings(timed);
            egui::Grid::new("plume effects")
                .num_columns(headings.len())
                .striped(true)
                .show(ui, |ui| {
                    for heading in headings {
                        ui.strong(*heading);
                    }
                    ui.end_row();
                    for row in rows {
                        for cell in row {
                            ui.label(cell);
                        }
                        ui.end_row();
                    }
                });
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use bevy::diagnostic::{Diagnostic, DiagnosticMeasurement};
    use bevy::platform::time::Instant;

    use super::*;

    /// A diagnostic at `path` with the given measurements.
    fn measured(path: DiagnosticPath, suffix: &'static str, values: &[f64]) -> Diagnostic {
        let mut diagnostic = Diagnostic::new(path).with_suffix(suffix);
        for &value in values {
            diagnostic.add_measurement(DiagnosticMeasurement {
                time: Instant::now(),
                value,
            });
        }
        diagnostic
    }

    #[test]
    fn the_diagnostics_table_shows_what_is_measured_in_its_own_order() {
        let mut store = DiagnosticsStore::default();
        store.add(measured(
            PlumeDiagnosticsPlugin::STEP_GPU_MS,
            " ms",
            &[0.25],
        ));
        store.add(measured(
            PlumeDiagnosticsPlugin::LIVE_PARTICLES,
            "",
            &[1200.0],
        ));
        store.add(measured(
            PlumeDiagnosticsPlugin::PARTICLE_MIB,
            " MiB",
            &[3.25],
        ));
        // Added, never measured (a device without timestamps leaves the GPU time so).
        store.add(measured(PlumeDiagnosticsPlugin::BATCHES, "", &[]));
        let rows = diagnostic_rows(&store);
        assert_eq!(
            rows,
            [
                ("live particles", "1200".to_string()),
                ("particle state", "3.2 MiB".to_string()),
                ("steps' GPU time", "0.250 ms".to_string()),
            ]
        );
    }

    #[test]
    fn the_effects_table_is_sorted_by_name_with_times_where_asked() {
        let counts = |alive| PlumeParticleCounts {
            alive,
            spawned: alive + 5,
            dropped: 1,
            ..Default::default()
        };
        let smoke = (Name::new("smoke"), counts(40));
        let sparks = (Name::new("sparks"), counts(7));
        let unnamed = (Entity::from_raw_u32(3).unwrap(), counts(2));
        let timed = PlumeGpuTime {
            steps_ms: Some(0.0626),
            draw_ms: Some(0.25),
        };
        let waiting = PlumeGpuTime::default();
        let items = || {
            [
                (
                    Entity::from_raw_u32(1).unwrap(),
                    Some(&sparks.0),
                    &sparks.1,
                    Some(&waiting),
                ),
                (
                    Entity::from_raw_u32(2).unwrap(),
                    Some(&smoke.0),
                    &smoke.1,
                    Some(&timed),
                ),
                (unnamed.0, None, &unnamed.1, None),
            ]
            .into_iter()
        };
        let row = |cells: &[&str]| cells.iter().map(|c| c.to_string()).collect::<Vec<_>>();
        let unnamed_label = unnamed.0.to_string();
        assert_eq!(
            effect_rows(items(), true),
            [
                row(&[&unnamed_label, "2", "7", "1", "-", "-"]),
                row(&["smoke", "40", "45", "1", "0.063", "0.250"]),
                row(&["sparks", "7", "12", "1", "-", "-"]),
            ]
        );
        assert_eq!(
            effect_rows(items(), false)[1],
            row(&["smoke", "40", "45", "1"])
        );
        assert_eq!(effect_headings(true).len(), 6);
        assert_eq!(effect_headings(false).len(), 4);
    }
}
