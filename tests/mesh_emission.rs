//! Spawning on meshes: uniform by area on a mesh's surface, along its normals, the GPU picking
//! the very triangle the f64 reference picks; bad uses are refused where they are written.

mod common;

use common::meshes::{box_obj, sphere_obj, write};
use common::*;
use glam::DVec3;

const DT: f64 = 0.001;

fn spray(shape: &str, count: u32) -> String {
    format!(
        r#"Effect(
    name: "spray",
    capacity: {count},
    seed: 11,
    dt: {DT},
    emitters: [Emitter(burst: {count}, shape: {shape}, velocity: Normal(speed: (1.0, 2.0)))],
    integrator: SemiImplicitEuler,
)"#
    )
}

/// Runs one step on the GPU and in the reference and returns (spawn position, velocity) of
/// every particle from both, checking that they agree: the triangle is picked by integer
/// thresholds on both sides, so only the f32 arithmetic of the point differs (a few ulps).
fn spawned(src: &str) -> Vec<(DVec3, DVec3)> {
    let e = compile(src);
    let (_, gpu) = run_gpu(&e, 1);
    let (_, cpu) = run_cpu(&e, 1);
    assert_eq!(gpu.len(), cpu.len());
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!(g.id, c.id);
        assert!(
            (g.position - c.position).length() <= 16.0 * U32 * (1.0 + c.position.length())
                && (g.velocity - c.velocity).length() <= 16.0 * U32 * (1.0 + c.velocity.length()),
            "particle {}: at {:?} moving {:?} on the GPU, at {:?} moving {:?} in f64",
            g.id,
            g.position,
            g.velocity,
            c.position,
            c.velocity
        );
    }
    cpu.iter()
        .map(|c| (c.position - c.velocity * DT, c.velocity))
        .collect()
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
        // The face it is on: the coordinate at 0 or at the size, the others within.
        let face = (0..6)
            .find(|&f| {
                let axis = f / 2;
                let at = if f % 2 == 0 { 0.0 } else { size[axis] };
                (local[axis] - at).abs() < 1e-5
            })
            .unwrap_or_else(|| panic!("{x:?} is on no face"));
        assert!(
            local.cmpge(DVec3::splat(-1e-5)).all() && local.cmple(size + 1e-5).all(),
            "{x:?} is off the box"
        );
        let axis = face / 2;
        let mut normal = DVec3::ZERO;
        normal[axis] = if face % 2 == 0 { -1.0 } else { 1.0 };
        let speed = v.length();
        assert!((1.0..=2.0).contains(&speed), "speed {speed}");
        assert!(
            (*v / speed - normal).length() < 1e-6,
            "{v:?} is not along {normal:?}"
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
fn mesh_spawn_errors_are_located() {
    let cube = write("cube-spawn.obj", &box_obj([0.0; 3], [1.0; 3]));
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
