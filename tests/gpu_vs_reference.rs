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

use common::compare::{compare_at, curved_colliders, roundings_per_step};
use common::*;
use plume::compiler::reference::ReferenceSim;
use plume::runtime::Effect;

#[test]
fn every_example_matches_the_reference_after_50_and_100_steps() {
    let mut checked = 0;
    for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/effects")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("ron") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if is_graph_file(&path) {
            // Effects with groups and events: tests/events.rs, group by group.
            continue;
        }
        let effect = compile_file(&path);
        let gpu = gpu();
        let mut gsim = Effect::new(&gpu, effect.clone()).expect("GPU sim");
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
                effect.layout.half_motion.then_some(effect.ir.dt),
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
