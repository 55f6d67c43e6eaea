//! Lit particles (`render.lit`) in a Bevy scene, on llvmpipe (lavapipe): Bevy's own
//! `DirectionalLight`, `PointLight` and ambient light (global, or a camera's own) light the
//! sprites and trails, not the effect file's lights; turning the light turns the lit side,
//! and a scene with no light leaves them dark as it leaves a lit mesh.

use crate::common::{project, serial, Harness, HEIGHT, WIDTH};
use bevy::prelude::*;
use bevy_plume::PlumeEffect;

/// One opaque grey puff 4 m across at the origin, shaded as a half sphere. Its file names a
/// bright white light from straight ahead, which a Bevy scene must not use.
const PUFF: &str = r#"Effect(name: "puff", capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    lights: [Directional(direction: (0.0, 0.0, -1.0), intensity: 3.0), Ambient(intensity: 1.0)],
    render: Render(color: [(0.0, (0.6, 0.6, 0.6, 1.0))], size: [(0.0, 4.0)],
                   lit: Some(Lit(normals: Sphere))))
"#;

/// The mean brightness (0 to 255, over the three channels) of `pixels` of `image` (clamped
/// to it).
fn mean_brightness(image: &image::RgbaImage, pixels: impl Iterator<Item = (u32, u32)>) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for (x, y) in pixels {
        let p = image.get_pixel(x.min(WIDTH - 1), y.min(HEIGHT - 1)).0;
        sum += (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0;
        n += 1.0;
    }
    sum / n
}

/// The mean brightness of the puff's left and right thirds along its horizontal middle row.
fn sides(image: &image::RgbaImage) -> (f64, f64) {
    let (cx, cy) = project(0.0, 0.0);
    let (edge, _) = project(2.0, 0.0);
    let radius = edge - cx;
    let row = |from: f32, to: f32| {
        let xs = (cx + from * radius) as u32..(cx + to * radius) as u32;
        mean_brightness(image, xs.map(|x| (x, cy as u32)))
    };
    (row(-0.9, -0.35), row(0.35, 0.9))
}

/// A sun of 8,000 lux at `from`, shining toward the origin.
fn spawn_sun(h: &mut Harness, from: Vec3) -> Entity {
    let sun = DirectionalLight {
        illuminance: 8_000.0,
        ..default()
    };
    let at = Transform::from_translation(from).looking_at(Vec3::ZERO, Vec3::Y);
    h.app.world_mut().spawn((sun, at)).id()
}

#[test]
fn bevys_lights_light_the_particles() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("lights", PUFF);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    // The sun from the right (+x), travelling toward -x.
    let sun = spawn_sun(&mut h, Vec3::new(5.0, 0.0, 0.0));
    h.update(10);
    let (left, right) = sides(&h.capture_running());
    assert!(
        right > 60.0 && left < 10.0,
        "lit from the right: left third {left:.1}, right third {right:.1}"
    );
    // The sun moved to the left: the other side lights up.
    *h.app.world_mut().get_mut::<Transform>(sun).unwrap() =
        Transform::from_xyz(-5.0, 0.0, 0.0).looking_at(Vec3::ZERO, Vec3::Y);
    h.update(2);
    let (left, right) = sides(&h.capture_running());
    assert!(
        left > 60.0 && right < 10.0,
        "lit from the left: left third {left:.1}, right third {right:.1}"
    );
    // No light at all: dark, as a lit mesh would be (the file's own lights are not used).
    h.app.world_mut().despawn(sun);
    h.update(2);
    let image = h.capture();
    let brightest = image
        .pixels()
        .map(|p| *p.0[..3].iter().max().unwrap())
        .max();
    assert_eq!(brightest, Some(0), "unlit scene, yet the puff shows");
}

#[test]
fn a_cameras_own_ambient_light_lights_the_particles_it_draws() {
    // No sun and no global ambient light: dark. The camera's own AmbientLight (Bevy 0.20's
    // per-camera override) lights the puff, both sides alike (within a tenth: the sides
    // sampled are a pixel or so apart), and more of it, more light.
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("camera-ambient", PUFF);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    let camera = h.camera();
    let mut brightness = Vec::new();
    for ambient in [0.0, 300.0, 900.0] {
        h.app.world_mut().entity_mut(camera).insert(AmbientLight {
            color: Color::WHITE,
            brightness: ambient,
            ..default()
        });
        h.update(3);
        let (left, right) = sides(&h.capture());
        assert!(
            (left - right).abs() <= 3.0 + 0.1 * left.max(right),
            "ambient {ambient}: even light, left {left:.1} right {right:.1}"
        );
        brightness.push(0.5 * (left + right));
    }
    assert!(brightness[0] < 1.0, "no light, yet {:.1}", brightness[0]);
    assert!(
        brightness[1] > 10.0 && brightness[2] > brightness[1] + 10.0,
        "more ambient light, brighter: {brightness:?}"
    );
}

