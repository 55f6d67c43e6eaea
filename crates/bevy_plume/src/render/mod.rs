//! The render app's side of the plugin: extraction ([`extract`]; the scene's lights in
//! [`lights`]), the instances on Bevy's
//! device ([`instances`]), the compute work: steps before the cameras and each camera's draw
//! preparation before its main pass ([`simulate`], world-space steps along the entity's
//! motion in [`motion`]), and the draw in the transparent phases, 3D and 2D ([`draw`]), by the renderer
//! [`renderer_choice`] picks.

pub(crate) mod batches;
pub(crate) mod counts;
pub(crate) mod draw;
pub(crate) mod extract;
pub(crate) mod instances;
pub(crate) mod lights;
pub(crate) mod motion;
pub(crate) mod read;
pub(crate) mod renderer_choice;
pub(crate) mod simulate;

use bevy::core_pipeline::core_2d::Transparent2d;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d, Transparent3d};
use bevy::core_pipeline::schedule::camera_driver;
use bevy::core_pipeline::{Core2d, Core2dSystems, Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::render_phase::DrawFunctions;
use bevy::render::renderer::{RenderGraph, RenderGraphSystems};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderSystems};

/// Adds the render world's resources and systems (from [`crate::PlumePlugin::build`]).
pub(crate) fn build(app: &mut App) {
    // One map both worlds hold: the render world's readings, the main world's `Aabb`s.
    let measured = crate::bounds::MeasuredBounds::default();
    app.insert_resource(measured.clone());
    // And the lights particles give off: the render world's readings, the main world's
    // point lights.
    let given = crate::particle_lights::GivenLights::default();
    app.insert_resource(given.clone());
    // And the firings of reported events: the render world's readings, the main world's
    // messages.
    let fired = crate::event_reports::FiredEvents::default();
    app.insert_resource(fired.clone());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        warn!("bevy_plume: no render app (RenderPlugin missing): effects will not run");
        return;
    };
    render_app
        .insert_resource(measured)
        .insert_resource(given)
        .insert_resource(fired)
        .init_resource::<extract::ExtractedEffects>()
        .init_resource::<extract::ExtractedBursts>()
        .init_resource::<lights::ExtractedLights>()
        .init_resource::<instances::PlumeInstances>()
        .init_resource::<batches::PlumeBatches>()
        .init_resource::<instances::PlumeRenderStats>()
        .add_systems(
            ExtractSchedule,
            (
                extract::extract_effects,
                extract::extract_bursts,
                lights::extract_lights,
            )
                .chain(),
        )
        .add_systems(
            Render,
            (
                batches::sync_batches,
                instances::sync_instances,
                draw::queue_effects,
                draw::queue_effects_2d,
                draw::retire_unseen,
            )
                .chain()
                .in_set(RenderSystems::Queue),
        )
        .add_systems(
            RenderGraph,
            simulate::simulate
                .in_set(RenderGraphSystems::Render)
                .before(camera_driver),
        )
        .add_systems(
            Core3d,
            (
                simulate::prepare_for_view
                    .after(Core3dSystems::Prepass)
                    .before(Core3dSystems::MainPass),
                simulate::composite_for_view
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d),
                simulate::end_draw_timing.after(main_transparent_pass_3d),
            ),
        )
        .add_systems(
            Core2d,
            (
                simulate::prepare_for_view.before(Core2dSystems::MainPass),
                simulate::composite_for_view_2d
                    .after(simulate::prepare_for_view)
                    .before(Core2dSystems::MainPass),
                simulate::end_draw_timing.after(Core2dSystems::MainPass),
            ),
        );
}

/// Registers the draw function (from [`crate::PlumePlugin::finish`], once the core pipeline
/// has made the transparent phase's draw functions).
pub(crate) fn finish(app: &mut App) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    let Some(functions) = render_app
        .world()
        .get_resource::<DrawFunctions<Transparent3d>>()
    else {
        warn!(
            "bevy_plume: no 3D transparent phase (Core3dPlugin missing): effects will not be drawn"
        );
        return;
    };
    functions.write().add(draw::DrawPlume);
    match render_app
        .world()
        .get_resource::<DrawFunctions<Transparent2d>>()
    {
        Some(functions) => {
            functions.write().add(draw::DrawPlume);
        }
        None => debug!("bevy_plume: no 2D transparent phase (Core2dPlugin missing): 2D cameras draw no effects"),
    }
}
