//! Shared helpers of the GPU tests: one GPU for the whole test binary (wgpu's GL backend on
//! llvmpipe where there is no GPU), and runners for the GPU and the CPU reference.
#![allow(dead_code)]

pub mod compare;
pub mod effect_gen;
pub mod meshes;

use std::sync::{Mutex, MutexGuard, OnceLock};

use plume::compiler::reference::{ParticleRecord, ReferenceSim, Totals};
use plume::runtime::{Effect, Gpu, GpuChoice};
use plume::{compile_str, CompileOptions, CompiledEffect};

/// The test binary's GPU. Tests never skip: with no adapter they fail with the runtime's
/// message, which says how to install a software driver.
pub fn gpu() -> MutexGuard<'static, Gpu> {
    static GPU: OnceLock<Result<Mutex<Gpu>, String>> = OnceLock::new();
    match GPU.get_or_init(|| {
        Gpu::new(&GpuChoice::default())
            .map(Mutex::new)
            .map_err(|e| e.to_string())
    }) {
        Ok(m) => m.lock().unwrap_or_else(|p| p.into_inner()),
        Err(e) => panic!("{e}"),
    }
}

/// Compiles `source` or fails the test with the rendered diagnostics.
pub fn compile(source: &str) -> CompiledEffect {
    compile_str(source, &CompileOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render("test.ron", source)))
}

/// Reads and compiles the effect file at `path` (its texture resolved from its directory), or
/// fails the test with the rendered diagnostics.
pub fn compile_file(path: &std::path::Path) -> CompiledEffect {
    let source = std::fs::read_to_string(path).unwrap();
    let options = CompileOptions {
        base_dir: path.parent().map(|p| p.to_path_buf()),
        ..Default::default()
    };
    compile_str(&source, &options)
        .unwrap_or_else(|e| panic!("{}", e.render(&path.display().to_string(), &source)))
}

/// Whether the effect file at `path` has groups or events (an effect graph).
pub fn is_graph_file(path: &std::path::Path) -> bool {
    let source = std::fs::read_to_string(path).unwrap();
    plume::parse(&source)
        .map(|e| plume::compiler::graph::graph_field(&e).is_some())
        .unwrap_or(false)
}

/// Reads and compiles the effect graph at `path`, or fails the test with the diagnostics.
pub fn compile_graph_file(path: &std::path::Path) -> plume::compiler::graph::CompiledGraph {
    let source = std::fs::read_to_string(path).unwrap();
    let options = CompileOptions {
        base_dir: path.parent().map(|p| p.to_path_buf()),
        ..Default::default()
    };
    plume::compiler::graph::compile_graph_str(&source, &options)
        .unwrap_or_else(|e| panic!("{}", e.render(&path.display().to_string(), &source)))
}

/// `effect` on `gpu` with at most `chunk_slots` particles per buffer (to exercise the split
/// on small effects).
pub fn split(gpu: &Gpu, effect: CompiledEffect, chunk_slots: Option<u64>) -> Effect {
    let name = effect.ir.name.clone();
    let graph = plume::compiler::graph::CompiledGraph::single(&name, effect);
    Effect::with_chunk_slots(gpu, graph, chunk_slots).expect("GPU sim")
}

/// The GPU draw of `sim` from its camera into a `side` x `side` image, and the CPU-fed
/// reference drawing of the same particles (colour, size, half axes and frames in f64).
pub fn draw_and_reference(sim: &Effect, side: u32) -> (Vec<u8>, Vec<u8>) {
    draw_group_and_reference(sim, 0, side)
}

