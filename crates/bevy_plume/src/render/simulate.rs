//! The frame's GPU work for the effects: every instance's steps, once a frame before Bevy's
//! cameras draw ([`simulate`]); then, in each camera's own schedule just before its main pass,
//! what each draw needs from that camera: the view, and for `sort` the depth order
//! ([`prepare_for_view`]), and for a `SceneDepth` collider a copy of the camera's depth
//! prepass for the next frame's steps. The depth order lives in the effect's buffers, so
//! preparing it per camera, right before that camera draws, gives every camera its own
//! back-to-front order. A draw by the compute renderer is prepared later, between the
//! camera's opaque and transparent passes ([`composite_for_view`]): it reads the depth the
//! opaque pass drew.

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::ecs::entity::{EntityHashMap, EntityHashSet};
use bevy::ecs::system::SystemParam;
use bevy::pbr::ViewShadowBindings;
use bevy::prelude::*;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::view::{ExtractedView, ViewDepthStencilTexture};
use plume_compiler::placement::Placement;
use plume_runtime::{BoundsWatch, Camera, Lights};

use crate::bounds::{MeasuredBounds, MeasuredBox};
use crate::effect::SimulationSpace;
use crate::event_reports::FiredEvents;
use crate::particle_lights::GivenLights;
use crate::render::batches::{BatchView, PlumeBatches};
use crate::render::counts::WatchedCounts;
use crate::render::instances::{DrawTiming, Instance, PlumeInstances, PlumeRenderStats};
use crate::render::lights::ExtractedLights;
use crate::render::motion;

/// What the render world reads back after the steps for the main world: measured bounds,
/// the lights particles give off, the firings of reported events.
#[derive(SystemParam)]
pub(crate) struct Readings<'w> {
    measured: Res<'w, MeasuredBounds>,
    given: Res<'w, GivenLights>,
    fired: Res<'w, FiredEvents>,
}