#[test]
fn a_point_light_lights_the_side_it_is_on() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("point-light", PUFF);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    h.app.world_mut().spawn((
        PointLight {
            intensity: 2_000_000.0,
            range: 20.0,
            ..default()
        },
        Transform::from_xyz(-4.0, 0.0, 1.0),
    ));
    h.update(10);
    let (left, right) = sides(&h.capture_running());
    assert!(
        left > 40.0 && left > 3.0 * right.max(1.0),
        "a lamp on the left: left third {left:.1}, right third {right:.1}"
    );
}

/// Streaks moving along +x across the view, each trailing a ribbon square to the line of
/// sight, so that lit it faces the camera (+z): lit as a flat card, it takes a light from in
/// front and none from behind (no wrap, no ambient light).
const STREAKS: &str = r#"Effect(name: "streaks", capacity: 8,
    emitters: [Emitter(rate: 2.0, shape: Point((-3.0, 0.0, 0.0)), velocity: Constant((1.5, 0.0, 0.0)),
                       lifetime: Some((3.0, 3.0)))],
    render: Render(color: [(0.0, (0.8, 0.8, 0.8, 1.0))], size: [(0.0, 0.0)],
                   trail: Some(Trail(points: 24, every: 2, width: [(0.0, 0.6)],
                                     color: [(0.0, (1.0, 1.0, 1.0, 1.0))])),
                   lit: Some(Lit())))
"#;

#[test]
fn bevys_lights_light_trails_as_cards_facing_the_eye() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("lit-trails", STREAKS);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    // The sun behind the camera, travelling toward -z: onto the ribbons' faces.
    let sun = spawn_sun(&mut h, Vec3::new(0.0, 0.0, 5.0));
    h.update(60);
    let front = h.capture_running();
    let (lit, _, _) = crate::common::lit_pixels(&front, 40);
    let brightest = front.pixels().map(|p| p.0[0]).max().unwrap_or(0);
    // Three or four ribbons 0.6 m wide in view, about 5 pixels at 10 m.
    assert!(
        lit > 30 && brightest > 150,
        "lit from the front, only {lit} pixels show, the brightest {brightest}"
    );
    // The sun behind the ribbons: their backs are lit, the faces the camera sees are dark.
    *h.app.world_mut().get_mut::<Transform>(sun).unwrap() =
        Transform::from_xyz(0.0, 0.0, -5.0).looking_at(Vec3::ZERO, Vec3::Y);
    h.update(2);
    let (lit, _, _) = crate::common::lit_pixels(&h.capture(), 8);
    assert_eq!(lit, 0, "lit from behind, yet {lit} pixels show");
}

/// Bright embers hovering at the origin that give off 4 lights (`render.light`), in front of a
/// lit grey wall 1.5 m behind them.
const EMBERS: &str = r#"Effect(name: "embers", capacity: 200, seed: 2,
    emitters: [Emitter(burst: 200, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.3),
                       velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (1.0, 0.6, 0.2, 1.0))], size: [(0.0, 0.08)], blend: Additive,
                   light: Some(ParticleLight(count: 4, intensity: 3.0, range: 6.0))))
"#;

