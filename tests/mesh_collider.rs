//! Mesh colliders: a closed OBJ mesh baked into a signed distance field. A box mesh collides
//! as the analytic `Box` does, a wall a few field cells thick is never passed through at
//! 1,000 m/s, contacts on a placed (moved, scaled, rotated) mesh on the GPU match the f64
//! reference, particles dropped on a mesh come to rest on it, and bad meshes are refused at
//! the collider's `file`.

mod common;

use common::meshes::{box_obj, sphere_obj, write};
use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;

const INTEGRATORS: &[&str] = &["Euler", "SemiImplicitEuler", "Verlet", "Midpoint", "Rk4"];

fn shot(collider: &str, integrator: &str, from: (f64, f64, f64), velocity: &str) -> String {
    format!(
        r#"Effect(
    name: "shot",
    capacity: 500,
    seed: 3,
    dt: 0.016666667,
    emitters: [Emitter(burst: 500, shape: Disc(center: {from:?}, normal: (1.0, 0.0, 0.0), radius: 0.3),
                       velocity: {velocity})],
    forces: [Gravity((0.0, -9.81, 0.0))],
    integrator: {integrator},
    collide: [{collider}],
)"#
    )
}

#[test]
fn a_box_mesh_collides_as_the_box_collider_does() {
    // On a box's faces the baked field is exact (the distance to a plane is linear, so
    // trilinear between exact nodes), so contacts differ from the analytic box's only by the
    // bisection's width (2^-20 of a march step) and the contact margins.
    let file = write("slab.obj", &box_obj([-0.5, -1.0, -1.0], [0.5, 1.0, 1.0]));
    let by_mesh = format!("Mesh(file: {file:?}, restitution: 0.7, friction: 0.2)");
    let by_box =
        "Box(min: (-0.5, -1.0, -1.0), max: (0.5, 1.0, 1.0), restitution: 0.7, friction: 0.2)";
    let cone = "Cone(axis: (1.0, 0.1, 0.05), angle: 8.0, speed: (50.0, 80.0))";
    for integrator in INTEGRATORS {
        let mesh = compile(&shot(&by_mesh, integrator, (-2.0, 0.0, 0.0), cone));
        let analytic = compile(&shot(by_box, integrator, (-2.0, 0.0, 0.0), cone));
        let (_, a) = run_cpu(&mesh, 3);
        let (_, b) = run_cpu(&analytic, 3);
        let mut bounced = 0;
        for (m, b) in a.iter().zip(&b) {
            assert!(
                (m.position - b.position).length() < 1e-5,
                "{integrator}: particle {} at {:?} off the mesh, {:?} off the box",
                m.id,
                m.position,
                b.position
            );
            assert!((m.velocity - b.velocity).length() < 1e-5);
            bounced += usize::from(b.velocity.x < 0.0);
        }
        assert!(bounced > 400, "{integrator}: only {bounced} bounced");
    }
}

#[test]
fn particles_at_1000_m_s_never_pass_through_a_mesh_wall_three_cells_thick() {
    // The wall is 2 m tall at resolution 32: cells of 6.25 cm, the wall 18.75 cm thick. At
    // 16.7 m per step, sampling positions would miss it nearly always.
    let file = write(
        "wall.obj",
        &box_obj([-0.09375, -1.0, -1.0], [0.09375, 1.0, 1.0]),
    );
    let wall = format!("Mesh(file: {file:?}, restitution: 1.0, friction: 0.0)");
    for integrator in INTEGRATORS {
        let src = shot(
            &wall,
            integrator,
            (-20.0, 0.0, 0.0),
            "Constant((1000.0, 0.0, 0.0))",
        );
        let e = compile(&src);
        let surface = e.ir.colliders[0].surface.clone();
        let gpu = gpu();
        let mut sim = Effect::new(&gpu, e.clone()).unwrap();
        let mut cpu = ReferenceSim::new(&e.ir);
        for step in 1..=6 {
            sim.run(1, |_| {}).unwrap();
            cpu.step();
            for (side, records) in [("gpu", sim.records().unwrap()), ("cpu", cpu.records())] {
                assert_eq!(records.len(), 500, "{side}: particles were lost");
                for r in &records {
                    assert!(
                        surface.allows(r.position) && r.position.x < 0.0,
                        "{integrator} {side}, step {step}: particle {} at {:?} is in or past the wall",
                        r.id,
                        r.position
                    );
                }
            }
        }
        let (_, after) = run_cpu(&e, 2);
        assert!(
            after.iter().all(|r| r.velocity.x < 0.0),
            "{integrator}: all bounced back"
        );
    }
}

