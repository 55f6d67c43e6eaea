//! Only what the scene requires: how much of its spawns each effect keeps this frame. An
//! effect keeps its own [`PlumeEffect::spawn_scale`], times its level of detail
//! ([`PlumeLod`]: fewer spawns the fewer pixels it covers), times its share of the game's
//! particle budget ([`PlumeBudget`]: the least visible effects thinned first). The result is
//! each entity's [`PlumeThinning`]; the render world hands its `scale` to the effect's spawn
//! schedule (`Effect::set_spawn_scale`), where the f64 reference thins the same way.

use bevy::camera::primitives::Aabb;
use bevy::prelude::*;

use crate::asset::PlumeEffectAsset;
use crate::effect::{PlumeEffect, PlumeThinning};

/// Level of detail by screen size: an effect with this component spawns fewer particles the
/// fewer pixels it covers. Its spawn scale is its size on screen (logical pixels across its
/// bounds, on the camera where it is largest) over `full_at_pixels`, at most 1 and at least
/// `least`; unseen by every camera, it keeps `least`. An effect without bounds (none
/// declared, none measured yet, a stateless one) is taken as covering the screen: never
/// thinned by its size.
///
/// ```no_run
/// # use bevy::prelude::*;
/// # use bevy_plume::{PlumeEffect, PlumeLod};
/// # fn spawn(mut commands: Commands, assets: Res<AssetServer>) {
/// // Every spawn from 200 pixels across; a quarter at 50; a tenth at most when far or unseen.
/// commands.spawn((PlumeEffect::new(assets.load("torch.plume.ron")), PlumeLod::new(200.0, 0.1)));
/// # }
/// ```
#[derive(Component, Clone, Copy, Debug, PartialEq, Reflect)]
#[reflect(Component)]
pub struct PlumeLod {
    /// Pixels across from which the effect keeps every spawn.
    pub full_at_pixels: f32,
    /// The least fraction of its spawns it keeps, however small or unseen (0 to 1).
    pub least: f32,
}

impl PlumeLod {
    /// Every spawn from `full_at_pixels` across, down to `least` of them.
    pub fn new(full_at_pixels: f32, least: f32) -> Self {
        Self {
            full_at_pixels,
            least,
        }
    }

    /// The fraction kept at `pixels` across.
    fn scale(&self, pixels: f32) -> f32 {
        let least = clamp01(self.least);
        if self.full_at_pixels.is_nan()
            || self.full_at_pixels <= 0.0
            || pixels >= self.full_at_pixels
        {
            return 1.0;
        }
        (pixels / self.full_at_pixels).clamp(least, 1.0)
    }
}

/// A budget of live particles that the plugin keeps across every effect. Each effect weighs
/// what its file keeps alive unthinned (rates times lifetimes and bursts, at most its
/// capacity: `Effect::expected_alive`) times its own spawn scale and level of detail; while
/// their sum is over the budget, the least visible effects are thinned first (unseen ones,
/// then the fewest pixels across, in that order), each as far as it takes, down to spawning
/// nothing. Their particles alive live on, so the count follows within a lifetime. Insert it
/// as a resource; none (the default) is no budget.
///
/// ```no_run
/// # use bevy::prelude::*;
/// App::new().insert_resource(bevy_plume::PlumeBudget::live_particles(200_000));
/// ```
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct PlumeBudget {
    /// The most particles every effect together is expected to keep alive (None: no limit).
    pub live_particles: Option<u64>,
}

impl PlumeBudget {
    /// At most `count` particles alive across every effect.
    pub fn live_particles(count: u64) -> Self {
        Self {
            live_particles: Some(count),
        }
    }
}

/// What [`thin_effects`] reads of each effect entity.
type ThinnedItem = (
    Entity,
    &'static PlumeEffect,
    &'static GlobalTransform,
    &'static ViewVisibility,
    Option<&'static Aabb>,
    Option<&'static PlumeLod>,
    &'static mut PlumeThinning,
);

