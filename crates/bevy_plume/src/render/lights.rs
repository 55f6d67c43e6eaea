//! Bevy's lights as Plume's: what lights the sprites of a lit effect (`render.lit`) in a Bevy
//! scene. Every visible `DirectionalLight` and `PointLight` and the ambient light are copied
//! each frame, in Plume's units: Bevy's light reaches the screen as colour × illuminance (lux)
//! × the camera's exposure through a Lambertian surface's 1/π, a point light's lumens spread
//! over 4π steradians, ambient light as colour × brightness × exposure. So a grey puff and a
//! grey wall under the same sun come out the same grey. At most `LIGHTS_MOST` sources are
//! kept: the directional lights first, then the point lights, brightest first. Each camera
//! sees them at its own `Exposure`, with its own `AmbientLight` where it has one (as Bevy
//! lights its meshes), else the `GlobalAmbientLight`. The first directional light that casts
//! shadows (`shadow_maps_enabled`; a `VolumetricLight` one first, as Bevy orders them) is
//! kept first, with each camera's cascades: its shadow map is then the camera's
//! `ViewShadowBindings` directional texture, whose first layers are that light's cascades
//! (reversed depth, as Bevy draws them).

use bevy::camera::Exposure;
use bevy::light::{Cascades, VolumetricLight};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::sync_world::RenderEntity;
use bevy::render::Extract;
use plume_runtime::glam::{DMat4, DVec3};
use plume_runtime::{LightSource, Lights, Shadow};

/// The lights of the main world this frame, in world space and Plume's units before a
/// camera's exposure, and what each camera sees them through.
#[derive(Resource, Clone, Debug, Default)]
pub(crate) struct ExtractedLights {
    /// The sources, at an exposure of 1, and the global ambient light.
    scene: Lights,
    /// Per camera (its render-world entity): its exposure and its own ambient light.
    views: HashMap<Entity, (f64, Option<DVec3>)>,
    /// Per camera (its render-world entity): the cascades of the light that casts shadows
    /// (source 0), each one's projection from world space.
    cascades: HashMap<Entity, Vec<DMat4>>,
}

impl ExtractedLights {
    /// The lights as the camera `view` (a render-world entity) sees them: at its exposure
    /// (Bevy's default for a camera not extracted), with its own ambient light if it has one.
    pub(crate) fn for_view(&self, view: Entity) -> Lights {
        let default_exposure = f64::from(Exposure::default().exposure());
        let (exposure, own) = self
            .views
            .get(&view)
            .copied()
            .unwrap_or((default_exposure, None));
        let scaled = |c: DVec3| c * exposure;
        Lights {
            ambient: scaled(own.unwrap_or(self.scene.ambient)),
            sources: self
                .scene
                .sources
                .iter()
                .map(|s| match *s {
                    LightSource::Directional { direction, color } => LightSource::Directional {
                        direction,
                        color: scaled(color),
                    },
                    LightSource::Point {
                        position,
                        color,
                        range,
                    } => LightSource::Point {
                        position,
                        color: scaled(color),
                        range,
                    },
                })
                .collect(),
            shadow: self.cascades.get(&view).map(|cascades| Shadow {
                cascades: cascades.clone(),
                reversed: true,
                ..Shadow::of_source(0)
            }),
        }
    }
}

/// What a camera's lighting is made of: its entity, its render-world twin, exposure and own
/// ambient light.
type CameraLighting = (
    Entity,
    RenderEntity,
    Option<&'static Exposure>,
    Option<&'static AmbientLight>,
);

/// What a directional light's lighting is made of: its entity, the light, its place, whether
/// it is seen, its shadow cascades per camera and whether it is volumetric.
type DirectionalLighting = (
    Entity,
    &'static DirectionalLight,
    &'static GlobalTransform,
    &'static InheritedVisibility,
    Option<&'static Cascades>,
    Has<VolumetricLight>,
);

/// Copies the scene's visible lights and ambient light into [`ExtractedLights`], each
/// camera's exposure and own ambient light, and the shadow cascades of the light that casts
/// shadows.
pub(crate) fn extract_lights(
    mut extracted: ResMut<ExtractedLights>,
    directional: Extract<Query<DirectionalLighting>>,
    points: Extract<Query<(&PointLight, &GlobalTransform, &InheritedVisibility)>>,
    ambient: Extract<Option<Res<GlobalAmbientLight>>>,
    cameras: Extract<Query<CameraLighting, With<Camera>>>,
) {
    // Scaled by each camera's exposure when drawn (`for_view`).
    let exposure = 1.0;
    let linear = |c: Color| {
        let c = c.to_linear();
        DVec3::new(f64::from(c.red), f64::from(c.green), f64::from(c.blue))
    };
    let mut sources: Vec<(f64, LightSource)> = Vec::new();
    // Bevy's first shadow map: a volumetric shadow-casting light's, else the first
    // shadow-casting light's.
    let casting = directional
        .iter()
        .filter(|(_, light, _, visible, cascades, _)| {
            light.shadow_maps_enabled && visible.get() && cascades.is_some()
        })
        .min_by_key(|(.., volumetric)| !*volumetric);
    let caster = casting.map(|(entity, ..)| entity);
    extracted.cascades.clear();
    for (entity, light, transform, visible, cascades, _) in &directional {
        if !visible.get() {
            continue;
        }
        let casts = caster == Some(entity);
        if let (true, Some(cascades)) = (casts, cascades) {
            for (camera, render_camera, ..) in &cameras {
                if let Some(list) = cascades.cascades.get(&camera) {
                    let matrices = list
                        .iter()
                        .take(plume_compiler::shadow::SHADOW_CASCADES_MOST)
                        .map(|c| {
                            DMat4::from_cols_array(
                                &c.clip_from_world.to_cols_array().map(f64::from),
                            )
                        })
                        .collect();
                    extracted.cascades.insert(render_camera, matrices);
                }
            }
        }
        let forward = transform.forward();
        let color =
            linear(light.color) * f64::from(light.illuminance) * exposure / std::f64::consts::PI;
        let direction = DVec3::new(
            f64::from(forward.x),
            f64::from(forward.y),
            f64::from(forward.z),
        );
        // Directional lights before any point light, the one that casts shadows first.
        let first = match casts {
            true => f64::INFINITY,
            false => f64::MAX,
        };
        sources.push((first, LightSource::Directional { direction, color }));
    }
    for (light, transform, visible) in &points {
        if !visible.get() {
            continue;
        }
        let at = transform.translation();
        let color = linear(light.color) * f64::from(light.intensity) / (4.0 * std::f64::consts::PI)
            * exposure
            / std::f64::consts::PI;
        sources.push((
            color.max_element(),
            LightSource::Point {
                position: DVec3::new(f64::from(at.x), f64::from(at.y), f64::from(at.z)),
                color,
                range: f64::from(light.range.max(1e-3)),
            },
        ));
    }
    sources.sort_by(|a, b| b.0.total_cmp(&a.0));
    sources.truncate(plume_compiler::lights::LIGHTS_MOST);
    let ambient = ambient
        .as_ref()
        .map_or(DVec3::ZERO, |a| linear(a.color) * f64::from(a.brightness));
    extracted.scene = Lights {
        ambient,
        sources: sources.into_iter().map(|(_, s)| s).collect(),
        shadow: None,
    };
    extracted.views = cameras
        .iter()
        .map(|(_, view, exposure, own)| {
            let exposure = f64::from(exposure.copied().unwrap_or_default().exposure());
            let own = own.map(|a| linear(a.color) * f64::from(a.brightness));
            (view, (exposure, own))
        })
        .collect();
}
