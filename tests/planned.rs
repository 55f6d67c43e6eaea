//! Steps of several effects in one compute pass (`Effect::plan_steps` and
//! `Effect::record_planned`) give each effect exactly what `Effect::advance` gives it: the same
//! particles, byte for byte, frame after frame, with a world-space placement that moves and
//! with bursts; an effect with events refuses to plan, and says what to use instead.

mod common;

use common::*;
use plume::compiler::bursts::Burst;
use plume::compiler::placement::Placement;
use plume::runtime::Effect;
use plume::CompileOptions;

fn effect(gpu: &plume::runtime::Gpu, name: &str, options: &CompileOptions) -> Effect {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("effects")
        .join(format!("{name}.ron"));
    Effect::from_file(gpu, &path, options).unwrap()
}

#[test]
fn planned_steps_in_a_shared_pass_match_advance_byte_for_byte() {
    let gpu = gpu();
    let placed = CompileOptions {
        placed: true,
        bursts: true,
        ..Default::default()
    };
    // Each effect twice: one advanced alone, one planned into a pass shared with the others.
    let names = ["fountain", "snow", "tornado"];
    let mut alone: Vec<Effect> = names.iter().map(|n| effect(&gpu, n, &placed)).collect();
    let mut shared: Vec<Effect> = names.iter().map(|n| effect(&gpu, n, &placed)).collect();
    for frame in 0..12u32 {
        // A placement that moves each frame, and a burst now and then.
        let at = Placement::from_cols(
            glam::Mat4::from_translation(glam::Vec3::new(frame as f32 * 0.3, 0.0, 0.0))
                .to_cols_array(),
        )
        .unwrap();
        let steps = 1 + u64::from(frame % 3);
        for e in alone.iter_mut().chain(shared.iter_mut()) {
            e.set_placement(at);
            if frame % 4 == 1 {
                e.burst(0, Burst::new(0, 50).at([0.0, 1.0, 0.0])).unwrap();
            }
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for e in &mut alone {
            e.advance(&mut encoder, steps).unwrap();
        }
        let plans: Vec<_> = shared
            .iter_mut()
            .map(|e| e.plan_steps(&mut encoder, steps).unwrap())
            .collect();
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            for (e, plan) in shared.iter().zip(&plans) {
                assert_eq!(plan.steps() as u64, steps);
                e.record_planned(&mut pass, plan).unwrap();
            }
        }
        gpu.queue.submit([encoder.finish()]);
    }
    for ((a, b), name) in alone.iter().zip(&shared).zip(names) {
        let (ra, rb) = (a.records().unwrap(), b.records().unwrap());
        assert!(!ra.is_empty(), "{name}: particles alive");
        assert_eq!(ra, rb, "{name}: planned steps differ from advance");
        assert_eq!(a.steps_done(), b.steps_done());
    }
}

#[test]
fn an_effect_with_events_does_not_plan_and_says_to_advance() {
    let gpu = gpu();
    let mut fireworks = effect(&gpu, "fireworks", &CompileOptions::default());
    assert!(!fireworks.plans_steps());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let err = fireworks
        .plan_steps(&mut encoder, 1)
        .unwrap_err()
        .to_string();
    assert!(err.contains("Effect::advance"), "{err}");
    let mut fountain = effect(&gpu, "fountain", &CompileOptions::default());
    let err = fountain
        .plan_steps(&mut encoder, 257)
        .unwrap_err()
        .to_string();
    assert!(err.contains("256"), "{err}");
}