/// [`draw_and_reference`] of group `g` of `sim` alone, from the effect's camera.
pub fn draw_group_and_reference(sim: &Effect, g: usize, side: u32) -> (Vec<u8>, Vec<u8>) {
    use plume::runtime::oracle::{group_renderer, sprites_at, ReferenceRenderer};
    use plume::runtime::outputs::Offscreen;
    let ir = &sim.group_compiled(g).unwrap().ir;
    // The group's own camera (the top-level one's, for group 0) on a square image.
    let camera = plume::runtime::Camera::from_effect(&ir.camera, 1.0);
    let target = Offscreen::new(sim.gpu(), side, side).unwrap();
    let renderer = group_renderer(sim, g, &target.target()).unwrap();
    let gpu_img = target.render(sim, &renderer, &camera).unwrap();
    let reference = ReferenceRenderer::new(sim.gpu(), side, side, ir).unwrap();
    let records = sim.group_records(g).unwrap();
    // The frame's time, as the draw's `t` reads it.
    let time = sim.steps_done() as f64 * ir.dt;
    let cpu_img = match ir.render.ribbon {
        // Ribbons joining particles: the chains of the GPU's table, placed in f64.
        Some(_) => {
            let table = plume::runtime::oracle::read_ribbon_table(sim, g)
                .unwrap()
                .into_iter()
                .map(|e| e.map(|(id, link, _)| (id, link)))
                .collect();
            let ribbons =
                plume::runtime::oracle::ribbon_strips(&records, &table, ir, (&camera, time));
            reference.draw_with_strips(&ribbons, &[], &camera)
        }
        // Trails (the top-level group's, which read_trails reads) before the sprites.
        None if ir.render.trail.is_some() && g == 0 => {
            let trails = plume::runtime::oracle::read_trails(sim).unwrap();
            let ribbons = plume::runtime::oracle::trail_strips(&records, &trails, ir, camera.view);
            reference.draw_with_strips(
                &ribbons,
                &sprites_at(&records, ir, &camera, false, time),
                &camera,
            )
        }
        // Mesh particles: each sprite's mesh placed and lit in f64, in the draw's order.
        None if ir.render.mesh.is_some() => {
            let sprites = sprites_at(&records, ir, &camera, ir.sort, time);
            let triangles = plume::runtime::oracle::mesh_triangles(&sprites, ir, &camera);
            reference.draw_with_strips(&triangles, &[], &camera)
        }
        None => reference.draw(&sprites_at(&records, ir, &camera, false, time), &camera),
    }
    .unwrap();
    (gpu_img, cpu_img)
}

/// Per-channel absolute differences of two images: (mean, largest, how many exceed `over`).
pub fn differences(a: &[u8], b: &[u8], over: u8) -> (f64, u8, usize) {
    assert_eq!(a.len(), b.len());
    let mut sum = 0u64;
    let (mut max, mut count) = (0u8, 0usize);
    for (x, y) in a.iter().zip(b) {
        let d = x.abs_diff(*y);
        sum += u64::from(d);
        max = max.max(d);
        count += usize::from(d > over);
    }
    (sum as f64 / a.len() as f64, max, count)
}

/// Runs `steps` on the GPU; returns totals and live particles.
pub fn run_gpu(effect: &CompiledEffect, steps: u64) -> (Totals, Vec<ParticleRecord>) {
    let gpu = gpu();
    let mut sim = Effect::new(&gpu, effect.clone()).expect("GPU sim");
    sim.run(steps, |_| {}).expect("GPU run");
    (
        sim.totals().expect("totals"),
        sim.records().expect("records"),
    )
}

/// Runs one step of `src` (an effect of step `dt`) on the GPU and in the reference and returns
/// (spawn position, velocity) of every particle, checking that they agree: every spawn draw
/// is an integer hash, bit-identical on both sides, and a choice between faces or triangles
/// is made on integers, so only the f32 arithmetic of the point differs (a few ulps).
pub fn spawn_states(src: &str, dt: f64) -> Vec<(glam::DVec3, glam::DVec3)> {
    spawn_states_within(src, dt, 16.0 * U32)
}

/// [`spawn_states`], the GPU within `tolerance` · (1 + |x|) of the reference (for spawns that
/// take sines and cosines, whose f32 error is the driver's: see `TRIG` in tests/spawning.rs).
pub fn spawn_states_within(src: &str, dt: f64, tolerance: f64) -> Vec<(glam::DVec3, glam::DVec3)> {
    let e = compile(src);
    let (_, gpu) = run_gpu(&e, 1);
    let (_, cpu) = run_cpu(&e, 1);
    assert_eq!(gpu.len(), cpu.len());
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!(g.id, c.id);
        assert!(
            (g.position - c.position).length() <= tolerance * (1.0 + c.position.length())
                && (g.velocity - c.velocity).length() <= tolerance * (1.0 + c.velocity.length()),
            "particle {}: at {:?} moving {:?} on the GPU, at {:?} moving {:?} in f64",
            g.id,
            g.position,
            g.velocity,
            c.position,
            c.velocity
        );
    }
    cpu.iter()
        .map(|c| (c.position - c.velocity * dt, c.velocity))
        .collect()
}

/// Runs `steps` on the CPU reference.
pub fn run_cpu(effect: &CompiledEffect, steps: u64) -> (Totals, Vec<ParticleRecord>) {
    let mut sim = ReferenceSim::new(&effect.ir);
    sim.run(steps);
    (sim.totals(), sim.records())
}

