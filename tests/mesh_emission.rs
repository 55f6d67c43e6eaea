//! Spawning on meshes: uniform by area on a mesh's surface, along its normals, or in its
//! volume, the GPU picking the very triangle (or field cell) the f64 reference picks; bad uses
//! are refused where they are written.

mod common;

use common::meshes::{box_obj, sphere_obj, write};
use common::*;
use glam::DVec3;

const DT: f64 = 0.001;

fn spray(shape: &str, count: u32) -> String {
    spray_with(shape, count, "Normal(speed: (1.0, 2.0))")
}

fn spray_with(shape: &str, count: u32, velocity: &str) -> String {
    format!(
        r#"Effect(
    name: "spray",
    capacity: {count},
    seed: 11,
    dt: {DT},
    emitters: [Emitter(burst: {count}, shape: {shape}, velocity: {velocity})],
    integrator: SemiImplicitEuler,
)"#
    )
}

/// Runs one step on the GPU and in the reference and returns (spawn position, velocity) of
/// every particle, checking that they agree (see [`common::spawn_states`]).
fn spawned(src: &str) -> Vec<(DVec3, DVec3)> {
    spawn_states(src, DT)
}

#[test]
fn particles_spawn_on_a_box_mesh_uniformly_by_area_along_its_normals() {
    // Faces of 0.5, 1 and 2 m² (two each): 1/14, 1/7 and 2/7 of the particles each.
    let file = write("crate.obj", &box_obj([0.0, 0.0, 0.0], [2.0, 1.0, 0.5]));
    let n = 20_000;
    let offset = DVec3::new(1.0, 2.0, 3.0);
    let particles = spawned(&spray(
        &format!("Mesh(file: {file:?}, offset: (1.0, 2.0, 3.0))"),
        n,
    ));
    assert_eq!(particles.len(), n as usize);
    let size = DVec3::new(2.0, 1.0, 0.5);
    let mut on_face = [0usize; 6];
    for (x, v) in &particles {
        let local = *x - offset;
        assert!(
            local.cmpge(DVec3::splat(-1e-5)).all() && local.cmple(size + 1e-5).all(),
            "{x:?} is off the box"
        );
        // The face is the one the velocity leaves along; the point must lie on it.
        let speed = v.length();
        assert!((1.0..=2.0).contains(&speed), "speed {speed}");
        let n = *v / speed;
        let axis = (0..3)
            .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap();
        let mut normal = DVec3::ZERO;
        normal[axis] = n[axis].signum();
        assert!((n - normal).length() < 1e-6, "{v:?} is not along an axis");
        let face = 2 * axis + usize::from(normal[axis] > 0.0);
        let at = if face % 2 == 0 { 0.0 } else { size[axis] };
        assert!(
            (local[axis] - at).abs() < 1e-5,
            "{x:?} is not on face {face}"
        );
        on_face[face] += 1;
    }
    for (face, &count) in on_face.iter().enumerate() {
        let area = [0.5, 1.0, 2.0][face / 2];
        let p = area / 7.0;
        let expected = f64::from(n) * p;
        let sigma = (f64::from(n) * p * (1.0 - p)).sqrt();
        assert!(
            (count as f64 - expected).abs() < 4.5 * sigma,
            "face {face}: {count} particles, {expected:.0} expected (sigma {sigma:.0})"
        );
    }
}

#[test]
fn particles_spawn_on_a_placed_sphere_mesh_moving_outward() {
    // A unit sphere mesh of 12 rings scaled to 0.5, turned and moved: every point lies between
    // the polygon's inner radius and the sphere's, and moves within a facet's tilt of radially.
    let file = write("orb.obj", &sphere_obj(12, 24));
    let center = DVec3::new(-1.0, 0.5, 2.0);
    let particles = spawned(&spray(
        &format!("Mesh(file: {file:?}, offset: (-1.0, 0.5, 2.0), scale: 0.5, rotation: (20.0, 0.0, 70.0))"),
        4000,
    ));
    let inner = 0.5 * (std::f64::consts::PI / 13.0).cos() * (std::f64::consts::PI / 24.0).cos();
    for (x, v) in &particles {
        let r = (*x - center).length();
        assert!(r <= 0.5 + 1e-6 && r >= inner - 1e-6, "{x:?} at radius {r}");
        let radial = (*x - center) / r;
        assert!(
            v.normalize().dot(radial) > 0.95,
            "{v:?} is not outward at {x:?}"
        );
    }
}

