//! Do per-particle substeps beat uniform ones on orbit.ron? An f64 experiment (issue 40's
//! optional part), run before building anything on the GPU:
//!
//! ```sh
//! cargo run --release --example per_particle_substeps
//! ```
//!
//! orbit.ron's first 1,024 particles (its burst: a bar beside an attractor, pushed sideways)
//! are followed for 4 s (240 steps of 1/60 s), each on its own (the attractor is their only
//! force), by Midpoint (two force evaluations a substep; a velocity scheme, so a particle may
//! change its substep from step to step, which Verlet's stored displacement may not):
//!
//! - **uniform**: s substeps for every particle, s = 1 ..= 16;
//! - **per particle**: at the start of each step, each particle takes n = ceil(c · dt · √k)
//!   substeps (1 ..= 64), k its local stiffness, the largest |∂a/∂x| along the three axes by
//!   finite differences: three more force evaluations a step, counted. c sweeps 50 ..= 600 (orbit.ron's k is at most about 1.5 per s², so dt · √k is about 0.02).
//!
//! Each run's error is the largest distance, over particles and steps, from the truth (RK4 with
//! 64 substeps, checked against 32). Its cost is force evaluations per particle-step: the mean
//! over particles (a CPU, or a GPU whose lanes each run their own count), and the mean over
//! groups of 32 consecutive particles of the group's largest (a GPU subgroup runs in lockstep:
//! every lane waits for the lane with the most substeps).

use glam::DVec3;
use plume::compiler::forces::ParticleCtx;
use plume::compiler::reference::spawn::spawn;
use plume::compiler::reference::step::substep;
use plume::compiler::{EffectIr, Integrator};

const PARTICLES: u32 = 1024;
const STEPS: usize = 240;
const LANES: usize = 32;

/// The IR with `integrator` and `substeps`.
fn with(ir: &EffectIr, integrator: Integrator, substeps: u32) -> EffectIr {
    let mut out = ir.clone();
    out.integrator = integrator;
    out.substeps = substeps;
    out
}

/// Positions at the end of every step (step-major), with each particle's substeps each step
/// given by `substeps(x, v)`; returns them and the evaluations each particle spent each step.
fn run(
    ir: &EffectIr,
    integrator: Integrator,
    substeps: &dyn Fn(DVec3, DVec3) -> (u32, u32),
) -> (Vec<Vec<DVec3>>, Vec<Vec<u32>>) {
    let by_count: Vec<EffectIr> = (0..=64).map(|n| with(ir, integrator, n.max(1))).collect();
    let mut states: Vec<(DVec3, DVec3)> = (0..PARTICLES)
        .map(|id| {
            let s = spawn(ir, 0, id, id, 0);
            (s.x, s.v)
        })
        .collect();
    let mut positions = Vec::with_capacity(STEPS);
    let mut costs = Vec::with_capacity(STEPS);
    for step in 0..STEPS {
        let mut xs = Vec::with_capacity(states.len());
        let mut cs = Vec::with_capacity(states.len());
        for (id, (x, v)) in states.iter_mut().enumerate() {
            let (n, probe) = substeps(*x, *v);
            let step_ir = &by_count[n as usize];
            let h = step_ir.h();
            let ctx = ParticleCtx {
                id: id as u32,
                age0: step as f64 * ir.dt,
                t0: step as f64 * ir.dt,
                life: 0.0,
                ..ParticleCtx::default()
            };
            for s in 0..n {
                let t = step as f64 * ir.dt + f64::from(s) * h;
                substep(step_ir, None, None, None, &ctx, x, v, t);
            }
            xs.push(*x);
            cs.push(n * stages(integrator) + probe);
        }
        positions.push(xs);
        costs.push(cs);
    }
    (positions, costs)
}

/// Force evaluations a substep.
fn stages(integrator: Integrator) -> u32 {
    match integrator {
        Integrator::Midpoint => 2,
        Integrator::Rk4 => 4,
        _ => 1,
    }
}

/// The largest distance between the same particle at the same step.
fn error(a: &[Vec<DVec3>], b: &[Vec<DVec3>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(s, t)| s.iter().zip(t).map(|(x, y)| (*x - *y).length()))
        .fold(0.0, f64::max)
}

/// (mean over particle-steps, mean over subgroup-steps of the subgroup's largest).
fn costs(c: &[Vec<u32>]) -> (f64, f64) {
    let count = (c.len() * c[0].len()) as f64;
    let mean = c.iter().flatten().map(|&n| f64::from(n)).sum::<f64>() / count;
    let groups: Vec<f64> = c
        .iter()
        .flat_map(|s| s.chunks(LANES).map(|g| f64::from(*g.iter().max().unwrap())))
        .collect();
    (mean, groups.iter().sum::<f64>() / groups.len() as f64)
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects/orbit.ron");
    let source = std::fs::read_to_string(&path).expect("effects/orbit.ron");
    let options = plume::CompileOptions {
        base_dir: path.parent().map(|p| p.to_path_buf()),
        ..Default::default()
    };
    let compiled = plume::compile_str(&source, &options).expect("orbit.ron compiles");
    let mut ir = compiled.ir;
    ir.accuracy = None;
    let started = std::time::Instant::now();
    let (truth, _) = run(&ir, Integrator::Rk4, &|_, _| (64, 0));
    let (check, _) = run(&ir, Integrator::Rk4, &|_, _| (32, 0));
    println!(
        "truth: RK4 x64, {:.1e} m from RK4 x32 ({PARTICLES} particles, {STEPS} steps, {:.1} s)",
        error(&truth, &check),
        started.elapsed().as_secs_f64()
    );
    println!("scheme                        error (m)   evaluations/step: mean   subgroup of 32");
    for s in [1u32, 2, 3, 4, 6, 8, 12, 16] {
        let (xs, c) = run(&ir, Integrator::Midpoint, &|_, _| (s, 0));
        let (mean, warp) = costs(&c);
        println!(
            "uniform Midpoint x{s:<3}          {:9.2e}   {mean:22.2}   {warp:14.2}",
            error(&xs, &truth)
        );
    }
    // The local stiffness: the largest change of the acceleration per metre along an axis.
    let base = with(&ir, Integrator::Midpoint, 1);
    let stiffness = |x: DVec3, v: DVec3| -> f64 {
        let ctx = ParticleCtx {
            id: 0,
            age0: 0.0,
            t0: 0.0,
            life: 0.0,
            ..ParticleCtx::default()
        };
        let eps = 1e-4;
        let a0 = plume::compiler::reference::step::accel(&base, None, &ctx, x, v, 0.0);
        [DVec3::X, DVec3::Y, DVec3::Z]
            .iter()
            .map(|&u| {
                (plume::compiler::reference::step::accel(&base, None, &ctx, x + u * eps, v, 0.0)
                    - a0)
                    .length()
                    / eps
            })
            .fold(0.0, f64::max)
    };
    for c in [50.0, 75.0, 100.0, 150.0, 200.0, 300.0, 400.0, 600.0] {
        let dt = ir.dt;
        let choose = |x: DVec3, v: DVec3| {
            let n = (c * dt * stiffness(x, v).sqrt()).ceil().clamp(1.0, 64.0) as u32;
            // Three probes (the base acceleration is the scheme's first evaluation).
            (n, 3)
        };
        let (xs, cost) = run(&ir, Integrator::Midpoint, &choose);
        let (mean, warp) = costs(&cost);
        println!(
            "per particle, c = {c:<5}        {:9.2e}   {mean:22.2}   {warp:14.2}",
            error(&xs, &truth)
        );
    }
}
