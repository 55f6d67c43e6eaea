//! Drawing instances in Bevy's transparent phases: each camera that sees an effect gets one
//! phase item for it, sorted with the rest of the transparent phase (by the effect's distance
//! in 3D, by its z in 2D; the particles within it in Plume's own order, back to front when the
//! file says `sort`), and drawn with Plume's pipelines straight into Bevy's render pass.

use bevy::core_pipeline::core_2d::{Transparent2d, CORE_2D_DEPTH_FORMAT};
use bevy::core_pipeline::core_3d::{Transparent3d, TransparentSortingInfo3d, CORE_3D_DEPTH_FORMAT};
use bevy::math::FloatOrd;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_phase::{
    Draw, DrawError, DrawFunctions, PhaseItemExtraIndex, TrackedRenderPass, ViewSortedRenderPhases,
};
use bevy::render::render_resource::CachedRenderPipelineId;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{ExtractedView, RenderVisibleEntities};
use plume_runtime::DrawTarget;

use crate::effect::{PlumeEffect, AUTO_COMPUTE_CAPACITY};
use crate::render::batches::{BatchView, PlumeBatches};
use crate::render::instances::{PlumeInstances, PlumeRenderStats};
use crate::render::renderer_choice::{draws_by_compute, renderer_or_raster};

/// The target a camera's transparent pass draws into: its colour format and samples, Bevy's
/// reversed-Z depth buffer tested (nearer is greater) and never written. Soft particles fade
/// against the depth prepass, which they can read only single-sampled: with MSAA they are
/// drawn hard.
pub(crate) fn view_target(view: &ExtractedView, msaa: &Msaa, depth_prepass: bool) -> DrawTarget {
    let samples = msaa.samples();
    DrawTarget::new(view.target_format)
        .with_depth_compare(CORE_3D_DEPTH_FORMAT, wgpu::CompareFunction::GreaterEqual)
        .with_samples(samples)
        .with_soft(samples == 1 && depth_prepass)
}

/// The size of the compute renderer's image for a camera: its target's, when its viewport is
/// the whole target (the compute renderer's image maps the projection onto the whole depth texture it
/// reads); None otherwise.
fn compute_size(view: &ExtractedView, camera: Option<&ExtractedCamera>) -> Option<(u32, u32)> {
    let size = camera?.physical_target_size?;
    let whole = view.viewport == UVec4::new(0, 0, size.x, size.y);
    whole.then_some((size.x, size.y))
}

/// What the queue systems read of each camera: its entity, view, camera, MSAA, the entities
/// it sees and whether it has a depth prepass.
type ViewItem = (
    Entity,
    &'static ExtractedView,
    Option<&'static ExtractedCamera>,
    &'static Msaa,
    &'static RenderVisibleEntities,
    Has<bevy::core_pipeline::prepass::DepthPrepass>,
);

/// What the queue systems share: the instances, the batches, the statistics and the adapter.
type Shared<'a> = (
    &'a mut PlumeInstances,
    &'a mut PlumeBatches,
    &'a mut PlumeRenderStats,
    bool,
);

/// Queues one transparent item per visible effect per 3D camera (`Camera3d`), sorted by its
/// centre's distance, making each camera's draw of it first where there is none yet.
#[allow(clippy::too_many_arguments)]
pub(crate) fn queue_effects(
    draw_functions: Res<DrawFunctions<Transparent3d>>,
    mut phases: ResMut<ViewSortedRenderPhases<Transparent3d>>,
    views: Query<ViewItem>,
    adapter: Res<RenderAdapterInfo>,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
    mut stats: ResMut<PlumeRenderStats>,
) {
    stats.instances += batches.members.len();
    stats.batches = batches.count();
    stats.particle_bytes += batches.particle_bytes();
    // A CPU adapter rasterises faster than it splats (as `plume render --draw auto` finds).
    let gpu_adapter = adapter.device_type != wgpu::DeviceType::Cpu;
    let Some(draw_function) = draw_functions.read().get_id::<DrawPlume>() else {
        return;
    };
    let mut shared = (&mut *store, &mut *batches, &mut *stats, gpu_adapter);
    for (view_entity, view, camera, msaa, visible, depth_prepass) in &views {
        let Some(phase) = phases.get_mut(&view.retained_view_entity) else {
            continue;
        };
        let target = view_target(view, msaa, depth_prepass);
        let size = compute_size(view, camera);
        queue_view(
            &mut shared,
            (view_entity, target, Some(size)),
            visible,
            &mut |entity, center| {
                phase.add_transient(Transparent3d {
                    sorting_info: TransparentSortingInfo3d::Sorted {
                        mesh_center: center,
                        depth_bias: 0.0,
                    },
                    distance: 0.0,
                    pipeline: CachedRenderPipelineId::INVALID,
                    entity,
                    draw_function,
                    batch_range: 0..1,
                    extra_index: PhaseItemExtraIndex::None,
                    indexed: false,
                });
            },
        );
    }
}