/// Runs `steps` on the GPU and the reference, asserts equal totals and live ids, and returns
/// the largest position distance over (1 + |x|).
pub fn worst_gpu_distance(effect: &CompiledEffect, steps: u64) -> f64 {
    let (gt, gpu) = run_gpu(effect, steps);
    let (ct, cpu) = run_cpu(effect, steps);
    assert_eq!(gt, ct, "totals differ after {steps} steps");
    let mut worst: f64 = 0.0;
    for (g, c) in gpu.iter().zip(&cpu) {
        assert_eq!(g.id, c.id, "live ids differ after {steps} steps");
        worst = worst.max((g.position - c.position).length() / (1.0 + c.position.length()));
    }
    worst
}

/// f32 unit roundoff.
pub const U32: f64 = 1.0 / 16_777_216.0;

/// Asserts that `drawn` (the live particles in draw order) runs back to front from `effect`'s
/// camera as the depth sort promises: a particle comes before a farther one only when their
/// depths lie within one step of the 16-bit keys, (farthest − nearest live depth) / 65,533
/// (plume_runtime::depth_quantise), plus the f32 rounding of the GPU's depth (1e-5 relative).
pub fn assert_back_to_front(effect: &CompiledEffect, drawn: &[ParticleRecord]) {
    let cam = effect.ir.camera;
    let forward = (cam.target - cam.eye).normalize();
    let depth = |r: &ParticleRecord| (r.position - cam.eye).dot(forward);
    let (near, far) = drawn
        .iter()
        .map(depth)
        .fold((f64::MAX, f64::MIN), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let step = (far - near).max(0.0) / 65533.0;
    for w in drawn.windows(2) {
        let (a, b) = (depth(&w[0]), depth(&w[1]));
        assert!(
            a >= b - step - 1e-5 * a.abs().max(1.0),
            "particle {} at depth {a} drawn before {} at {b} (a key step is {step})",
            w[0].id,
            w[1].id
        );
    }
}

/// `sim` drawn by the compute renderer from the effect's camera, `side` pixels square.
pub fn splat_image(sim: &Effect, side: u32) -> Vec<u8> {
    let mut splat = plume::runtime::outputs::ComputeOffscreen::new(sim, side, side)
        .expect("the compute renderer draws it");
    let camera = plume::runtime::Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let img = splat.render(sim, &camera).unwrap();
    assert!(splat.entries_are_complete().unwrap(), "splat entries lost");
    img
}

/// The largest difference between two `width`-wide RGBA images' means over `block` x `block`
/// squares, over the squares and the three colour channels: a pixel that flips at a sprite's
/// edge moves a 4 x 4 square's mean by a sixteenth of its difference; a misplaced, missing or
/// miscoloured sprite moves the squares it covers by all of it.
pub fn local_difference(a: &[u8], b: &[u8], width: u32, block: u32) -> f64 {
    assert_eq!(a.len(), b.len());
    let height = (a.len() / 4) as u32 / width;
    let mut worst = 0.0f64;
    for by in (0..height).step_by(block as usize) {
        for bx in (0..width).step_by(block as usize) {
            for c in 0..3 {
                let (mut sa, mut sb, mut n) = (0i64, 0i64, 0i64);
                for y in by..(by + block).min(height) {
                    for x in bx..(bx + block).min(width) {
                        let k = 4 * (y * width + x) as usize + c;
                        sa += i64::from(a[k]);
                        sb += i64::from(b[k]);
                        n += 1;
                    }
                }
                worst = worst.max((sa - sb).abs() as f64 / n as f64);
            }
        }
    }
    worst
}

/// Asserts that `sim`'s raster draw at `side` pixels agrees with the CPU-fed reference drawing
/// (a channel a step apart where rounding crosses a half, a rim pixel's coverage a few steps
/// where sizes differ by f32 rounding: a mean difference under 0.05 and at most one value in
/// 1,000 more than 4 apart) and, when `splat`, with the compute renderer (at most one in 1,000
/// more than 2 apart); returns the raster image.
pub fn assert_draws_agree(sim: &Effect, side: u32, splat: bool, what: &str) -> Vec<u8> {
    let (gpu_img, cpu_img) = draw_and_reference(sim, side);
    let (mean, max, over) = differences(&gpu_img, &cpu_img, 4);
    assert!(
        mean < 0.05 && over * 1000 < gpu_img.len(),
        "{what}: GPU and CPU-fed draws differ: mean {mean}, max {max}, {over} over 4"
    );
    if splat {
        let splat_img = splat_image(sim, side);
        let (mean, max, over) = differences(&gpu_img, &splat_img, 2);
        assert!(
            mean < 0.05 && over * 1000 < gpu_img.len(),
            "{what}: splat and raster differ: mean {mean}, max {max}, {over} over 2"
        );
    }
    gpu_img
}
