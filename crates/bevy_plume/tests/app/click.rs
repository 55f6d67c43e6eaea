//! The `from_code` example's click path (examples/from_code.rs, included here as a module so
//! the test runs its very system): a left click at the pixel where a point of the ground
//! projects bursts exactly 400 sparks there, through the camera's ray; a click with the cursor
//! outside the window bursts nothing. Headless on lavapipe, with a
//! window entity that only carries the cursor (no display).

#[path = "../../examples/from_code.rs"]
mod from_code;

use crate::common::{serial, Harness, HEIGHT, WIDTH};
use bevy::input::mouse::MouseButtonInput;
use bevy::input::ButtonState;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::window::WindowResolution;
use bevy_plume::{read_particles, PlumeEffect};
use from_code::{burst_on_click, Impacts};

/// Clicks the left button with the cursor at pixel `at` of the window (None: outside it) and
/// runs the frames that read the press and the release.
fn click(h: &mut Harness, window: Entity, at: Option<Vec2>) {
    h.app
        .world_mut()
        .get_mut::<Window>(window)
        .unwrap()
        .set_physical_cursor_position(at.map(|p| DVec2::new(f64::from(p.x), f64::from(p.y))));
    for state in [ButtonState::Pressed, ButtonState::Released] {
        h.app.world_mut().write_message(MouseButtonInput {
            button: MouseButton::Left,
            state,
            window,
        });
        h.update(1);
    }
}

#[test]
fn a_click_bursts_where_the_cursor_s_ray_meets_the_ground() {
    let _one = serial();
    let mut h = Harness::new(std::path::Path::new(from_code::ASSETS));
    // The example's camera: up and back, looking down at the ground.
    let camera = h.camera();
    h.app
        .world_mut()
        .entity_mut(camera)
        .insert(Transform::from_xyz(0.0, 6.0, 12.0).looking_at(Vec3::new(0.0, 0.5, 0.0), Vec3::Y));
    // A window of the image's size: only its cursor is read.
    let window = h
        .app
        .world_mut()
        .spawn(Window {
            resolution: WindowResolution::new(WIDTH, HEIGHT),
            ..default()
        })
        .id();
    let handle = h.load("impact.plume.ron");
    let impacts = h
        .app
        .world_mut()
        .spawn((
            Impacts,
            PlumeEffect::new(handle)
                .with_bursts()
                .with_param("wind", 0.0),
        ))
        .id();
    h.app.add_systems(Update, burst_on_click);
    h.update(3);
    h.wait_for_effects();
    let count = |h: &Harness| {
        read_particles(h.app.sub_app(RenderApp).world(), impacts, 0)
            .expect("the instance runs")
            .expect("read back")
    };
    assert!(count(&h).is_empty(), "nothing spawns before a click");
    // Where a point of the ground projects, as the camera sees it.
    let target = Vec3::new(2.0, 0.0, -1.0);
    let pixel = {
        let world = h.app.world_mut();
        let mut cameras = world.query::<(&Camera, &GlobalTransform)>();
        let (camera, eye) = cameras.single(world).unwrap();
        camera.world_to_viewport(eye, target).expect("in view")
    };
    click(&mut h, window, Some(pixel));
    h.update(1);
    let sparks = count(&h);
    assert_eq!(sparks.len(), 400, "one click, one burst of 400");
    // Spawned in the emitter's 5 cm sphere around the hit and flown for the few steps since
    // (up to 6 m/s, 0.1 m a step): all near it, and the sparks' horizontal centre on it (the
    // cone of launch directions is symmetric about the vertical).
    let mut centre = Vec2::ZERO;
    for s in &sparks {
        let p = Vec3::new(
            s.position.x as f32,
            s.position.y as f32,
            s.position.z as f32,
        );
        let off = p - target;
        assert!(
            off.length() < 0.6,
            "a spark at {p}, {off} from where the click's ray meets the ground"
        );
        centre += Vec2::new(off.x, off.z) / sparks.len() as f32;
    }
    assert!(
        centre.length() < 0.03,
        "the sparks' horizontal centre is {centre} from the click's ground point"
    );
    // The cursor outside the window: no ray, no burst.
    click(&mut h, window, None);
    h.update(1);
    assert_eq!(
        count(&h).len(),
        400,
        "a click outside the window bursts nothing"
    );
}
