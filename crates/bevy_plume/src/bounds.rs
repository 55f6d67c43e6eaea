//! An effect entity's `Aabb`, so that Bevy's frustum culling skips drawing an effect out of
//! view (it keeps simulating): the box its file declares (`bounds`), or else the box of its
//! live particles measured on the GPU. The render world records that measurement each frame
//! after the steps (`Effect::watch_live_bounds`, read back without waiting) and puts each
//! reading into [`MeasuredBounds`], a map both worlds hold; the main world turns it into the
//! entity's `Aabb` here.

use bevy::camera::primitives::Aabb;
use bevy::prelude::*;

use crate::asset::PlumeEffectAsset;
use crate::effect::PlumeEffect;

/// One effect's latest measured box, in its simulation space (the world for a world-space
/// effect, the entity's own space for a local one); None when no particle was alive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MeasuredBox {
    pub corners: Option<(Vec3, Vec3)>,
    /// Whether the box is in world coordinates (a world-space effect).
    pub in_world: bool,
}

/// The latest measured box of every running effect without declared bounds, by main-world
/// entity: written by the render world, read by the main world.
pub(crate) type MeasuredBounds = crate::shared::EntityShared<MeasuredBox>;

/// Marks an [`Aabb`] that the plugin gave an effect entity from its file's `bounds`: kept in
/// step with the file (a hot reload may change or remove them). An `Aabb` the game inserted
/// itself is never touched.
#[derive(Component)]
pub(crate) struct BoundsFromFile;

/// Gives each effect entity its file's `bounds` as an [`Aabb`], so that Bevy's frustum
/// culling skips drawing an effect whose box is out of view (it keeps simulating).
pub(crate) fn bounds_from_files(
    mut commands: Commands,
    effects: Query<(Entity, &PlumeEffect, Option<&Aabb>, Has<BoundsFromFile>)>,
    assets: Res<Assets<PlumeEffectAsset>>,
) {
    for (entity, effect, aabb, ours) in &effects {
        if aabb.is_some() && !ours {
            continue;
        }
        let Some(asset) = assets.get(&effect.handle) else {
            continue;
        };
        let declared = asset.graph.groups[0].effect.ir.bounds.map(|(min, max)| {
            Aabb::from_min_max(
                min.as_vec3().to_array().into(),
                max.as_vec3().to_array().into(),
            )
        });
        match (declared, aabb) {
            (Some(want), Some(have)) if *have == want => {}
            (Some(want), _) => {
                commands.entity(entity).insert((want, BoundsFromFile));
            }
            (None, Some(_)) => {
                commands.entity(entity).remove::<(Aabb, BoundsFromFile)>();
            }
            (None, None) => {}
        }
    }
}

/// Marks an [`Aabb`] that the plugin gave an effect entity from the box of its live particles
/// measured on the GPU (a file without `bounds`): kept in step with each new reading.
#[derive(Component)]
pub(crate) struct BoundsMeasured;

/// How far past its particles' centres an effect's sprites reach (m): its largest size (a
/// sprite's width, height or velocity streak, whichever is longest, turned any way).
fn sprite_reach(asset: &PlumeEffectAsset) -> f32 {
    let mut reach = 0.0f64;
    for group in &asset.graph.groups {
        let render = &group.effect.ir.render;
        let sizes = render.size.iter().chain(render.size_y.iter().flatten());
        for &(_, size) in sizes {
            reach = reach.max(size);
        }
        if let crate::plume_compiler::orient::OrientIr::Velocity { max_length, .. } = render.orient
        {
            reach = reach.max(max_length);
        }
    }
    reach as f32
}

/// What [`bounds_from_gpu`] reads of an effect entity: its effect, transform and `Aabb`, and
/// whose the `Aabb` is (measured, or the file's).
type MeasuredItem = (
    Entity,
    &'static PlumeEffect,
    &'static GlobalTransform,
    Option<&'static Aabb>,
    Has<BoundsMeasured>,
    Has<BoundsFromFile>,
);

/// Gives each effect entity whose file declares no `bounds` the box of its live particles as
/// measured on the GPU ([`MeasuredBounds`]), as an [`Aabb`] in the entity's space: its
/// sprites' reach added, and a tenth of the box on every side for the frames the reading lags
/// behind. A world-space effect's box, measured in the world, is carried into the entity's
/// space. An effect with ribbons (`render.trail`, whose points trail the particles) or a
/// stateless one gets none and is always drawn; an `Aabb` the game inserted itself is left
/// alone.
pub(crate) fn bounds_from_gpu(
    mut commands: Commands,
    effects: Query<MeasuredItem>,
    assets: Res<Assets<PlumeEffectAsset>>,
    measured: Res<MeasuredBounds>,
) {
    let boxes = measured.lock();
    for (entity, effect, transform, aabb, ours, from_file) in &effects {
        if from_file || (aabb.is_some() && !ours) {
            continue;
        }
        let Some(asset) = assets.get(&effect.handle) else {
            continue;
        };
        let trails = asset
            .graph
            .groups
            .iter()
            .any(|g| g.effect.ir.render.trail.is_some());
        let Some(reading) = boxes.get(&entity).filter(|_| !trails) else {
            if ours {
                commands.entity(entity).remove::<(Aabb, BoundsMeasured)>();
            }
            continue;
        };
        let want = match reading.corners {
            // Nothing alive: nothing to draw.
            None => Aabb::from_min_max(Vec3::ZERO, Vec3::ZERO),
            Some((min, max)) => {
                let (min, max) = match reading.in_world {
                    true => local_box(transform.to_matrix().inverse(), min, max),
                    false => (min, max),
                };
                let pad = Vec3::splat(sprite_reach(asset)) + 0.1 * (max - min);
                Aabb::from_min_max(min - pad, max + pad)
            }
        };
        if aabb != Some(&want) {
            commands.entity(entity).insert((want, BoundsMeasured));
        }
    }
}

/// The box in another space (through `m`) that holds the box from `min` to `max`: the box of
/// its eight corners carried through.
fn local_box(m: Mat4, min: Vec3, max: Vec3) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for k in 0..8 {
        let corner = Vec3::new(
            if k & 1 == 0 { min.x } else { max.x },
            if k & 2 == 0 { min.y } else { max.y },
            if k & 4 == 0 { min.z } else { max.z },
        );
        let p = m.transform_point3(corner);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}
