//! Light from particles in a Bevy scene (`render.light`): the lights an effect's brightest
//! particles give off become Bevy `PointLight`s, which Bevy's clustered lighting uses on every
//! mesh (sparks lighting the ground). The render world picks them after each frame's steps
//! (`ParticleLights::watch`, read back without waiting) and puts each reading, in world space,
//! into [`GivenLights`], a map both worlds hold; the main world keeps one `PointLight` entity
//! per light here, each marked [`PlumeLightOf`] its effect, and removes them with it.

use bevy::camera::Exposure;
use bevy::ecs::entity::EntityHashMap;
use bevy::prelude::*;
use plume_runtime::LightSource;

/// The latest lights each effect's particles give off, world space, by main-world entity:
/// written by the render world, read by the main world.
pub(crate) type GivenLights = crate::shared::EntityShared<Vec<LightSource>>;

/// A `PointLight` the plugin keeps for a light that the particles of effect entity `.0` give
/// off (`render.light`): moved, coloured and removed by the plugin.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Reflect)]
#[reflect(Component)]
pub struct PlumeLightOf(pub Entity);

/// Keeps one `PointLight` per light each effect's particles give off: moved to the light,
/// coloured as it, in Bevy's units at the first camera's exposure (the inverse of what
/// `render::lights` does to Bevy's lights: Plume's light 1 m away is colour × lumens / 4π ×
/// exposure / π); extra ones removed, and all of an effect's once it is gone.
pub(crate) fn given_lights_to_point_lights(
    mut commands: Commands,
    given: Res<GivenLights>,
    mut lights: Query<(Entity, &PlumeLightOf, &mut Transform, &mut PointLight)>,
    exposures: Query<&Exposure, With<Camera>>,
) {
    let exposure = exposures
        .iter()
        .next()
        .copied()
        .unwrap_or_default()
        .exposure();
    let given = given.lock();
    let mut kept: EntityHashMap<Vec<Entity>> = EntityHashMap::default();
    for (entity, of, ..) in &lights {
        kept.entry(of.0).or_default().push(entity);
    }
    for (effect, held) in &kept {
        let wanted = given.get(effect).map_or(0, Vec::len);
        for &extra in held.iter().skip(wanted) {
            commands.entity(extra).despawn();
        }
    }
    for (effect, sources) in given.iter() {
        let held = kept.get(effect).map_or(&[][..], Vec::as_slice);
        for (k, source) in sources.iter().enumerate() {
            let LightSource::Point {
                position,
                color,
                range,
            } = *source
            else {
                continue;
            };
            let brightest = color.max_element().max(1e-9);
            let light = PointLight {
                color: Color::linear_rgb(
                    (color.x / brightest) as f32,
                    (color.y / brightest) as f32,
                    (color.z / brightest) as f32,
                ),
                intensity: (brightest * 4.0 * std::f64::consts::PI * std::f64::consts::PI
                    / f64::from(exposure)) as f32,
                range: range as f32,
                ..default()
            };
            let at = Transform::from_xyz(position.x as f32, position.y as f32, position.z as f32);
            match held.get(k).and_then(|&e| lights.get_mut(e).ok()) {
                Some((_, _, mut transform, mut point)) => {
                    *transform = at;
                    *point = light;
                }
                None => {
                    commands.spawn((PlumeLightOf(*effect), light, at));
                }
            }
        }
    }
}