#[test]
fn particles_that_give_off_light_light_the_scene_with_point_lights() {
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("particle-light", EMBERS);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    let embers = h.app.world_mut().spawn(PlumeEffect::new(handle)).id();
    let world = h.app.world_mut();
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(8.0, 8.0, 0.2));
    let grey = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(Color::srgb(0.6, 0.6, 0.6));
    world.spawn((
        Mesh3d(mesh),
        MeshMaterial3d(grey),
        Transform::from_xyz(0.0, 0.0, -1.5),
    ));
    h.wait_for_pipelines();
    h.update(10);
    // Four point lights of the embers' colour where the embers are.
    let mut query = h
        .app
        .world_mut()
        .query::<(&bevy_plume::PlumeLightOf, &PointLight, &Transform)>();
    let lights: Vec<_> = query
        .iter(h.app.world())
        .map(|(of, light, at)| (of.0, light.color.to_linear(), at.translation))
        .collect();
    assert_eq!(lights.len(), 4, "{lights:?}");
    for (of, color, at) in &lights {
        assert_eq!(*of, embers);
        assert!(
            at.length() < 0.31,
            "a light at {at}, outside the embers' sphere"
        );
        assert!(
            (color.green / color.red - 0.6).abs() < 0.01
                && (color.blue / color.red - 0.2).abs() < 0.01,
            "{color:?}"
        );
    }
    // The wall beside the embers is lit by them; its far corner much less.
    let image = h.capture_running();
    let brightness = |x: f32, y: f32| {
        let (px, py) = project(x, y);
        let p = image.get_pixel(px as u32, py as u32).0;
        (u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2])) / 3
    };
    let (near, far) = (brightness(1.2, 0.0), brightness(3.4, 1.7));
    assert!(
        near > 40 && near > 3 * far.max(1),
        "the wall beside the embers {near}, at its corner {far}"
    );
    // The effect gone, its lights go with it.
    h.app.world_mut().despawn(embers);
    h.update(3);
    let left = query.iter(h.app.world()).count();
    assert_eq!(left, 0, "lights outlived their effect");
}

/// Two flat lit puffs 1.5 m across, side by side at x = -2.5 and 2.5.
const PAIR: &str = r#"Effect(name: "pair", capacity: 2,
    emitters: [
        Emitter(burst: 1, shape: Point((-2.5, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(burst: 1, shape: Point((2.5, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    render: Render(color: [(0.0, (0.6, 0.6, 0.6, 1.0))], size: [(0.0, 1.5)],
                   lit: Some(Lit(normals: Flat))))
"#;

/// The mean brightness of the 3 x 3 pixels around the point (x, 0, 0).
fn brightness_at(image: &image::RgbaImage, x: f32) -> f64 {
    let (cx, cy) = project(x, 0.0);
    let (cx, cy) = (cx as u32, cy as u32);
    let around = (0..9).map(|k| (cx + k % 3 - 1, cy + k / 3 - 1));
    mean_brightness(image, around)
}

#[test]
fn a_mesh_in_the_suns_way_shadows_the_particles_behind_it() {
    // The sun shines down and away from the camera, along (0, -1, -1); a slab 3 m above and
    // in front of the left puff is in its way, nothing is in the right one's. With Bevy's
    // shadow maps the left puff gets no sunlight (and there is no other light); without them
    // both get the same.
    let _one = serial();
    let (mut h, handle) = Harness::with_effect("shadowed", PAIR);
    h.app.insert_resource(GlobalAmbientLight::NONE);
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    let sun = h
        .app
        .world_mut()
        .spawn((
            DirectionalLight {
                illuminance: 3_000.0,
                shadow_maps_enabled: true,
                ..default()
            },
            Transform::from_xyz(0.0, 5.0, 5.0).looking_at(Vec3::ZERO, Vec3::Y),
        ))
        .id();
    let world = h.app.world_mut();
    let slab = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(2.0, 0.2, 2.0));
    let grey = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::from_color(Color::srgb(0.3, 0.3, 0.3)));
    world.spawn((
        Mesh3d(slab),
        MeshMaterial3d(grey),
        Transform::from_xyz(-2.5, 3.0, 3.0),
    ));
    h.wait_for_pipelines();
    h.update(5);
    let image = h.capture_running();
    let (left, right) = (brightness_at(&image, -2.5), brightness_at(&image, 2.5));
    assert!(
        right > 60.0 && left < 3.0,
        "the left puff in the slab's shadow: left {left:.1}, right {right:.1}"
    );
    h.app
        .world_mut()
        .get_mut::<DirectionalLight>(sun)
        .unwrap()
        .shadow_maps_enabled = false;
    h.update(3);
    let image = h.capture_running();
    let (left, right) = (brightness_at(&image, -2.5), brightness_at(&image, 2.5));
    assert!(
        right > 60.0 && (left - right).abs() <= 3.0,
        "no shadow maps, both in the sun: left {left:.1}, right {right:.1}"
    );
}