/// Steps every instance. An instance whose frame is one part (the usual frame: one place, a
/// few steps) has its steps planned, and all of those are recorded in one compute pass: a pass
/// per instance cost the CPU more than the steps themselves for small effects. The rest (a
/// world-space frame in parts, an effect with events) record their own passes.
pub(crate) fn simulate(
    mut context: RenderContext,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
    readings: Readings,
    mut watched: Option<ResMut<WatchedCounts>>,
    mut stats: ResMut<PlumeRenderStats>,
) {
    let Readings {
        measured,
        given,
        fired,
    } = readings;
    let encoder = context.command_encoder();
    if let (Some(watched), Some(gpu)) = (watched.as_deref_mut(), store.gpu.as_ref()) {
        watched.begin(gpu, encoder);
    }
    batches.record_steps(encoder);
    let mut planned = Vec::new();
    // An instance whose GPU time is asked for is timed only while the diagnostics read back.
    let timing = watched.is_some();
    let gpu = timing.then(|| store.gpu.clone()).flatten();
    for (entity, instance) in store.instances.iter_mut() {
        let timed = timing && instance.timed && begin_timing(instance, gpu.as_ref(), encoder);
        let steps = std::mem::take(&mut instance.clock.steps);
        let in_world = instance.space == SimulationSpace::World;
        let name = &instance.effect.compiled().ir.name;
        let finite = instance.world_from_local.is_finite();
        if in_world && !finite {
            warn!(
                "{name}: the entity's transform is not finite; its emitters stay where they were"
            );
        }
        // World space: the frame's steps spawn along the entity's way from where it was.
        let to = instance.world_from_local;
        let parts = match (in_world && finite, steps) {
            (_, 0) => Vec::new(),
            (true, _) => motion::parts(steps, instance.placed_at.unwrap_or(to), to),
            (false, _) => vec![(steps, to)],
        };
        // One plan holds at most 256 steps (a long warm-up records its own passes); a timed
        // instance records its own passes, between its timestamps.
        let plan = !timed && parts.len() == 1 && steps <= 256 && instance.effect.plans_steps();
        for (n, at) in parts {
            if in_world && finite {
                if let Some(placement) = Placement::from_cols(at.to_cols_array()) {
                    instance.effect.set_placement(placement);
                }
            }
            let recorded = match plan {
                true => instance
                    .effect
                    .plan_steps(encoder, n)
                    .map(|steps| planned.push((*entity, steps))),
                false => instance.effect.advance(encoder, n),
            };
            if let Err(err) = recorded {
                error!("{}: {err}", instance.effect.compiled().ir.name);
                break;
            }
        }
        if finite {
            instance.placed_at = Some(to);
        }
        if let Some(timer) = instance.timer.as_mut().filter(|_| timed) {
            timer.end(encoder);
        }
    }
    // Bounds: the planned instances' reductions go into the shared pass, after their steps.
    let mut boxes = measured.lock();
    boxes.retain(|entity, _| store.instances.contains_key(entity));
    let mut reducing = EntityHashSet::default();
    for (entity, _) in &planned {
        if let Some(instance) = store.instances.get(entity).filter(|i| measures_bounds(i)) {
            match instance.effect.watch_bounds_begin(encoder) {
                Ok((watch, now)) => {
                    note_bounds(&mut boxes, *entity, instance, watch);
                    if now {
                        reducing.insert(*entity);
                    }
                }
                Err(err) => warn_once!("{}: {err}", instance.effect.compiled().ir.name),
            }
        }
    }
    if !planned.is_empty() {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("plume steps"),
            timestamp_writes: None,
        });
        for (entity, steps) in &planned {
            let Some(instance) = store.instances.get(entity) else {
                continue;
            };
            let effect = &instance.effect;
            let mut recorded = effect.record_planned(&mut pass, steps);
            if recorded.is_ok() && reducing.contains(entity) {
                recorded = effect.watch_bounds_dispatch(&mut pass);
            }
            if let Err(err) = recorded {
                error!("{}: {err}", effect.compiled().ir.name);
            }
        }
    }
    for entity in &reducing {
        if let Some(instance) = store.instances.get(entity) {
            if let Err(err) = instance.effect.watch_bounds_end(encoder) {
                warn_once!("{}: {err}", instance.effect.compiled().ir.name);
            }
        }
    }
    // The rest measure in passes of their own.
    let planned: EntityHashSet = planned.iter().map(|(e, _)| *e).collect();
    for (entity, instance) in &store.instances {
        if !measures_bounds(instance) {
            boxes.remove(entity);
            continue;
        }
        if planned.contains(entity) {
            continue;
        }
        match instance.effect.watch_live_bounds(encoder) {
            Ok(watch) => note_bounds(&mut boxes, *entity, instance, watch),
            Err(err) => warn_once!("{}: {err}", instance.effect.compiled().ir.name),
        }
    }
    drop(boxes);
    watch_particle_lights(encoder, &mut store, &given);
    watch_reports(encoder, &store, &fired);
    if let Some(watched) = watched.as_deref_mut() {
        watched.end(encoder, &mut store, &mut batches, &mut stats);
    }
}

/// Stamps the start of a timed instance's steps (making its timer on the first frame), taking
/// the time of an earlier frame's that came back; false where the device has no timestamp
/// queries or the last reading is still out (its steps then go untimed this frame).
fn begin_timing(
    instance: &mut Instance,
    gpu: Option<&plume_runtime::Gpu>,
    encoder: &mut wgpu::CommandEncoder,
) -> bool {
    if instance.timer.is_none() {
        instance.timer = gpu.and_then(plume_runtime::GpuTimer::new);
    }
    let Some(timer) = instance.timer.as_mut() else {
        return false;
    };
    match timer.begin(encoder) {
        Ok(taken) => {
            instance.step_gpu_ns = taken.or(instance.step_gpu_ns);
            timer.is_begun()
        }
        Err(err) => {
            warn_once!(
                "{}: its steps' timer: {err}",
                instance.effect.compiled().ir.name
            );
            false
        }
    }
}

/// Records each reporting instance's readback after its steps, and queues the firings that
/// came back, in world space, for the main world's messages.
fn watch_reports(encoder: &mut wgpu::CommandEncoder, store: &PlumeInstances, fired: &FiredEvents) {
    for (entity, instance) in &store.instances {
        if !instance.effect.reports_events() {
            continue;
        }
        match instance.effect.watch_reports(encoder) {
            Ok(reports) if !reports.is_empty() => {
                // A local-space effect reports in its own space.
                let to_world = match instance.space {
                    SimulationSpace::World => Mat4::IDENTITY,
                    SimulationSpace::Local => instance.world_from_local,
                };
                fired.push(*entity, reports, to_world);
            }
            Ok(_) => {}
            Err(err) => warn_once!("{}: {err}", instance.effect.compiled().ir.name),
        }
    }
}

