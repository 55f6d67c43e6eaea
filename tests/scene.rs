//! The scene `plume render` draws around an effect: the meshes it names, drawn with depth, so
//! that particles behind a mesh are hidden and those in front are not.

mod common;

use common::meshes::{box_obj, write};
use common::*;
use plume::runtime::outputs::{Offscreen, Scene};
use plume::runtime::Effect;

const W: u32 = 160;
const H: u32 = 90;

/// A wall (a mesh collider between the camera and the origin) and two still sheets of white
/// particles close enough to cover what they span: one behind the wall, one in front of its
/// left half.
fn effect() -> String {
    let wall = write(
        "scene-wall.obj",
        &box_obj([-1.0, -1.0, -0.1], [1.0, 1.0, 0.1]),
    );
    format!(
        r#"Effect(
    name: "behind",
    capacity: 4000,
    seed: 1,
    emitters: [
        Emitter(burst: 1271, shape: Grid(min: (-2.0, -1.5, -2.0), max: (2.0, 1.5, -2.0), counts: (41, 31, 1)), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(burst: 273, shape: Grid(min: (-0.9, -0.5, 1.0), max: (-0.3, 0.5, 1.0), counts: (13, 21, 1)), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    collide: [Mesh(file: {wall:?}, restitution: 0.5, friction: 0.0)],
    camera: Camera(eye: (0.0, 0.0, 6.0), target: (0.0, 0.0, 0.0), fov_y: 45.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.3)], blend: Alpha, background: (0.0, 0.0, 0.0)),
)"#
    )
}

fn pixel(img: &[u8], x: u32, y: u32) -> [u8; 4] {
    let i = ((y * W + x) * 4) as usize;
    [img[i], img[i + 1], img[i + 2], img[i + 3]]
}

#[test]
fn the_scene_hides_particles_behind_its_meshes_and_not_those_in_front() {
    let e = compile(&effect());
    let triangles = e.ir.scene_triangles();
    assert_eq!(triangles.len(), 12, "the wall's 6 quads");
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e).unwrap();
    sim.run(1, |_| {}).unwrap();
    let target = Offscreen::new(&gpu, W, H).unwrap();
    let camera = target.effect_camera(&sim);
    let plain = target
        .render(&sim, &sim.renderer(&target.target()).unwrap(), &camera)
        .unwrap();
    let scene = Scene::new(&gpu, &triangles, target.target().color_format, (W, H))
        .unwrap()
        .expect("a scene with triangles");
    let renderer = sim.renderer(&Scene::target(target.target())).unwrap();
    let shown = target
        .render_over_scene(&sim, &renderer, &camera, &scene)
        .unwrap();
    if let Ok(dir) = std::env::var("PLUME_SCENE_PNG") {
        for (name, img) in [("plain", &plain), ("shown", &shown)] {
            image::RgbaImage::from_raw(W, H, img.clone())
                .unwrap()
                .save(format!("{dir}/{name}.png"))
                .unwrap();
        }
    }
    // Where the wall's right half is (x = 0.5 m, y = 0 at z = 0.1 projects right of centre),
    // the sheet behind shows without the scene and the lit grey wall with it.
    let (wx, wy) = camera
        .project(W, H, glam::DVec3::new(0.5, 0.0, 0.1))
        .unwrap();
    let (wx, wy) = (wx as u32, wy as u32);
    let white = |p: [u8; 4]| p[0] > 200 && p[1] > 200 && p[2] > 200;
    assert!(
        white(pixel(&plain, wx, wy)),
        "no particles behind the wall to hide: {:?}",
        pixel(&plain, wx, wy)
    );
    let wall = pixel(&shown, wx, wy);
    assert!(
        !white(wall) && wall[0] > 20 && wall[0] < 200 && wall[0].abs_diff(wall[2]) < 30,
        "the wall's grey should cover the sheet behind it, got {wall:?}"
    );
    // The sheet in front of the left half is drawn over the wall.
    let (fx, fy) = camera
        .project(W, H, glam::DVec3::new(-0.6, 0.0, 1.0))
        .unwrap();
    assert!(
        white(pixel(&shown, fx as u32, fy as u32)),
        "{:?}",
        pixel(&shown, fx as u32, fy as u32)
    );
    // Away from the wall the sheet behind shows in both.
    let (ox, oy) = camera
        .project(W, H, glam::DVec3::new(1.7, 1.3, -2.0))
        .unwrap();
    assert!(
        white(pixel(&shown, ox as u32, oy as u32)) && white(pixel(&plain, ox as u32, oy as u32))
    );
}

/// The wall's face toward the camera (normal +z) at its centre pixel, lit by the scene's plain
/// light and then by a lit effect's own (set as `plume render` sets them): the grey times the
/// light Lambert's law gives, within one 8-bit step.
#[test]
fn the_scene_is_lit_by_a_lit_effects_lights() {
    use plume::compiler::lights::{LightSource, Lights};
    use plume::runtime::outputs::SCENE_GREY;
    let e = compile(&effect());
    let triangles = e.ir.scene_triangles();
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, e).unwrap();
    sim.run(1, |_| {}).unwrap();
    let target = Offscreen::new(&gpu, W, H).unwrap();
    let camera = target.effect_camera(&sim);
    let scene = Scene::new(&gpu, &triangles, target.target().color_format, (W, H))
        .unwrap()
        .expect("a scene with triangles");
    let renderer = sim.renderer(&Scene::target(target.target())).unwrap();
    // A point of the wall's face that no particle covers: its lower right, in front of the
    // sheet behind (hidden) and right of the sheet in front.
    let (x, y) = camera
        .project(W, H, glam::DVec3::new(0.8, -0.8, 0.1))
        .unwrap();
    let face = |lights: &Lights| {
        let received = lights.received(glam::DVec3::Z, glam::DVec3::new(0.8, -0.8, 0.1), 0.0);
        [0, 1, 2].map(|c| f64::from(SCENE_GREY[c]) * received[c] * 255.0)
    };
    let red_sun = Lights {
        ambient: glam::DVec3::new(0.0, 0.0, 0.1),
        sources: vec![LightSource::Directional {
            direction: glam::DVec3::new(0.3, 0.0, -1.0),
            color: glam::DVec3::new(1.5, 0.4, 0.0),
        }],
        shadow: None,
    };
    for (name, lights) in [("plain", None), ("the effect's", Some(&red_sun))] {
        if let Some(lights) = lights {
            scene.set_lights(lights);
        }
        let img = target
            .render_over_scene(&sim, &renderer, &camera, &scene)
            .unwrap();
        let got = pixel(&img, x as u32, y as u32);
        let want = face(lights.unwrap_or(&Scene::plain_lights()));
        assert!(
            (0..3).all(|c| (f64::from(got[c]) - want[c].min(255.0)).abs() <= 1.0),
            "{name} light: the wall is {got:?}, Lambert's law gives {want:.2?}"
        );
    }
}