#[test]
fn contacts_on_a_placed_mesh_on_the_gpu_match_the_reference() {
    // A unit sphere mesh halved, moved and turned. Both sides march the same f32 field; they
    // differ by how f32 rounds the grid coordinates and the interpolation (about 1e-7 m
    // here) and by the f32 step itself, so the position bound is the other colliders' 32 ulps
    // of 1 + |x|. The outgoing velocity turns with the normal, the field's gradient by central
    // differences half a cell (1/64 of the radius at resolution 32) wide: a position error e
    // turns it by about e / (half a cell), so the velocity's unit is an ulp of 1 + |v| times
    // 1 + (1 + |x|) / (half a cell), about 130 ulps here. Measured: positions within 14 ulps,
    // velocities within 0.66 of that unit; the bounds are 32 ulps and 2 units.
    let file = write("ball.obj", &sphere_obj(12, 24));
    let ball = format!(
        "Mesh(file: {file:?}, offset: (0.2, 0.1, 0.0), scale: 0.5, rotation: (30.0, 45.0, 10.0), restitution: 0.7, friction: 0.2)"
    );
    let half_cell = 0.5 * (2.0 * 0.5 / 32.0);
    for integrator in INTEGRATORS {
        let src = shot(
            &ball,
            integrator,
            (-2.0, 0.5, 0.0),
            "Cone(axis: (1.0, -0.2, 0.0), angle: 10.0, speed: (50.0, 80.0))",
        );
        let e = compile(&src);
        let (_, gpu) = run_gpu(&e, 2);
        let (_, cpu) = run_cpu(&e, 2);
        let mut bounced = 0;
        let (mut worst_x, mut worst_v) = (0.0_f64, 0.0_f64);
        for (g, c) in gpu.iter().zip(&cpu) {
            assert_eq!(g.id, c.id);
            let dx = (g.position - c.position).length() / (U32 * (1.0 + c.position.length()));
            let turn = 1.0 + (1.0 + c.position.length()) / half_cell;
            let dv =
                (g.velocity - c.velocity).length() / (U32 * (1.0 + c.velocity.length()) * turn);
            worst_x = worst_x.max(dx);
            worst_v = worst_v.max(dv);
            assert!(
                dx <= 32.0 && dv <= 2.0,
                "{integrator}: particle {} at {:?} moving {:?} on the GPU, {:?} moving {:?} in f64",
                g.id,
                g.position,
                g.velocity,
                c.position,
                c.velocity
            );
            bounced += usize::from(c.velocity.x < 0.0);
        }
        eprintln!("{integrator}: worst position {worst_x:.1} ulps, velocity {worst_v:.2} of its bound's unit");
        assert!(bounced > 50, "{integrator}: only {bounced} bounced");
    }
}

#[test]
fn particles_dropped_on_a_mesh_come_to_rest_on_it() {
    // A slab whose top is y = 0, under a falling disc; after 4 s every particle rests on the
    // top (a contact slower than the rest speed does not bounce), on the GPU and in the
    // reference, and none has sunk into the field.
    let file = write("floor.obj", &box_obj([-1.5, -1.0, -1.5], [1.5, 0.0, 1.5]));
    let floor = format!("Mesh(file: {file:?}, restitution: 0.3, friction: 0.5)");
    let src = shot(
        &floor,
        "SemiImplicitEuler",
        (0.0, 1.0, 0.0),
        "Constant((0.0, 0.0, 0.0))",
    )
    .replace(
        "normal: (1.0, 0.0, 0.0), radius: 0.3",
        "normal: (0.0, 1.0, 0.0), radius: 0.5",
    );
    let e = compile(&src);
    let surface = e.ir.colliders[0].surface.clone();
    for (side, records) in [("gpu", run_gpu(&e, 240).1), ("cpu", run_cpu(&e, 240).1)] {
        for r in &records {
            assert!(
                surface.allows(r.position),
                "{side}: particle {} sank to {:?}",
                r.id,
                r.position
            );
            assert!(
                r.position.y < 1e-4 && r.velocity.length() < 0.05,
                "{side}: particle {} is not at rest on the top: at {:?} moving {:?}",
                r.id,
                r.position,
                r.velocity
            );
        }
    }
}

#[test]
fn bad_meshes_are_refused_at_the_collider_file() {
    let open = write(
        "open.obj",
        &box_obj([0.0; 3], [1.0; 3]).replace("f 3 7 8 4\n", ""),
    );
    let nan = write(
        "nan.obj",
        &box_obj([0.0; 3], [1.0; 3]).replacen("v 1 1 1", "v nan 1 1", 1),
    );
    let flat = write(
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 1 2 4\nf 1 4 3\nf 1 4 2\nf 1 3 4\n",
    );
    let good = write("cube.obj", &box_obj([0.0; 3], [1.0; 3]));
    let cases = [
        (
            "Mesh(file: \"no/such/rock.obj\", restitution: 0.5, friction: 0.0)".to_string(),
            "collide[0] (Mesh).file: cannot open mesh `no/such/rock.obj`",
        ),
        (
            format!("Mesh(file: {open:?}, restitution: 0.5, friction: 0.0)"),
            "is not closed: 4 edge(s) border an odd number of triangles",
        ),
        (
            format!("Mesh(file: {nan:?}, restitution: 0.5, friction: 0.0)"),
            "is (NaN, 1, 1): every coordinate must be finite",
        ),
        (
            format!("Mesh(file: {flat:?}, restitution: 0.5, friction: 0.0)"),
            "is flat (its box is 1 x 0 x 1): a solid needs a volume",
        ),
        (
            format!("Mesh(file: {good:?}, resolution: 2, restitution: 0.5, friction: 0.0)"),
            "collide[0] (Mesh).resolution: resolution is the cells along the mesh's longest side, 4 to 128, got 2",
        ),
        (
            format!("Mesh(file: {good:?}, scale: 0.0, restitution: 0.5, friction: 0.0)"),
            "collide[0] (Mesh).scale",
        ),
    ];
    for (collider, expected) in cases {
        let src = shot(
            &collider,
            "Euler",
            (3.0, 1.0, 0.0),
            "Constant((1.0, 0.0, 0.0))",
        );
        let error = plume::compile_str(&src, &Default::default()).unwrap_err();
        let text = error.render("shot.ron", &src);
        assert!(
            text.contains(expected) && text.contains("shot.ron:10:"),
            "{text}"
        );
    }
}