/// Records each instance's light pick after its steps (`render.light`), and puts the lights
/// that came back, in world space, into `given` for the main world's point lights.
fn watch_particle_lights(
    encoder: &mut wgpu::CommandEncoder,
    store: &mut PlumeInstances,
    given: &GivenLights,
) {
    let mut lights = given.lock();
    lights.retain(|entity, _| store.instances.contains_key(entity));
    for (entity, instance) in store.instances.iter_mut() {
        // Made once: empty for an effect whose particles give off no light.
        if instance.particle_lights.is_none() {
            match instance.effect.particle_lights() {
                Ok(probe) => instance.particle_lights = Some(probe),
                Err(err) => {
                    warn_once!("{}: {err}", instance.effect.compiled().ir.name);
                    continue;
                }
            }
        }
        let Some(probe) = instance.particle_lights.as_ref().filter(|p| !p.is_empty()) else {
            continue;
        };
        match probe.watch(&instance.effect, encoder) {
            Ok(Some(read)) => {
                // A local-space effect's lights are in its own space.
                let world = match instance.space {
                    SimulationSpace::World => Mat4::IDENTITY,
                    SimulationSpace::Local => instance.world_from_local,
                };
                let to_world = plume_runtime::glam::Mat4::from_cols_array(&world.to_cols_array());
                let in_world = plume_runtime::Lights {
                    ambient: plume_runtime::glam::DVec3::ZERO,
                    sources: read,
                    shadow: None,
                }
                .transformed(to_world.as_dmat4());
                lights.insert(*entity, in_world.sources);
            }
            Ok(None) => {}
            Err(err) => warn_once!("{}: {err}", instance.effect.compiled().ir.name),
        }
    }
}

/// Whether an instance's bounds are measured: a stateful effect whose file declares none.
fn measures_bounds(instance: &Instance) -> bool {
    instance.effect.compiled().ir.bounds.is_none() && !instance.effect.is_stateless()
}

/// Puts a reading that came back into `boxes`.
fn note_bounds(
    boxes: &mut EntityHashMap<MeasuredBox>,
    entity: Entity,
    instance: &Instance,
    watch: BoundsWatch,
) {
    if let BoundsWatch::Measured(bounds) = watch {
        let corners = bounds.map(|b| (Vec3::from(b.min), Vec3::from(b.max)));
        let in_world = instance.space == SimulationSpace::World;
        boxes.insert(entity, MeasuredBox { corners, in_world });
    }
}

