//! The comparison of GPU particles against the f64 reference, with the tolerance that
//! tests/gpu_vs_reference.rs justifies (four f32 roundings a step per force evaluation,
//! added up linearly).

use super::U32;

/// Whether the effect has a curved collider (a sphere, a height field or a mesh, whose field
/// curves round its edges). Particles that land
/// near a point where the surface turns away in every direction (a sphere's apex, a ridge's
/// crest) slide off to the side that rounding picks: f32 and f64 then part ways by up to the
/// distance travelled since (rock_fountain.ron at step 100: 90% of particles within 3.9e-7
/// (1 + |x|), the farthest 2.9e-2). Such effects need 95% of particles within the bound; each
/// contact's own accuracy is tested in tests/colliders.rs.
pub fn curved_colliders(ir: &plume::compiler::EffectIr) -> bool {
    use plume::compiler::colliders::Surface;
    ir.colliders.iter().any(|c| {
        matches!(
            c.surface,
            Surface::Sphere(_) | Surface::HeightField(_) | Surface::Mesh(_)
        )
    })
}

/// `half_motion_dt`: the effect's dt where its layout stores the motion in 16-bit floats
/// (`Layout::half_motion`). The oracle rounds as the GPU stores, but where the f32 and f64
/// values fall on either side of a half's rounding boundary (about 1 rounding in 2,000: f32's
/// 6e-8 relative error against a half's 4.9e-4 spacing), the two stored velocities differ by
/// one spacing, 2^-10 of the velocity at most, and the positions then part by that much a
/// second. The bound adds two such flips in flight (2^-9 (1 + |v|) of velocity, and that times
/// the run's duration of position) to the f32 bound.
// Each argument is one fact about the effect that the bound depends on, named at the call.
#[allow(clippy::too_many_arguments)]
pub fn compare_at(
    name: &str,
    steps: u64,
    flocks: bool,
    curved: bool,
    half_motion_dt: Option<f64>,
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
        // Tints (tint.rs): a palette pick is the same integer draw on both sides; a stored
        // tint is 8-bit on both, and the f32 and f64 products it rounds may fall either side
        // of a half step, or on it (rounded half to even on the GPU, half up here): one step
        // apart at most.
        assert!(
            (g.tint - c.tint).abs().max_element() <= 1.0 / 255.0 + 1e-9,
            "{name}: particle {} tint: gpu {:?} cpu {:?}",
            g.id,
            g.tint,
            c.tint
        );
        let (flip_v, flip_x) = match half_motion_dt {
            Some(dt) => {
                let dv = (1.0 + c.velocity.length()) / 512.0;
                (dv, dv * dt * steps as f64)
            }
            None => (0.0, 0.0),
        };
        let dx = ((g.position - c.position).length() - flip_x).max(0.0);
        let dv = ((g.velocity - c.velocity).length() - flip_v).max(0.0);
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
/// A custom force adds a rounding for each node of its expression to every evaluation:
/// hanabi's force_field port, whose velocity change per frame is turned into an acceleration
/// by dividing by dt, measured 1.2e-5 (1 + |x|) at step 50 in position, over the four-rounding
/// bound (1.2e-5 at 50 steps) and under this one.
pub fn roundings_per_step(ir: &plume::compiler::EffectIr) -> f64 {
    let stages = match ir.integrator {
        plume::Integrator::Midpoint => 2.0,
        plume::Integrator::Rk4 => 4.0,
        _ => 1.0,
    };
    let custom: usize = ir.custom_terms().map(|c| c.expr.size()).sum();
    (4.0 + custom as f64) * stages * f64::from(ir.substeps)
}