/// Sets every effect entity's [`PlumeThinning`] from its size on screen, its level of detail
/// and the budget.
pub(crate) fn thin_effects(
    budget: Option<Res<PlumeBudget>>,
    assets: Res<Assets<PlumeEffectAsset>>,
    cameras: Query<(&Camera, &GlobalTransform)>,
    mut effects: Query<ThinnedItem>,
) {
    let cameras: Vec<_> = cameras.iter().filter(|(c, _)| c.is_active).collect();
    // (entity, its own scale, pixels across, expected alive): every scale is decided before
    // any is written, so an entity's component changes only when its thinning does.
    let mut weighed = Vec::new();
    for (entity, effect, transform, seen, aabb, lod, _) in &effects {
        let pixels = match (seen.get(), aabb) {
            (false, _) => 0.0,
            (true, None) => f32::INFINITY,
            (true, Some(aabb)) => pixels_across(&cameras, transform, aabb),
        };
        let expected_alive = assets
            .get(&effect.handle)
            .map_or(0, |a| a.graph.expected_alive());
        let own = clamp01(effect.spawn_scale) * lod.map_or(1.0, |l| l.scale(pixels));
        weighed.push((entity, own, pixels, expected_alive));
    }
    let shares = match budget.and_then(|b| b.live_particles) {
        Some(limit) => budget_shares(&weighed, limit),
        None => vec![1.0; weighed.len()],
    };
    // The query visits the entities in the order it did above (nothing was spawned or
    // changed archetype in between): the weights zip with them.
    let weights = weighed.into_iter().zip(shares);
    for ((entity, .., mut thinning), ((weighed_entity, own, pixels, expected_alive), share)) in
        effects.iter_mut().zip(weights)
    {
        debug_assert_eq!(entity, weighed_entity);
        thinning.set_if_neq(PlumeThinning {
            scale: own * share,
            pixels,
            expected_alive,
        });
    }
}

/// Each effect's share (0 to 1) of what it asks for, so that the sum of what they keep alive
/// is at most `limit`: the least visible (fewest pixels, then the entity, for a stable order)
/// cut first, each as far as it takes. `weighed`: (entity, own scale, pixels, expected alive).
fn budget_shares(weighed: &[(Entity, f32, f32, u64)], limit: u64) -> Vec<f32> {
    let asks: Vec<f64> = weighed
        .iter()
        .map(|&(_, own, _, alive)| f64::from(own) * alive as f64)
        .collect();
    let mut over = asks.iter().sum::<f64>() - limit as f64;
    let mut shares = vec![1.0; weighed.len()];
    let mut order: Vec<usize> = (0..weighed.len()).collect();
    order.sort_by(|&a, &b| {
        weighed[a]
            .2
            .total_cmp(&weighed[b].2)
            .then(weighed[a].0.cmp(&weighed[b].0))
    });
    for i in order {
        if over <= 0.0 {
            break;
        }
        if asks[i] <= 0.0 {
            continue;
        }
        let cut = asks[i].min(over);
        over -= cut;
        shares[i] = ((asks[i] - cut) / asks[i]) as f32;
    }
    shares
}

/// Logical pixels across the sphere around `aabb` (carried by `transform`) on the camera where
/// it is largest; infinite where a camera is inside it.
fn pixels_across(
    cameras: &[(&Camera, &GlobalTransform)],
    transform: &GlobalTransform,
    aabb: &Aabb,
) -> f32 {
    let center = transform.transform_point(Vec3::from(aabb.center));
    let scale = transform
        .to_scale_rotation_translation()
        .0
        .abs()
        .max_element();
    let radius = Vec3::from(aabb.half_extents).length() * scale;
    let mut most = 0.0f32;
    for (camera, at) in cameras {
        if at.translation().distance(center) <= radius {
            return f32::INFINITY;
        }
        // The sphere's centre and a point on its rim across the camera's view.
        let rim = center + at.right() * radius;
        if let (Ok(a), Ok(b)) = (
            camera.world_to_viewport(at, center),
            camera.world_to_viewport(at, rim),
        ) {
            most = most.max(2.0 * a.distance(b));
        }
    }
    most
}

/// `x` within 0 to 1, NaN as 0.
fn clamp01(x: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0)
    }
}