/// Queues one item per visible effect per 2D camera (`Camera2d`) into Bevy's transparent 2D
/// phase, sorted with the sprites by its entity's z (larger in front): drawn by the raster
/// renderer, tested against the 2D depth buffer as sprites are, or where the effect asks for
/// it (`PlumeDraw::Compute`; `Auto` keeps the raster one in 2D) by the compute renderer,
/// which cannot read a 2D camera's depth: its image is tested at the entity's depth.
pub(crate) fn queue_effects_2d(
    draw_functions: Option<Res<DrawFunctions<Transparent2d>>>,
    phases: Option<ResMut<ViewSortedRenderPhases<Transparent2d>>>,
    views: Query<ViewItem>,
    mut store: ResMut<PlumeInstances>,
    mut batches: ResMut<PlumeBatches>,
    mut stats: ResMut<PlumeRenderStats>,
) {
    let (Some(draw_functions), Some(mut phases)) = (draw_functions, phases) else {
        return;
    };
    let Some(draw_function) = draw_functions.read().get_id::<DrawPlume>() else {
        return;
    };
    let mut shared = (&mut *store, &mut *batches, &mut *stats, false);
    for (view_entity, view, camera, msaa, visible, _) in &views {
        let Some(phase) = phases.get_mut(&view.retained_view_entity) else {
            continue;
        };
        let target = DrawTarget::new(view.target_format)
            .with_depth_compare(CORE_2D_DEPTH_FORMAT, wgpu::CompareFunction::GreaterEqual)
            .with_samples(msaa.samples())
            .with_soft(false);
        queue_view(
            &mut shared,
            (view_entity, target, Some(compute_size(view, camera))),
            visible,
            &mut |entity, center| {
                phase.add_transient(Transparent2d {
                    sort_key: FloatOrd(center.z),
                    entity,
                    pipeline: CachedRenderPipelineId::INVALID,
                    draw_function,
                    batch_range: 0..1,
                    extracted_index: usize::MAX,
                    extra_index: PhaseItemExtraIndex::None,
                    indexed: false,
                });
            },
        );
    }
}

/// Makes (or keeps) each visible effect's draw for one camera `(view, target, compute)` and
/// hands `add` each to queue, with its centre: the camera's compute image size in `compute`
/// (`Some(None)`: a viewport the compute renderer cannot fill), None where the camera draws
/// with the raster renderer alone.
fn queue_view(
    (store, batches, stats, gpu_adapter): &mut Shared<'_>,
    (view_entity, target, compute_image): (Entity, DrawTarget, Option<Option<(u32, u32)>>),
    visible: &RenderVisibleEntities,
    add: &mut dyn FnMut((Entity, MainEntity), Vec3),
) {
    let Some(visible) = visible.get::<PlumeEffect>() else {
        return;
    };
    let frame = store.frame;
    // The batches this camera sees an entity of, each with the first such entity.
    let mut seen_batches = bevy::platform::collections::HashMap::new();
    for &(render_entity, main_entity) in &visible.entities_cpu_culling {
        let Some(instance) = store.instances.get_mut(&main_entity.id()) else {
            if let Some(id) = batches.batch_id(main_entity.id()) {
                seen_batches
                    .entry(id)
                    .or_insert((render_entity, main_entity));
            }
            continue;
        };
        let large = instance.capacity >= AUTO_COMPUTE_CAPACITY;
        let compute = draws_by_compute(instance.draw, *gpu_adapter, large, || {
            instance.compute_draws()
        });
        let (target, size) = compute_target(target, compute_image.filter(|_| compute));
        if instance
            .view_draw(view_entity, target, size, frame)
            .is_none()
        {
            continue;
        }
        stats.draws += 1;
        if instance
            .views
            .get(&view_entity)
            .is_some_and(|d| d.renderer.is_compute())
        {
            stats.compute_draws += 1;
        }
        add(
            (render_entity, main_entity),
            instance.world_from_local.w_axis.truncate(),
        );
    }
    for (id, entity) in seen_batches {
        let Some(batch) = batches.batch_mut(id) else {
            continue;
        };
        // A batch's `Auto` is the compute renderer's only when its effect is large.
        let compute = !batch.compute_refused
            && draws_by_compute(batch.draw, *gpu_adapter, true, || {
                let ir = &batch.batch.compiled().ir;
                plume_runtime::outputs::ComputeOffscreen::why_not(&[ir]).is_none()
            });
        let (target, size) = compute_target(target, compute_image.filter(|_| compute));
        if !batch
            .views
            .get(&view_entity)
            .is_some_and(|v| v.target == target && v.size == size)
        {
            let effect = batch.batch.effect();
            match renderer_or_raster(effect, &target, size, &mut batch.compute_refused) {
                (size, Ok(renderer)) => {
                    let view = BatchView {
                        target,
                        size,
                        renderer,
                        frame,
                    };
                    batch.views.insert(view_entity, view);
                }
                (_, Err(err)) => {
                    let name = &effect.compiled().ir.name;
                    warn_once!("{name}: a batch cannot be drawn: {err}");
                    continue;
                }
            }
        }
        let Some(view) = batch.views.get_mut(&view_entity) else {
            continue;
        };
        view.frame = frame;
        stats.draws += 1;
        if view.renderer.is_compute() {
            stats.compute_draws += 1;
        }
        let center = batches
            .members
            .get(&entity.1.id())
            .map_or(Vec3::ZERO, |m| m.world_from_local().w_axis.truncate());
        add(entity, center);
    }
}

