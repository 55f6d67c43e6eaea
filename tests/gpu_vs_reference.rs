//! Every example effect on the GPU (llvmpipe in CI) against the CPU f64 reference.
//!
//! Tolerance. The GPU computes in f32 (unit roundoff u = 2^-24), the reference in f64. Each step
//! a particle's position and velocity go through a handful of rounded operations (the force sum,
//! the velocity update, the position update, a contact), each off by at most about
//! u·(|x| + 1 m) once scaled to position. Bounding that by 4 roundings a step and letting errors
//! add up linearly (a worst case: measured errors are about ten times smaller) gives
//! |x_gpu - x_cpu| <= 4 N u (1 + |x|) after N steps: 2.4e-5 relative at N = 100, for one force
//! evaluation a step; substeps and multi-stage integrators multiply it (`roundings_per_step`). Velocities get
//! the same bound relative to (1 + |v|). Spawn draws are bit-identical integer hashes and deaths
//! are integer steps, so the sets of live ids must be equal exactly.

mod common;

use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::EffectInstance;

/// Whether the effect has a curved collider (a sphere or a height field). Particles that land
/// near a point where the surface turns away in every direction (a sphere's apex, a ridge's
/// crest) slide off to the side that rounding picks: f32 and f64 then part ways by up to the
/// distance travelled since (rock_fountain.ron at step 100: 90% of particles within 3.9e-7
/// (1 + |x|), the farthest 2.9e-2). Such effects need 95% of particles within the bound; each
/// contact's own accuracy is tested in tests/colliders.rs.
fn curved_colliders(ir: &plume::compiler::EffectIr) -> bool {
    use plume::compiler::colliders::Surface;
    ir.colliders
        .iter()
        .any(|c| matches!(c.surface, Surface::Sphere(_) | Surface::HeightField(_)))
}

fn compare_at(
    name: &str,
    steps: u64,
    flocks: bool,
    curved: bool,
    roundings_per_step: f64,
    gpu: &[plume::compiler::reference::ParticleRecord],
    cpu: &[plume::compiler::reference::ParticleRecord],
) {
    let gpu_ids: Vec<u32> = gpu.iter().map(|r| r.id).collect();
    let cpu_ids: Vec<u32> = cpu.iter().map(|r| r.id).collect();
    assert_eq!(
        gpu_ids, cpu_ids,
        "{name}: live ids differ after {steps} steps"
    );
    // Independent particles: 4 roundings of 2^-24 a step. A flock couples them: every boid's
    // rounding reaches its neighbours, and a dense flock amplifies it (boids.ron: measured
    // 1.5e-5 (1 + |x|) in position and 3.9e-5 (1 + |v|) in velocity at step 100); allow 1e-4.
    let tol = if flocks {
        1e-4
    } else {
        roundings_per_step * steps as f64 * U32
    };
    let mut outside = 0;
    for (g, c) in gpu.iter().zip(cpu) {
        assert_eq!(g.age, c.age);
        let dx = (g.position - c.position).length();
        let dv = (g.velocity - c.velocity).length();
        if curved {
            outside += usize::from(
                dx > tol * (1.0 + c.position.length()) || dv > tol * (1.0 + c.velocity.length()),
            );
            continue;
        }
        assert!(
            dx <= tol * (1.0 + c.position.length()),
            "{name}: particle {} after {steps} steps: gpu {:?} cpu {:?} (|dx| = {dx:e})",
            g.id,
            g.position,
            c.position
        );
        assert!(
            dv <= tol * (1.0 + c.velocity.length()),
            "{name}: particle {} velocity after {steps} steps: gpu {:?} cpu {:?}",
            g.id,
            g.velocity,
            c.velocity
        );
    }
    assert!(
        outside * 20 <= gpu.len(),
        "{name}: {outside} of {} particles off the reference after {steps} steps (5% allowed)",
        gpu.len()
    );
}

/// Four roundings per force evaluation and update, times the evaluations a step makes: one per
/// substep for the one-stage integrators, two for Midpoint, four for Rk4 (each stage evaluates
/// the forces and adds a rounded combination). magnetic_bottle.ron (Rk4, 2 substeps, a
/// rotation whose phase errors add up) measured 1.1e-4 (1 + |v|) / 4 at step 100 in velocity,
/// under this bound of 32 roundings a step (1.9e-4) and over the one-stage bound (2.4e-5).
fn roundings_per_step(ir: &plume::compiler::EffectIr) -> f64 {
    let stages = match ir.integrator {
        plume::Integrator::Midpoint => 2.0,
        plume::Integrator::Rk4 => 4.0,
        _ => 1.0,
    };
    4.0 * stages * f64::from(ir.substeps)
}

#[test]
fn every_example_matches_the_reference_after_50_and_100_steps() {
    let mut checked = 0;
    for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/effects")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("ron") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let effect = compile_file(&path);
        let gpu = gpu();
        let mut gsim = EffectInstance::new(&gpu, effect.clone()).expect("GPU sim");
        let mut csim = ReferenceSim::new(&effect.ir);
        let mut seen_alive = false;
        for steps in [50u64, 100] {
            gsim.run(50, |_| {}).unwrap();
            csim.run(50);
            let (gt, ct) = (gsim.totals().unwrap(), csim.totals());
            assert_eq!(gt, ct, "{name}: totals differ after {steps} steps");
            let (g, c) = (gsim.records().unwrap(), csim.records());
            seen_alive |= !c.is_empty();
            compare_at(
                &name,
                steps,
                effect.ir.flock.is_some(),
                curved_colliders(&effect.ir),
                roundings_per_step(&effect.ir),
                &g,
                &c,
            );
        }
        assert!(seen_alive, "{name}: nothing alive to compare");
        checked += 1;
    }
    assert!(checked >= 6, "expected the six examples, checked {checked}");
}