/// Prepares every draw the current camera queued this frame, in the camera's schedule before
/// its main pass.
pub(crate) fn prepare_for_view(
    view: ViewQuery<(
        Entity,
        &ExtractedView,
        Option<&ViewPrepassTextures>,
        Option<&ViewShadowBindings>,
    )>,
    mut context: RenderContext,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
    lights: Res<ExtractedLights>,
    watched: Option<Res<WatchedCounts>>,
) {
    let (view_entity, view, prepass, shadows) = view.into_inner();
    // The scene's lights as this camera sees them (its exposure, its own ambient light).
    let lights = lights.for_view(view_entity);
    // Bevy's directional shadow map of this camera, when a light casts shadows.
    let shadow_map = shadows
        .filter(|_| lights.shadow.is_some())
        .map(|s| &*s.directional_light_depth_texture);
    let encoder = context.command_encoder();
    let frame = store.frame;
    // A batch is in world space: drawn through the camera alone.
    for batch in batches.batches_mut() {
        if let Some(BatchView {
            renderer,
            frame: queued,
            ..
        }) = batch.views.get_mut(&view_entity)
        {
            if *queued != frame {
                continue;
            }
            if renderer.is_soft() && !renderer.is_compute() {
                if let Some(depth) = prepass.and_then(|p| p.depth_only_view()) {
                    renderer.set_scene_depth(depth);
                }
            }
            renderer.set_lights(&lights);
            if let Some(map) = shadow_map {
                if let Err(err) = renderer.set_shadow_map(map) {
                    warn_once!("{}: {err}", batch.batch.compiled().ir.name);
                }
            }
            // The compute renderer's draw is prepared after the opaque pass
            // (`composite_for_view`).
            if renderer.is_compute() {
                continue;
            }
            let camera = view_camera(view, Mat4::IDENTITY);
            if let Err(err) = batch
                .batch
                .effect()
                .prepare_draw(encoder, renderer, &camera)
            {
                error!("{}: {err}", batch.batch.compiled().ir.name);
            }
        }
    }
    let PlumeInstances { instances, gpu, .. } = &mut *store;
    for instance in instances.values_mut() {
        // Drawn through the entity's transform only in local space.
        let world_from_local = match instance.space {
            SimulationSpace::World => Mat4::IDENTITY,
            SimulationSpace::Local => instance.world_from_local,
        };
        if let Some(draw) = instance.views.get_mut(&view_entity) {
            if draw.frame != frame {
                continue;
            }
            // A timed entity's draw is timed while the diagnostics read back.
            match (gpu.as_ref(), instance.timed && watched.is_some()) {
                (Some(gpu), true) => draw
                    .timing
                    .get_or_insert_with(|| DrawTiming::new(gpu))
                    .begin_pass(),
                _ => draw.timing = None,
            }
            if draw.renderer.is_soft() && !draw.renderer.is_compute() {
                if let Some(depth) = prepass.and_then(|p| p.depth_only_view()) {
                    draw.renderer.set_scene_depth(depth);
                }
            }
            draw.renderer
                .set_lights(&lights_in_space(&lights, world_from_local));
            if let Some(map) = shadow_map {
                if let Err(err) = draw.renderer.set_shadow_map(map) {
                    warn_once!("{}: {err}", instance.effect.compiled().ir.name);
                }
            }
            let camera = view_camera(view, world_from_local);
            // A SceneDepth collider meets what this camera's depth prepass drew this frame, in
            // the effect's space, from the next frame's steps on (the runtime copies it).
            if instance.effect.collides_with_scene_depth() {
                match prepass.and_then(|p| p.depth.as_ref()) {
                    Some(depth) => {
                        if let Err(err) = instance.effect.set_scene_depth(
                            encoder,
                            &depth.texture.texture,
                            camera.view,
                            camera.proj,
                        ) {
                            error!("{}: {err}", instance.effect.compiled().ir.name);
                        }
                    }
                    None => warn_once!(
                        "{}: a SceneDepth collider meets the depth prepass of the camera that draws it: give the camera `DepthPrepass`",
                        instance.effect.compiled().ir.name
                    ),
                }
            }
            if draw.renderer.is_compute() {
                continue;
            }
            if let Some(timing) = &mut draw.timing {
                timing.begin_prepare(encoder);
            }
            if let Err(err) = instance
                .effect
                .prepare_draw(encoder, &draw.renderer, &camera)
            {
                error!("{}: {err}", instance.effect.compiled().ir.name);
            }
            if let Some(timing) = &mut draw.timing {
                timing.end_prepare(encoder);
            }
        }
    }
}

/// After the current camera's transparent pass: records the copy of each timed draw's stamps
/// written inside it ([`DrawTiming`]).
pub(crate) fn end_draw_timing(
    view: ViewQuery<(Entity, &ExtractedView)>,
    mut context: RenderContext,
    mut store: ResMut<PlumeInstances>,
) {
    let (view_entity, _) = view.into_inner();
    let mut timings = store
        .instances
        .values_mut()
        .filter_map(|instance| instance.views.get_mut(&view_entity)?.timing.as_mut())
        .peekable();
    if timings.peek().is_none() {
        return;
    }
    let encoder = context.command_encoder();
    for timing in timings {
        timing.end_pass(encoder);
    }
}

/// Prepares every compute-renderer draw the current camera queued this frame, between its
/// opaque and transparent passes: the compute renderer copies the depth the opaque pass drew, composites
/// the effect against it, and the transparent pass puts the image over the camera's.
pub(crate) fn composite_for_view(
    view: ViewQuery<(Entity, &ExtractedView, &ViewDepthStencilTexture)>,
    mut context: RenderContext,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
) {
    let (view_entity, view, depth) = view.into_inner();
    prepare_compute_draws(
        (view_entity, view, Some(depth)),
        &mut context,
        &mut store,
        &mut batches,
    );
}

/// Prepares every compute-renderer draw a 2D camera queued this frame, before its main pass.
/// A 2D camera's depth is a render attachment only (Bevy 0.20): nothing is copied; an
/// instance's image is put over the camera's at its entity's depth, tested against the 2D
/// depth there (`set_composite_depth`), so what the camera drew in front of the entity's z
/// hides it, as the effect sorts with the sprites by that z. A batch, whose members stand at
/// many depths, is put over the camera's image untested.
pub(crate) fn composite_for_view_2d(
    view: ViewQuery<(Entity, &ExtractedView)>,
    mut context: RenderContext,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
) {
    let (view_entity, view) = view.into_inner();
    prepare_compute_draws(
        (view_entity, view, None),
        &mut context,
        &mut store,
        &mut batches,
    );
}

