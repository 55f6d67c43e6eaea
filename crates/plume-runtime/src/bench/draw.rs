//! `plume bench --render`: the draw of the effect's own picture at N particles, timed every way
//! it can be drawn (blending off, vertices only, one triangle a sprite, hidden quads against a
//! compacted list, the compute renderer stage by stage, into an HDR image to glow, stateless).

use plume_compiler::schema::State;
use plume_compiler::{compile_effect, EffectSpec};

use crate::bench::effect_copy::draw_copy;
use crate::bench::timer::PassTimer;
use crate::device::gpu::Gpu;
use crate::draw::raster::{DeadSlots, DrawOptions};
use crate::draw::renderer::EffectRenderer;
use crate::draw::splat::{ComputeOffscreen, STAGES};
use crate::error::RuntimeError;
use crate::outputs::offscreen::Offscreen;
use crate::outputs::scene::Scene;
use crate::sim::effect::Effect as RunningEffect;
use crate::sort::radix::SortAlgorithm;

/// The draw's figures at one image size, in seconds per frame: each the median of
/// [`DRAW_REPEATS`] frames, timed by GPU timestamps around the render pass alone (the wall
/// clock of the whole submission on adapters without timestamps).
#[derive(Clone, Debug, PartialEq)]
pub struct DrawTimes {
    /// Live particles drawn: the effect's own scene scaled to N
    /// ([`crate::bench::effect_copy::draw_copy`]).
    pub particles: u64,
    /// Steps run before drawing.
    pub steps: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The draw as the effect asks for it (its blending, its sizes), one instance per slot
    /// (free slots hidden, for an unsorted stateful effect; see `compacted` for the default).
    pub draw: f64,
    /// The same draw with blending off (each fragment replaces the pixel): blending's share.
    pub opaque: f64,
    /// Every sprite of size 0, hidden by the vertex shader: the vertex work alone, no pixels.
    pub vertex_only: f64,
    /// The compute work a frame records before the draw: depth keys, the radix sort and the
    /// indirect draw's count (sorted effects only).
    pub prepare: Option<f64>,
    /// A stateful, unsorted effect drawn through a compacted list of its live slots instead
    /// of hiding the free ones: (the list's compute passes, its draw).
    pub compacted: Option<(f64, f64)>,
    /// The same draw with one triangle per sprite instead of a quad (3 vertices and 1
    /// primitive instead of 4 and 2; 30% more area).
    pub triangle: f64,
    /// The compute renderer of the same image ([`ComputeOffscreen`]): its one compute pass (the frame
    /// preparation, a sort when the effect sorts, excluded as for the draw), and the (tile,
    /// sprite) entries it sorted; None for sprites it cannot draw (oriented ones).
    pub compute: Option<(f64, u64)>,
    /// The compute renderer's stages timed one by one (each the median of [`DRAW_REPEATS`]).
    pub compute_stages: Vec<(&'static str, f64)>,
    /// The same N particles of a stateless copy of the effect, drawn from the closed form in
    /// the vertex shader, when the effect can be stateless.
    pub stateless: Option<f64>,
    /// For a glowing effect (`render.glow`): (the same draw into the HDR image instead of
    /// RGBA8, the two blur passes that bloom it).
    pub glow: Option<(f64, f64)>,
    /// For particles that give off light (`render.light`): the two kernels that pick the
    /// lights, in one compute pass (their readback of a few bytes excluded).
    pub light: Option<f64>,
}

/// Frames timed per draw figure (the median is reported).
pub const DRAW_REPEATS: usize = 5;

/// Times the draws (see [`DrawTimes`]) of the effect's scene with about `particles` alive in
/// `slots` at `width` x `height` from the effect's camera.
pub(crate) fn time_draws(
    gpu: &Gpu,
    timer: &PassTimer<'_>,
    effect: &EffectSpec,
    (particles, slots): (u32, u32),
    (width, height): (u32, u32),
) -> Result<DrawTimes, RuntimeError> {
    let (scene, steps) = draw_copy(effect, particles, slots);
    let compile = |state| {
        let mut e = scene.clone();
        e.state = state;
        compile_effect(&e, "").map_err(|e| RuntimeError::Output(e.to_string()))
    };
    // The stateful copy is measured in full; a stateless one (when the effect allows it) is
    // drawn from its closed form beside it.
    let mut sim = RunningEffect::new(gpu, compile(State::Stateful)?)?;
    sim.run(steps, |_| {})?;
    let sim = &sim;
    let target = Offscreen::new(gpu, width, height)?;
    let camera = target.effect_camera(sim);
    let median = |times: &mut Vec<f64>| {
        times.sort_by(f64::total_cmp);
        times[times.len() / 2]
    };
    // Warms the draw up (pipeline creation, first use of the buffers), then times it.
    let time = |sim: &RunningEffect, renderer: &EffectRenderer| {
        target.render(sim, renderer, &camera)?;
        let mut times = Vec::with_capacity(DRAW_REPEATS);
        for _ in 0..DRAW_REPEATS {
            times.push(timer.time_render(|encoder, timestamps| {
                target.record(encoder, sim, renderer, &camera, timestamps)
            })?);
        }
        Ok::<f64, RuntimeError>(median(&mut times))
    };
    // The draw as a host gets it by default; for an unsorted stateful effect that is the
    // compacted list, and `draw` below is the other way, every slot with free ones hidden.
    let hidden_slots = DrawOptions {
        dead_slots: DeadSlots::Hidden,
        ..Default::default()
    };
    // A light that casts a shadow is blocked by the shadow map of the effect's scene meshes,
    // as `plume render` draws it: bound to the draw and the compute renderer.
    let shadow = shadow_of_scene(gpu, sim, target.target().color_format, (width, height))?;
    let mut shadowed = sim.renderer_with(&target.target(), &hidden_slots)?;
    if let Some((lights, scene)) = &shadow {
        shadowed.set_lights(lights);
        shadowed.set_shadow_map(scene_map(scene))?;
    }
    let draw = time(sim, &shadowed)?;
    let opaque = time(
        sim,
        &sim.renderer_with(
            &target.target(),
            &DrawOptions {
                blend: Some(wgpu::BlendState::REPLACE),
                ..hidden_slots
            },
        )?,
    )?;
    let mut hidden = sim.renderer_with(&target.target(), &hidden_slots)?;
    hidden.set_size_scale(0.0);
    let vertex_only = time(sim, &hidden)?;
    let triangle = time(
        sim,
        &sim.renderer_with(
            &target.target(),
            &DrawOptions {
                primitive: plume_compiler::wgsl::draw::Primitive::Triangle,
                ..hidden_slots
            },
        )?,
    )?;
    // An effect the compute renderer does not draw, or not at this size on this adapter: no compute line.
    let made = match ComputeOffscreen::why_not(&[&sim.compiled().ir]).is_none() {
        true => match ComputeOffscreen::new(sim, width, height) {
            Err(RuntimeError::Unsupported(_)) => None,
            made => Some(made?),
        },
        false => None,
    };
    let (splat, compute_stages) = if let Some(mut splat) = made {
        if let Some((lights, scene)) = &shadow {
            splat.set_lights(lights);
            splat.set_shadow_map(scene_map(scene))?;
        }
        // Draws once, growing the entry list to what the frame needs, then times the pass.
        splat.render(sim, &camera)?;
        let mut times = Vec::with_capacity(DRAW_REPEATS);
        for _ in 0..DRAW_REPEATS {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            splat.prepare(&mut encoder, sim, &camera)?;
            gpu.queue.submit([encoder.finish()]);
            times.push(timer.time(|pass| {
                splat.record(pass)?;
                if let Some(glow) = splat.glow_passes() {
                    glow.record_into(pass);
                }
                Ok(())
            })?);
        }
        // Stage by stage, in order, each in its own timed pass: repeating one stage alone is
        // not the same work (the scan works in place).
        let mut per_stage = vec![Vec::with_capacity(DRAW_REPEATS); STAGES.len()];
        for _ in 0..DRAW_REPEATS {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            splat.prepare(&mut encoder, sim, &camera)?;
            gpu.queue.submit([encoder.finish()]);
            for (times, stage) in per_stage.iter_mut().zip(STAGES) {
                times.push(timer.time(|pass| splat.record_stage(pass, stage))?);
            }
        }
        let mut stages: Vec<(&'static str, f64)> = STAGES
            .into_iter()
            .zip(per_stage.iter_mut())
            .map(|(stage, times)| (stage, median(times)))
            .collect();
        // A glowing effect's bloom: the same two blur passes as the raster draw's (the copy of
        // the HDR image into the glow's texture before them is not timed).
        if let Some(glow) = splat.glow_passes() {
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| {
                    timer.time(|pass| {
                        glow.record_into(pass);
                        Ok(())
                    })
                })
                .collect::<Result<_, _>>()?;
            stages.push(("glow", median(&mut times)));
        }
        (Some((median(&mut times), splat.entries())), stages)
    } else {
        (None, Vec::new())
    };
    let prepare = match sim.compiled().ir.sort {
        true => {
            sim.groups()[0].time_sort(timer, SortAlgorithm::Radix)?;
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| sim.groups()[0].time_sort(timer, SortAlgorithm::Radix))
                .collect::<Result<_, _>>()?;
            Some(median(&mut times))
        }
        false => None,
    };
    // Hidden quads against a compacted list (stateful, unsorted effects): the list's compute
    // passes, then its draw.
    let compacted = match !sim.compiled().ir.sort {
        true => {
            let renderer = sim.renderer_with(
                &target.target(),
                &DrawOptions {
                    dead_slots: DeadSlots::Compacted,
                    ..Default::default()
                },
            )?;
            let draw = time(sim, &renderer)?;
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| timer.time(|pass| renderer.record_instance_counts(pass)))
                .collect::<Result<_, _>>()?;
            Some((median(&mut times), draw))
        }
        false => None,
    };
    let glow = match &sim.compiled().ir.render.glow {
        Some(g) => {
            let glowing = Offscreen::with_glow(gpu, width, height, Some(g))?;
            let renderer = sim.renderer_with(&glowing.target(), &hidden_slots)?;
            glowing.render(sim, &renderer, &camera)?;
            let mut draws = Vec::with_capacity(DRAW_REPEATS);
            let mut blurs = Vec::with_capacity(DRAW_REPEATS);
            let passes = glowing.glow().expect("a glowing target has its passes");
            for _ in 0..DRAW_REPEATS {
                draws.push(timer.time_render(|encoder, timestamps| {
                    glowing.record(encoder, sim, &renderer, &camera, timestamps)
                })?);
                blurs.push(timer.time(|pass| {
                    passes.record_into(pass);
                    Ok(())
                })?);
            }
            Some((median(&mut draws), median(&mut blurs)))
        }
        None => None,
    };
    let light = match sim.compiled().ir.render.light {
        Some(_) => {
            let lights = sim.particle_lights()?;
            lights.read(sim)?;
            let mut times: Vec<f64> = (0..DRAW_REPEATS)
                .map(|_| {
                    timer.time(|pass| {
                        lights.dispatch(pass);
                        Ok(())
                    })
                })
                .collect::<Result<_, _>>()?;
            Some(median(&mut times))
        }
        None => None,
    };
    let stateless = match compile(State::Auto)? {
        c if c.ir.stateless.is_some() => {
            let mut s = RunningEffect::new(gpu, c)?;
            s.run(steps, |_| {})?;
            Some(time(&s, &s.renderer(&target.target())?)?)
        }
        _ => None,
    };
    Ok(DrawTimes {
        particles: sim.totals()?.alive,
        steps,
        width,
        height,
        draw,
        opaque,
        vertex_only,
        prepare,
        compacted,
        triangle,
        compute: splat,
        compute_stages,
        stateless,
        glow,
        light,
    })
}

/// The effect's lights with the shadow its scene meshes cast, and the scene holding the map,
/// when a light casts one and the effect names meshes (said on stderr); None otherwise.
fn shadow_of_scene(
    gpu: &Gpu,
    sim: &RunningEffect,
    color_format: wgpu::TextureFormat,
    size: (u32, u32),
) -> Result<Option<(plume_compiler::lights::Lights, Scene)>, RuntimeError> {
    let ir = &sim.compiled().ir;
    if ir.lights.shadow.is_none() {
        return Ok(None);
    }
    let Some(mut scene) = Scene::new(gpu, &ir.scene_triangles(), color_format, size)? else {
        return Ok(None);
    };
    let lights = scene.cast_shadow(&ir.lights)?;
    eprintln!("draw: shadowed by the map of the effect's scene meshes");
    Ok(Some((lights, scene)))
}

/// The shadow map of a scene that has cast one.
fn scene_map(scene: &Scene) -> &wgpu::Texture {
    scene
        .shadow_map()
        .expect("shadow_of_scene returns scenes that cast a shadow")
        .texture()
}