#[test]
fn particles_spawn_in_a_placed_sphere_mesh_uniformly_by_volume() {
    // Cells whose centre is inside (resolution 32: cells of 1/32 of the diameter, 1/64 of the
    // radius before scaling), so every point is within half a cell's diagonal of the sphere and
    // a uniform density puts half the points within 2^(-1/3) of the radius, to within the
    // cells' staircase (a few per cent) and the draw's noise (0.5 / sqrt(n) = 0.8%).
    let file = write("orb-volume.obj", &sphere_obj(24, 48));
    let center = DVec3::new(0.5, 1.0, -1.0);
    let radius = 0.5;
    let particles = spawned(&spray_with(
        &format!("Mesh(file: {file:?}, offset: (0.5, 1.0, -1.0), scale: 0.5, rotation: (10.0, 30.0, 0.0), volume: true)"),
        4000,
        "Constant((0.0, 1.0, 0.0))",
    ));
    let cell = 2.0 * radius / 32.0;
    let mut inner = 0;
    for (x, _) in &particles {
        let r = (*x - center).length();
        assert!(
            r <= radius + 0.87 * cell,
            "{x:?} at radius {r} is outside the mesh"
        );
        inner += usize::from(r <= radius * 0.5_f64.cbrt());
    }
    let fraction = inner as f64 / particles.len() as f64;
    assert!(
        (fraction - 0.5).abs() < 0.04,
        "{fraction} of the points in the inner half of the volume"
    );
}

#[test]
fn mesh_spawn_errors_are_located() {
    let cube = write("cube-spawn.obj", &box_obj([0.0; 3], [1.0; 3]));
    let open = write(
        "open-spawn.obj",
        &box_obj([0.0; 3], [1.0; 3]).replace("f 3 7 8 4\n", ""),
    );
    let cases = [
        (
            spray("Mesh(file: \"no/such/statue.obj\")", 10),
            "emitters[0].shape (Mesh).file: cannot open mesh `no/such/statue.obj`",
            ":6:",
        ),
        (
            spray(
                "Disc(center: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), radius: 1.0)",
                10,
            ),
            "Normal follows the surface a particle spawns on: it needs a `Mesh` shape",
            ":6:",
        ),
        (
            spray(&format!("Mesh(file: {cube:?}, scale: -1.0)"), 10),
            "emitters[0].shape (Mesh).scale",
            ":6:",
        ),
        (
            spray(&format!("Mesh(file: {cube:?}, volume: true)"), 10),
            "a particle spawned in a mesh's volume has no surface normal",
            ":6:",
        ),
        (
            spray_with(&format!("Mesh(file: {open:?}, volume: true)"), 10, "Radial(speed: (1.0, 1.0))"),
            "emitters[0].shape (Mesh).file: mesh",
            ":6:",
        ),
        (
            spray_with(&format!("Mesh(file: {cube:?}, volume: true, resolution: 500)"), 10, "Radial(speed: (1.0, 1.0))"),
            "emitters[0].shape (Mesh).resolution: resolution is the field cells along the mesh's longest side, 4 to 128, got 500",
            ":6:",
        ),
    ];
    for (src, expected, line) in cases {
        let error = plume::compile_str(&src, &Default::default()).unwrap_err();
        let text = error.render("spray.ron", &src);
        assert!(
            text.contains(expected) && text.contains(&format!("spray.ron{line}")),
            "{text}"
        );
    }
}
