//! Motion in 16-bit floats (`Layout::half_motion`): where an accuracy budget leaves room, the
//! compiler stores each particle's velocity (or Verlet's displacement) in halves, and the
//! layout drops its padding (28 bytes a mortal particle instead of 32, 24 an immortal one).
//! On llvmpipe: the budget still holds on the GPU; the stored velocities are halves; the GPU
//! follows the f64 model that rounds as it stores; buffers split at odd slot counts hold the
//! same particles as one buffer; and the draw reads the planes as the readback does.

mod common;

use common::*;
use plume::compiler::passes::layout::Planes;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::bench::check_budget;
use plume::{compile_str, CompileOptions, CompiledEffect};

/// 64 particles on a damped spring (no closed form), with lifetimes when `mortal`, held to
/// `budget` metres over 1 s.
fn effect(budget: f64, mortal: bool) -> String {
    let lifetime = if mortal {
        "lifetime: Some((2.0, 3.0)),"
    } else {
        ""
    };
    format!(
        r#"Effect(
    name: "halves",
    capacity: 64,
    seed: 11,
    emitters: [Emitter(burst: 64, {lifetime} shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.5),
                       velocity: Cone(axis: (0.0, 1.0, 0.0), angle: 40.0, speed: (1.0, 3.0)))],
    forces: [Custom(accel: "-6.0 * x - 0.4 * v")],
    accuracy: (position: {budget:e}, over: 1.0),
    camera: Camera(eye: (0.0, 0.5, 6.0), target: (0.0, 0.5, 0.0), fov_y: 50.0),
    render: Render(color: [(0.0, (1.0, 0.8, 0.4, 1.0))], size: [(0.0, 0.08)],
                   background: (0.0, 0.0, 0.0), orient: Velocity(stretch: 0.05, max_length: 0.3)),
)"#
    )
}

fn compiled(src: &str) -> CompiledEffect {
    compile_str(src, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("halves.ron", src)))
}

#[test]
fn a_loose_budget_stores_motion_in_halves_and_the_gpu_keeps_the_budget() {
    let src = effect(0.05, true);
    let c = compiled(&src);
    let accuracy = c.ir.accuracy.clone().unwrap();
    assert!(accuracy.half_motion, "{}", accuracy.describe());
    assert!(
        accuracy.half_estimate.unwrap() <= 0.05 / 2.0,
        "{}",
        accuracy.describe()
    );
    assert!(
        accuracy
            .describe()
            .contains("motion stored in 16-bit floats"),
        "{}",
        accuracy.describe()
    );
    // position 12 + id 4 | velocity 8 + die_at 4: a 16-byte plane, an 8-byte and a 4-byte one.
    assert_eq!(c.layout.bytes_per_particle, 28);
    assert_eq!(
        c.layout.planes(),
        Planes {
            full: 1,
            pair: true,
            single: true
        }
    );
    let effect = plume::compiler::parse_with(&src, &CompileOptions::default()).unwrap();
    let check = check_budget(&gpu(), &effect).unwrap().expect("a budget");
    assert!(
        check.met() && check.particles == 64,
        "measured {:.3e} m on the GPU against 5e-2 m",
        check.measured
    );
}

#[test]
fn a_tight_budget_keeps_motion_in_32_bit_floats() {
    let c = compiled(&effect(1e-4, true));
    let accuracy = c.ir.accuracy.clone().unwrap();
    assert!(!accuracy.half_motion, "{}", accuracy.describe());
    // The halves were measured and missed: the note says by how much.
    assert!(accuracy.half_estimate.unwrap() > 1e-4 / 2.0);
    assert!(
        accuracy.describe().contains("motion kept in 32-bit floats"),
        "{}",
        accuracy.describe()
    );
    assert_eq!(c.layout.bytes_per_particle, 32);
}

/// The GPU run of a half-motion effect against its f64 oracle, which rounds the motion to
/// halves where the GPU stores it: every stored velocity component is a half, and positions agree.
/// They differ by f32's arithmetic, plus, where f32 and f64 land on opposite sides of a
/// half's rounding boundary (about 1 in 2,000 roundings, given f32's 6e-8 relative error against
/// a half's 4.9e-4 spacing), one half's spacing of velocity (at most 3 m/s · 4.9e-4 = 1.5e-3 m/s)
/// kept for the rest of the run (under 1 s): 1.5e-3 m. The spring damps rather than amplifies
/// it. The bound checked is 5e-3 m; the test prints what it measured.
#[test]
fn the_gpu_follows_the_f64_model_of_its_halves() {
    for mortal in [true, false] {
        let c = compiled(&effect(0.05, mortal));
        assert!(c.layout.half_motion);
        assert_eq!(c.layout.bytes_per_particle, if mortal { 28 } else { 24 });
        let steps = 50;
        let (_, gpu_records) = run_gpu(&c, steps);
        // The oracle stores what the layout stores: halves here.
        let mut sim = ReferenceSim::new(&c.ir);
        sim.run(steps);
        let cpu_records = sim.records();
        assert_eq!(gpu_records.len(), 64);
        assert_eq!(cpu_records.len(), 64);
        let mut worst: f64 = 0.0;
        for (g, r) in gpu_records.iter().zip(&cpu_records) {
            assert_eq!(g.id, r.id);
            // Verlet stores the displacement over a substep; the record divides it by h.
            let stored = if c.ir.integrator == plume::Integrator::Verlet {
                g.velocity * c.ir.h()
            } else {
                g.velocity
            };
            for v in stored.to_array() {
                let as_half = half::f16::from_f64(v).to_f64();
                assert!(
                    (as_half - v).abs() <= 1e-12 * v.abs(),
                    "motion {v} read back is not a 16-bit float"
                );
            }
            worst = worst.max((g.position - r.position).length());
        }
        println!("mortal {mortal}: worst position difference {worst:.2e} m");
        assert!(worst < 5e-3, "mortal {mortal}: {worst:.3e} m");
    }
}

/// Buffers of 7 slots (an odd count: the last pair and single words share a vec4 with no
/// neighbour) hold exactly the particles one buffer holds, and the draw of either, reading the
/// planes in WGSL, matches the CPU-fed drawing of the records read back.
#[test]
fn split_buffers_hold_the_same_particles_and_draw_them() {
    let c = compiled(&effect(0.05, true));
    let gpu = gpu();
    let mut whole = split(&gpu, c.clone(), None);
    let mut parts = split(&gpu, c, Some(7));
    whole.run(30, |_| {}).unwrap();
    parts.run(30, |_| {}).unwrap();
    let (a, b) = (whole.records().unwrap(), parts.records().unwrap());
    assert_eq!(a.len(), 64);
    assert_eq!(
        a, b,
        "the split buffers' particles differ from one buffer's"
    );
    for sim in [&whole, &parts] {
        let (gpu_img, cpu_img) = draw_and_reference(sim, 96);
        let (mean, max, over) = differences(&gpu_img, &cpu_img, 8);
        assert!(gpu_img.chunks(4).any(|p| p[0] > 0), "nothing drawn");
        // The same sprites rasterised from the same positions: only edge pixels may differ.
        assert!(
            mean < 0.5 && over < 40,
            "draw vs reference: mean {mean:.3}, largest {max}, {over} over 8"
        );
    }
}
