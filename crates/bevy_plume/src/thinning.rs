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
/// nothing. Their particles alive live on, so the count follows within a lifetime.
///
/// It may also bound the GPU time of a frame's steps (`step_gpu_ms`). Thinning spawns does not
/// shorten a step (a step runs over every slot of an effect's capacity, alive or not), so this
/// part pauses steps instead: while the estimate is over the budget, effects that no camera
/// sees stop stepping, the largest capacity first, each marked [`PlumeThinning::paused`];
/// they stand still until a camera sees them or the budget allows them again. An effect in
/// view is never paused, so a budget smaller than what the seen effects take is not kept. The
/// estimate is the last measured steps' GPU time spread over the slots that stepped, a frame
/// or two old: it needs [`crate::PlumeDiagnosticsPlugin`] (which measures it) and timestamp
/// queries, and is not kept without them (said once). A batched entity saves little paused:
/// its batch steps every slot while any member steps, so it only stops spawning and its
/// particles age on. Insert it as a resource; none (the default) is no budget.
///
/// ```no_run
/// # use bevy::prelude::*;
/// App::new().insert_resource(bevy_plume::PlumeBudget::live_particles(200_000));
/// App::new().insert_resource(bevy_plume::PlumeBudget::step_gpu_ms(0.5));
/// ```
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct PlumeBudget {
    /// The most particles every effect together is expected to keep alive (None: no limit).
    pub live_particles: Option<u64>,
    /// The most GPU milliseconds a frame's steps may take (None: no limit).
    pub step_gpu_ms: Option<f32>,
}

impl PlumeBudget {
    /// At most `count` particles alive across every effect.
    pub fn live_particles(count: u64) -> Self {
        Self {
            live_particles: Some(count),
            step_gpu_ms: None,
        }
    }

    /// At most `ms` GPU milliseconds of steps a frame.
    pub fn step_gpu_ms(ms: f32) -> Self {
        Self {
            live_particles: None,
            step_gpu_ms: Some(ms),
        }
    }

    /// This budget, with at most `ms` GPU milliseconds of steps a frame too.
    pub fn with_step_gpu_ms(self, ms: f32) -> Self {
        Self {
            step_gpu_ms: Some(ms),
            ..self
        }
    }
}

/// The steps' GPU time last measured, in ms (written by `PlumeDiagnosticsPlugin`; None where
/// it is not added or the device has no timestamp queries), for [`PlumeBudget::step_gpu_ms`].
#[derive(Resource, Clone, Copy, Debug, Default)]
pub(crate) struct MeasuredSteps {
    pub gpu_ms: Option<f32>,
}

/// What [`thin_effects`] remembers between frames for the budget of GPU time.
#[derive(Default)]
pub(crate) struct StepsLedger {
    /// Slots that stepped in the last frame decided.
    stepped_slots: u64,
    /// Frames with a budget of GPU time and no measurement.
    unmeasured_frames: u32,
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
    measured: Option<Res<MeasuredSteps>>,
    mut ledger: Local<StepsLedger>,
    assets: Res<Assets<PlumeEffectAsset>>,
    cameras: Query<(&Camera, &GlobalTransform)>,
    mut effects: Query<ThinnedItem>,
) {
    let budget = budget.map(|b| *b).unwrap_or_default();
    let cameras: Vec<_> = cameras.iter().filter(|(c, _)| c.is_active).collect();
    // (entity, its own scale, pixels across, expected alive): every scale is decided before
    // any is written, so an entity's component changes only when its thinning does.
    let mut weighed = Vec::new();
    // (slots, whether it steps unpaused, whether the budget may pause it) of each.
    let mut steppers = Vec::new();
    for (entity, effect, transform, seen, aabb, lod, _) in &effects {
        let pixels = match (seen.get(), aabb) {
            (false, _) => 0.0,
            (true, None) => f32::INFINITY,
            (true, Some(aabb)) => pixels_across(&cameras, transform, aabb),
        };
        let asset = assets.get(&effect.handle);
        let expected_alive = asset.map_or(0, |a| a.graph.expected_alive());
        let own = clamp01(effect.spawn_scale) * lod.map_or(1.0, |l| l.scale(pixels));
        weighed.push((entity, own, pixels, expected_alive));
        let slots = asset.map_or(0, |a| a.graph.capacity());
        let steps = effect.steps_when(seen.get());
        steppers.push((slots, steps, steps && !seen.get()));
    }
    let shares = match budget.live_particles {
        Some(limit) => budget_shares(&weighed, limit),
        None => vec![1.0; weighed.len()],
    };
    let paused = match budget.step_gpu_ms {
        Some(limit) => {
            let measured = measured.and_then(|m| m.gpu_ms);
            pauses(&weighed, &steppers, limit, measured, &mut ledger)
        }
        None => vec![false; weighed.len()],
    };
    ledger.stepped_slots = steppers
        .iter()
        .zip(&paused)
        .filter(|((_, steps, _), paused)| *steps && !**paused)
        .map(|((slots, ..), _)| slots)
        .sum();
    // The query visits the entities in the order it did above (nothing was spawned or
    // changed archetype in between): the weights zip with them.
    let weights = weighed.into_iter().zip(shares).zip(paused);
    for (
        (entity, .., mut thinning),
        (((weighed_entity, own, pixels, expected_alive), share), paused),
    ) in effects.iter_mut().zip(weights)
    {
        debug_assert_eq!(entity, weighed_entity);
        thinning.set_if_neq(PlumeThinning {
            scale: own * share,
            pixels,
            expected_alive,
            paused,
        });
    }
}

/// Which effects the budget of `limit` GPU ms of steps pauses: none until a measurement has
/// come back; then, while the estimate (`measured` ms over the slots that stepped last frame,
/// times the slots that would step) is over `limit`, the unseen ones the budget may pause,
/// the largest capacity first (then by entity, for a stable order). `steppers`: (slots,
/// whether it steps unpaused, whether it may be paused) of each of `weighed`.
fn pauses(
    weighed: &[(Entity, f32, f32, u64)],
    steppers: &[(u64, bool, bool)],
    limit: f32,
    measured: Option<f32>,
    ledger: &mut StepsLedger,
) -> Vec<bool> {
    let mut paused = vec![false; steppers.len()];
    let Some(ms) = measured else {
        ledger.unmeasured_frames += 1;
        if ledger.unmeasured_frames == 120 {
            warn!("bevy_plume: PlumeBudget::step_gpu_ms is not kept: add PlumeDiagnosticsPlugin, which measures the steps' GPU time (and needs timestamp queries)");
        }
        return paused;
    };
    if ledger.stepped_slots == 0 {
        return paused;
    }
    let per_slot = f64::from(ms) / ledger.stepped_slots as f64;
    let mut cost: f64 = steppers
        .iter()
        .filter(|(_, steps, _)| *steps)
        .map(|(slots, ..)| *slots as f64 * per_slot)
        .sum();
    let mut order: Vec<usize> = (0..steppers.len()).filter(|&i| steppers[i].2).collect();
    order.sort_by(|&a, &b| {
        steppers[b]
            .0
            .cmp(&steppers[a].0)
            .then(weighed[a].0.cmp(&weighed[b].0))
    });
    for i in order {
        if cost <= f64::from(limit) {
            break;
        }
        paused[i] = true;
        cost -= steppers[i].0 as f64 * per_slot;
    }
    paused
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
