//! Bevy's lights as Plume's: what lights the sprites of a lit effect (`render.lit`) in a Bevy
//! scene. Every visible `DirectionalLight` and `PointLight` and the ambient light are copied
//! each frame, in Plume's units: Bevy's light reaches the screen as colour × illuminance (lux)
//! × the camera's exposure through a Lambertian surface's 1/π, a point light's lumens spread
//! over 4π steradians, ambient light as colour × brightness × exposure. So a grey puff and a
//! grey wall under the same sun come out the same grey. At most `LIGHTS_MOST` sources are
//! kept: the directional lights first, then the point lights, brightest first.

use bevy::camera::Exposure;
use bevy::prelude::*;
use bevy::render::Extract;
use plume_runtime::glam::DVec3;
use plume_runtime::{LightSource, Lights};

/// The lights of the main world this frame, in world space and Plume's units.
#[derive(Resource, Clone, Debug, Default)]
pub(crate) struct ExtractedLights(pub Lights);

/// Copies the scene's visible lights and ambient light into [`ExtractedLights`], at the
/// exposure of the first camera that has an `Exposure` (Bevy's default otherwise).
pub(crate) fn extract_lights(
    mut extracted: ResMut<ExtractedLights>,
    directional: Extract<Query<(&DirectionalLight, &GlobalTransform, &InheritedVisibility)>>,
    points: Extract<Query<(&PointLight, &GlobalTransform, &InheritedVisibility)>>,
    ambient: Extract<Option<Res<GlobalAmbientLight>>>,
    exposures: Extract<Query<&Exposure, With<Camera>>>,
) {
    let exposure = f64::from(
        exposures
            .iter()
            .next()
            .copied()
            .unwrap_or_default()
            .exposure(),
    );
    let linear = |c: Color| {
        let c = c.to_linear();
        DVec3::new(f64::from(c.red), f64::from(c.green), f64::from(c.blue))
    };
    let mut sources: Vec<(f64, LightSource)> = Vec::new();
    for (light, transform, visible) in &directional {
        if !visible.get() {
            continue;
        }
        let forward = transform.forward();
        let color =
            linear(light.color) * f64::from(light.illuminance) * exposure / std::f64::consts::PI;
        let direction = DVec3::new(
            f64::from(forward.x),
            f64::from(forward.y),
            f64::from(forward.z),
        );
        // Directional lights before any point light.
        sources.push((f64::INFINITY, LightSource::Directional { direction, color }));
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
    let ambient = ambient.as_ref().map_or(DVec3::ZERO, |a| {
        linear(a.color) * f64::from(a.brightness) * exposure
    });
    extracted.0 = Lights {
        ambient,
        sources: sources.into_iter().map(|(_, s)| s).collect(),
    };
}