/// The target and compute image size an effect is drawn with: the compute renderer's where
/// `compute` gives its image size (it reads the main pass's depth, sample 0 of a multisampled
/// one, so soft particles fade with MSAA too), else the raster renderer's.
fn compute_target(
    target: DrawTarget,
    compute: Option<Option<(u32, u32)>>,
) -> (DrawTarget, Option<(u32, u32)>) {
    match compute {
        Some(Some(size)) => (target.with_soft(true), Some(size)),
        Some(None) => {
            warn_once!("bevy_plume: a camera whose viewport is not its whole target draws effects with the raster renderer");
            (target, None)
        }
        None => (target, None),
    }
}

/// Drops the draws of cameras that no longer see an effect (or are gone): run once a frame,
/// after every camera of every phase has queued.
pub(crate) fn retire_unseen(mut store: ResMut<PlumeInstances>, mut batches: ResMut<PlumeBatches>) {
    let frame = store.frame;
    for instance in store.instances.values_mut() {
        instance.views.retain(|_, draw| draw.frame == frame);
    }
    for batch in batches.batches_mut() {
        batch.views.retain(|_, view| view.frame == frame);
    }
}

/// Records an effect's draw for one camera into Bevy's transparent pass, with Plume's own
/// pipelines and bind groups on the pass's raw wgpu encoder.
pub(crate) struct DrawPlume;

impl Draw<Transparent3d> for DrawPlume {
    fn draw<'w>(
        &mut self,
        world: &'w World,
        pass: &mut TrackedRenderPass<'w>,
        view: Entity,
        item: &Transparent3d,
    ) -> Result<(), DrawError> {
        draw_entity(world, pass, view, item.entity.1.id());
        Ok(())
    }
}

impl Draw<Transparent2d> for DrawPlume {
    fn draw<'w>(
        &mut self,
        world: &'w World,
        pass: &mut TrackedRenderPass<'w>,
        view: Entity,
        item: &Transparent2d,
    ) -> Result<(), DrawError> {
        draw_entity(world, pass, view, item.entity.1.id());
        Ok(())
    }
}

/// Records `entity`'s draw for `view` (its own, or its batch's) into `pass`.
fn draw_entity<'w>(
    world: &'w World,
    pass: &mut TrackedRenderPass<'w>,
    view: Entity,
    entity: Entity,
) {
    let store = world.resource::<PlumeInstances>();
    let draw = store
        .instances
        .get(&entity)
        .and_then(|instance| instance.views.get(&view));
    if let Some(draw) = draw {
        // A timed draw is stamped before and after, inside the pass (`DrawTiming`).
        let timer = draw.timing.as_ref().and_then(|t| t.pass.as_ref());
        if let Some(timer) = timer {
            timer.stamp_in_pass(pass.wgpu_pass(), false);
        }
        draw.renderer.draw(pass.wgpu_pass());
        if let Some(timer) = timer {
            timer.stamp_in_pass(pass.wgpu_pass(), true);
        }
    } else if let Some(batch) = world.resource::<PlumeBatches>().batch_of(entity) {
        if let Some(batch_view) = batch.views.get(&view) {
            batch_view.renderer.draw(pass.wgpu_pass());
        }
    }
}