/// Records the compute renderer's work for one camera's draws: each compute draw of `view`
/// made this frame, tested against `depth` (the opaque pass's, copied) where there is one.
fn prepare_compute_draws(
    (view_entity, view, depth): (Entity, &ExtractedView, Option<&ViewDepthStencilTexture>),
    context: &mut RenderContext,
    store: &mut PlumeInstances,
    batches: &mut PlumeBatches,
) {
    let frame = store.frame;
    let mut depth_view = None;
    // A batch is in world space: drawn through the camera alone.
    for batch in batches.batches_mut() {
        let Some(draw) = batch.views.get_mut(&view_entity) else {
            continue;
        };
        if draw.frame != frame || !draw.renderer.is_compute() {
            continue;
        }
        if let Some(depth) = depth {
            let depth_view = depth_view.get_or_insert_with(|| scene_depth_view(depth));
            draw.renderer.set_scene_depth(depth_view);
        }
        let camera = view_camera(view, Mat4::IDENTITY);
        let encoder = context.command_encoder();
        if let Err(err) = batch
            .batch
            .effect()
            .prepare_draw(encoder, &draw.renderer, &camera)
        {
            error!("{}: {err}", batch.batch.compiled().ir.name);
        }
    }
    for instance in store.instances.values_mut() {
        let world_from_local = match instance.space {
            SimulationSpace::World => Mat4::IDENTITY,
            SimulationSpace::Local => instance.world_from_local,
        };
        let Some(draw) = instance.views.get_mut(&view_entity) else {
            continue;
        };
        if draw.frame != frame || !draw.renderer.is_compute() {
            continue;
        }
        match depth {
            Some(depth) => {
                let depth_view = depth_view.get_or_insert_with(|| scene_depth_view(depth));
                draw.renderer.set_scene_depth(depth_view);
            }
            // A 2D camera: the image at the entity's depth.
            None => {
                let at = instance.world_from_local.w_axis;
                let clip = view.clip_from_view * view.world_from_view.to_matrix().inverse() * at;
                draw.renderer.set_composite_depth(Some(clip.z / clip.w));
            }
        }
        let camera = view_camera(view, world_from_local);
        let encoder = context.command_encoder();
        if let Some(timing) = &mut draw.timing {
            timing.begin_prepare(encoder);
        }
        if let Err(err) = instance
            .effect
            .prepare_draw(encoder, &draw.renderer, &camera)
        {
            error!("{}: {err}", instance.effect.compiled().ir.name);
        }
        if let Some(timing) = &mut draw.timing {
            timing.end_prepare(encoder);
        }
    }
}

/// The depth the camera's opaque pass drew, for the compute renderer to composite against.
fn scene_depth_view(depth: &ViewDepthStencilTexture) -> bevy::render::render_resource::TextureView {
    depth.texture().create_view(&wgpu::TextureViewDescriptor {
        label: Some("plume scene depth"),
        aspect: wgpu::TextureAspect::DepthOnly,
        ..Default::default()
    })
}

/// The scene's lights in an effect's own space (`world_from_local`: the identity for a
/// world-space effect).
fn lights_in_space(lights: &Lights, world_from_local: Mat4) -> Lights {
    if world_from_local == Mat4::IDENTITY {
        return lights.clone();
    }
    lights.transformed(plume_mat4(world_from_local.inverse()).as_dmat4())
}

/// Plume's camera for drawing an effect whose space is `world_from_local` from Bevy's view:
/// the view matrix takes the effect's own space to the camera's, and the projection is Bevy's
/// (reversed Z, an infinite far plane; Plume's soft particles read depth through it).
pub(crate) fn view_camera(view: &ExtractedView, world_from_local: Mat4) -> Camera {
    let view_from_world = view.world_from_view.to_matrix().inverse();
    let clip_from_view = view.clip_from_view;
    Camera::new(
        plume_mat4(view_from_world * world_from_local),
        plume_mat4(clip_from_view),
    )
}

/// Bevy's matrix as Plume's (the two crates may use different glam versions; the layout,
/// column-major f32, is the same).
fn plume_mat4(m: Mat4) -> plume_runtime::glam::Mat4 {
    plume_runtime::glam::Mat4::from_cols_array(&m.to_cols_array())
}
