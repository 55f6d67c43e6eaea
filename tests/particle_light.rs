//! Light from particles (`render.light`) on llvmpipe: the lights the GPU picks (each bucket's
//! brightest visible particle, slot mod count) are the ones the f64 pick finds among the
//! particles read back, with their drawn colours; a watch brings them back without waiting;
//! an effect that gives off light keeps its particles' state.

mod common;

use common::*;
use glam::DVec3;
use plume::compiler::lights::LightSource;
use plume::runtime::oracle::{records_by_slot, sprites};
use plume::runtime::{Camera, Effect};

/// 500 particles of random hue and opacity in a cloud, fading over a life of 1 to 3 s; the
/// brightest of each of 6 buckets gives off light.
const SOURCE: &str = r#"Effect(
    name: "light-probe",
    capacity: 600,
    seed: 3,
    emitters: [Emitter(burst: 500, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 2.0),
                       velocity: Radial(speed: (0.0, 1.0)), lifetime: Some((1.0, 3.0)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0)), (1.0, (1.0, 1.0, 1.0, 0.0))],
                   color_by: Some("hsv(rand(0), 0.9, 0.5 + 0.5 * rand(1))"),
                   alpha_by: Some("0.2 + 0.8 * rand(2)"),
                   light: Some(ParticleLight(count: 6, intensity: 2.0, range: 3.5))),
)"#;

/// The f64 pick over the particles read back: each slot's position and drawn colour (the
/// reference drawing's, from the record), picked as `ParticleLight::pick` picks.
fn f64_lights(sim: &Effect) -> Vec<(DVec3, DVec3)> {
    let ir = &sim.compiled().ir;
    let camera = Camera::from_effect(&ir.camera, 1.0);
    let slots: Vec<Option<(DVec3, [f64; 4])>> = records_by_slot(sim)
        .unwrap()
        .into_iter()
        .map(|r| {
            r.map(|r| {
                let drawn = sprites(std::slice::from_ref(&r), ir, &camera, false)[0];
                (r.position, drawn.color.map(f64::from))
            })
        })
        .collect();
    ir.render.light.unwrap().pick(&slots)
}

#[test]
fn the_gpu_picks_each_buckets_brightest_particle_as_the_f64_pick_does() {
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, compile(SOURCE)).unwrap();
    let probe = sim.particle_lights().unwrap();
    for steps in [1, 40, 90] {
        sim.run(steps, |_| {}).unwrap();
        let got = probe.read(&sim).unwrap();
        let want = f64_lights(&sim);
        assert_eq!(got.len(), want.len(), "after {steps} more steps");
        assert_eq!(got.len(), 6);
        // Brightest first in both; positions as the f32 state holds them, colours as the
        // drawn sprite's f32 colour times the intensity.
        for (g, (x, c)) in got.iter().zip(&want) {
            let LightSource::Point {
                position,
                color,
                range,
            } = *g
            else {
                panic!("a particle's light is a point light, got {g:?}")
            };
            assert!((position - *x).length() < 1e-5, "{position} vs {x}");
            assert!(
                (color - *c * 2.0).length() < 1e-4,
                "{color} vs {}",
                *c * 2.0
            );
            assert_eq!(range, 3.5);
        }
    }
}

#[test]
fn a_watch_brings_the_lights_back_without_waiting() {
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, compile(SOURCE)).unwrap();
    sim.run(5, |_| {}).unwrap();
    let probe = sim.particle_lights().unwrap();
    let mut seen = None;
    for _ in 0..20 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(lights) = probe.watch(&sim, &mut encoder).unwrap() {
            seen = Some(lights);
            break;
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
    let lights = seen.expect("a reading came back within 20 frames");
    assert_eq!(lights, probe.read(&sim).unwrap());
}

#[test]
fn giving_off_light_keeps_the_particles_state() {
    // Sparks in closed form would be stateless; their light is picked from the particle
    // buffers, so the state pass keeps them.
    let source = r#"Effect(name: "sparks", capacity: 100,
        emitters: [Emitter(burst: 100, shape: Point((0.0, 0.0, 0.0)), velocity: Radial(speed: (1.0, 2.0)))],
        forces: [Gravity((0.0, -9.81, 0.0))],
        integrator: Exact,
        render: Render(light: Some(ParticleLight())))"#;
    let ir = compile(source).ir;
    assert!(ir.stateless.is_none());
    assert!(
        ir.state_reason.contains("render.light"),
        "{}",
        ir.state_reason
    );
}
