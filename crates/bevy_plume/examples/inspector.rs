//! Every `PlumeEffect` in the scene shown and edited live in an egui window by
//! bevy-inspector-egui, through the component's `Reflect`: its params, time scale, pause
//! (`playing`), seed, spawn scale, space and renderer. A change takes effect from the next
//! frame (a new seed or space compiles its variant on Bevy's task pool, the particles go on
//! meanwhile; a param reaches the running kernels without a compile). Beside it, the plugin's
//! diagnostics in `PlumeOverlayPlugin`'s window.
//!
//! In a window: `cargo +nightly run --ignore-rust-version --features inspector --example
//! inspector`. A shot of the window's 120th frame (under Xvfb without a display):
//! `... --example inspector -- --window-shot inspector.png --frames 120`.

use bevy::diagnostic::FrameTimeDiagnosticsPlugin;
use bevy::prelude::*;
use bevy::reflect::ReflectMut;
use bevy_egui::{egui, EguiContext, EguiPlugin, EguiPrimaryContextPass, PrimaryEguiContext};
use bevy_inspector_egui::{bevy_inspector, DefaultInspectorConfigPlugin};
use bevy_plume::headless::{default_plugins, Headless, HeadlessPlugin};
use bevy_plume::{PlumeEffect, PlumeGpuTime, PlumeOverlayPlugin, PlumePlugin};

/// The repository's effect files, as the asset folder.
const EFFECTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../effects");

fn main() -> AppExit {
    let headless = match Headless::from_args() {
        Ok(Some(h)) if !h.window => {
            eprintln!("error: the inspector draws into the window: use --window-shot");
            return AppExit::from_code(2);
        }
        Ok(h) => h,
        Err(message) => {
            eprintln!("error: {message}\nusage: inspector [--window-shot OUT.png [--frames N]]");
            return AppExit::from_code(2);
        }
    };
    let mut app = App::new();
    app.add_plugins(default_plugins(headless.as_ref(), EFFECTS))
        .add_plugins(PlumePlugin)
        .add_plugins(EguiPlugin::default())
        // Bevy here is built without `reflect_auto_register`: the types the inspector's
        // defaults name are registered by hand, before its plugin.
        .register_type::<Name>()
        .add_plugins(DefaultInspectorConfigPlugin)
        // The plugin's diagnostics in a window of their own, at the top right.
        .add_plugins((FrameTimeDiagnosticsPlugin::default(), PlumeOverlayPlugin))
        .add_systems(Startup, setup)
        .add_systems(EguiPrimaryContextPass, effects_window);
    if let Some(headless) = headless {
        app.add_plugins(HeadlessPlugin(headless));
    }
    app.run()
}

/// A camera, and two effects: a fountain with a seed of its own, and a magnetic bottle whose
/// params (`gyro`, the field's turning rate, and `L`, the bottle's half length) are set at
/// spawn so that they can be dragged live; both timed on the GPU, for the overlay's column.
fn setup(mut commands: Commands, assets: Res<AssetServer>) {
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(-1.5, 3.0, 9.0).looking_at(Vec3::new(-1.5, 1.5, 0.0), Vec3::Y),
    ));
    commands.spawn((
        Name::new("fountain"),
        PlumeEffect::new(assets.load("fountain.ron")).with_seed(7),
        PlumeGpuTime::default(),
        Transform::from_xyz(-2.0, 0.0, 0.0),
    ));
    commands.spawn((
        Name::new("magnetic bottle"),
        PlumeEffect::new(assets.load("magnetic_bottle.ron"))
            .with_param("gyro", 3.0)
            .with_param("L", 1.0)
            .with_time_scale(0.5),
        PlumeGpuTime::default(),
        Transform::from_xyz(2.0, 1.5, 0.0),
    ));
}

/// One egui window listing every effect entity by name, each `PlumeEffect` field drawn by the
/// inspector from its reflection (the asset handle as its path: the compiled effect is not
/// `Reflect`); an edited effect is written back to its entity.
fn effects_window(world: &mut World) {
    let Ok(context) = world
        .query_filtered::<&mut EguiContext, With<PrimaryEguiContext>>()
        .single(world)
    else {
        return;
    };
    let mut context = context.clone();
    let mut effects: Vec<(Entity, String, PlumeEffect)> = world
        .query::<(Entity, Option<&Name>, &PlumeEffect)>()
        .iter(world)
        .map(|(e, name, effect)| {
            (
                e,
                name.map_or(e.to_string(), Name::to_string),
                effect.clone(),
            )
        })
        .collect();
    effects.sort_by(|a, b| a.1.cmp(&b.1));
    egui::Window::new("Plume effects")
        .default_pos((8.0, 8.0))
        .default_width(300.0)
        .default_height(680.0)
        .show(context.get_mut(), |ui| {
            egui::ScrollArea::vertical()
                .auto_shrink(false)
                .show(ui, |ui| {
                    for (entity, name, mut effect) in effects {
                        let path = effect.handle.path().map(ToString::to_string);
                        let changed = ui
                            .push_id(entity, |ui| {
                                egui::CollapsingHeader::new(name)
                                    .default_open(true)
                                    .show(ui, |ui| effect_fields(&mut effect, path, ui, world))
                                    .body_returned
                                    .unwrap_or(false)
                            })
                            .inner;
                        if changed {
                            if let Some(mut current) = world.get_mut::<PlumeEffect>(entity) {
                                *current = effect;
                            }
                        }
                    }
                });
        });
}

/// A grid of an effect's fields, each edited through its reflection; true when one changed.
fn effect_fields(
    effect: &mut PlumeEffect,
    path: Option<String>,
    ui: &mut egui::Ui,
    world: &mut World,
) -> bool {
    let ReflectMut::Struct(fields) = effect.reflect_mut() else {
        return false;
    };
    let mut changed = false;
    egui::Grid::new("fields").num_columns(2).show(ui, |ui| {
        for i in 0..fields.field_len() {
            let name = fields.name_at(i).unwrap_or_default().to_string();
            ui.label(&name);
            if name == "handle" {
                ui.label(path.as_deref().unwrap_or("(not from a file)"));
            } else if let Some(field) = fields.field_at_mut(i).and_then(|f| f.try_as_reflect_mut())
            {
                changed |= ui
                    .push_id(i, |ui| bevy_inspector::ui_for_value(field, ui, world))
                    .inner;
            }
            ui.end_row();
        }
    });
    changed
}
