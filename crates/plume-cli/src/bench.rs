//! `plume bench`: update throughput against a copy kernel moving the same bytes, in one run.

use std::path::PathBuf;
use std::process::ExitCode;

use plume_runtime::bench::{
    bench, bench_graph, bench_sort, BenchOptions, DispatchTime, TimingSource,
};

use crate::load;

/// Options of `plume bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// The effect file (.ron).
    file: PathBuf,
    /// Live particles during the timed steps.
    #[arg(long, default_value_t = 1_000_000)]
    particles: u32,
    /// Timed steps (at most 256, one submission).
    #[arg(long, default_value_t = 100)]
    steps: u32,
    /// Also time drawing all live particles from the GPU buffers at this size (WIDTHxHEIGHT).
    #[arg(long, value_parser = crate::render::parse_size)]
    render: Option<(u32, u32)>,
    /// Fraction of the particle slots alive (0 to 1). Below 1, the draw compares hiding the
    /// free slots in the vertex shader with drawing a compacted list of the live ones.
    #[arg(long, default_value_t = 1.0, value_parser = parse_fraction)]
    occupancy: f64,
    /// Also time the radix sort alone on this many random (key, value) pairs, with every
    /// ranking the adapter runs (subgroup ballots, portable), on 32-bit and 16-bit keys.
    #[arg(long)]
    sort_keys: Option<u32>,
    /// For an effect with groups and events: steps run before timing (to reach a steady
    /// state).
    #[arg(long, default_value_t = 240)]
    warm_steps: u64,
    /// Also time each dispatch of a step: up to 16 steps more with a GPU timestamp after
    /// every dispatch (each adds a few microseconds, so the times are shares, not costs);
    /// needs timestamps inside compute passes.
    #[arg(long)]
    profile: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
    #[arg(long)]
    backend: Option<String>,
}

fn parse_fraction(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(f) if f > 0.0 && f <= 1.0 => Ok(f),
        _ => Err(format!("`{s}` must be a number in (0, 1]")),
    }
}

/// The draw's figures as JSON (the `draw` object of `plume bench --json`).
fn draw_json(d: &plume_runtime::bench::DrawTimes) -> serde_json::Value {
    serde_json::json!({
        "render_size": format!("{}x{}", d.width, d.height),
        "particles": d.particles,
        "scene_steps": d.steps,
        "ms": d.draw * 1e3,
        "opaque_ms": d.opaque * 1e3,
        "vertex_only_ms": d.vertex_only * 1e3,
        "prepare_ms": d.prepare.map(|s| s * 1e3),
        "light_ms": d.light.map(|s| s * 1e3),
        "compaction_ms": d.compacted.map(|(c, _)| c * 1e3),
        "triangle_ms": d.triangle * 1e3,
        "compute_ms": d.compute.map(|s| s.0 * 1e3),
        "compute_entries": d.compute.map(|s| s.1),
        "compute_stages_ms": d.compute_stages.iter().map(|(n, s)| (n.to_string(), s * 1e3)).collect::<std::collections::BTreeMap<_, _>>(),
        "compacted_ms": d.compacted.map(|(_, s)| s * 1e3),
        "stateless_ms": d.stateless.map(|s| s * 1e3),
        "glow_draw_ms": d.glow.map(|g| g.0 * 1e3),
        "glow_blur_ms": d.glow.map(|g| g.1 * 1e3),
    })
}

/// Each dispatch's time a step as JSON (`dispatches` of `plume bench --json --profile`).
fn dispatches_json(d: &[DispatchTime]) -> serde_json::Value {
    d.iter()
        .map(|t| serde_json::json!({"label": t.label, "us_per_step": t.us_per_step, "per_step": t.per_step}))
        .collect()
}

/// Prints each dispatch's time a step under `title`, if any were timed.
fn print_dispatches(title: &str, d: &[DispatchTime]) {
    if d.is_empty() {
        return;
    }
    let total: f64 = d.iter().map(|t| t.us_per_step).sum();
    println!("  {title} (µs a step, timestamps included: {total:.1} in all)");
    for t in d {
        println!(
            "    {:<26} {:>8.2}  ({:.0}%, {:.1} a step)",
            t.label,
            t.us_per_step,
            100.0 * t.us_per_step / total,
            t.per_step
        );
    }
}

/// The sort benchmark's figures as JSON (the `sort_alone` array of `plume bench --json`).
fn sort_json(s: &plume_runtime::bench::SortBench) -> serde_json::Value {
    let times = s.times.iter().map(|t| {
        serde_json::json!({
            "keys": s.keys, "ranking": format!("{:?}", t.ranking), "key_bits": t.key_bits,
            "ms": t.seconds * 1e3, "keys_per_s": s.keys as f64 / t.seconds,
            "first_pass_ms": t.stages.iter().map(|(name, s)| (name.to_string(), s * 1e3)).collect::<std::collections::BTreeMap<_, _>>(),
        })
    });
    serde_json::Value::Array(times.collect())
}

/// `plume bench` of an effect with groups and events: its steps with and without events.
fn bench_graph_command(
    args: &BenchArgs,
    name: &str,
    effect: &plume_compiler::EffectSpec,
) -> ExitCode {
    let gpu = match load::gpu(&args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    if !args.json {
        eprintln!(
            "benchmarking {name} scaled to {} slots on {} ...",
            args.particles,
            gpu.describe()
        );
    }
    let r = match bench_graph(
        &gpu,
        effect,
        args.particles,
        args.warm_steps,
        args.steps,
        args.profile,
    ) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let timing = match r.timing {
        TimingSource::Timestamps => "gpu timestamps",
        TimingSource::WallClock => "wall clock (no timestamp queries on this adapter)",
    };
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "effect": name, "adapter": r.adapter, "scale": r.scale, "slots": args.particles,
                "warm_steps": r.warm_steps, "steps": r.steps, "timing": timing,
                "groups": r.groups.iter().map(|(n, c, a)| serde_json::json!({"name": n, "capacity": c, "alive": a})).collect::<Vec<_>>(),
                "ms_per_step": r.seconds_per_step * 1e3,
                "plain_ms_per_step": r.plain_seconds_per_step * 1e3,
                "event_ms_per_step": r.event_seconds_per_step() * 1e3,
                "firings_per_step": r.firings_per_step,
                "children_per_step": r.children_per_step,
                "firings_per_second": r.firings_per_second(),
                "order_ms": r.order_seconds.iter().map(|s| s * 1e3).collect::<Vec<_>>(),
                "dispatches": args.profile.then(|| dispatches_json(&r.dispatches.0)),
                "plain_dispatches": args.profile.then(|| dispatches_json(&r.dispatches.1)),
            })
        );
        return ExitCode::SUCCESS;
    }
    println!("{name}");
    println!("  adapter             {}", r.adapter);
    println!("  timing              {timing}");
    println!(
        "  scaled              x{:.3} (capacities, bursts and rates), {} warm-up steps",
        r.scale, r.warm_steps
    );
    for (n, cap, alive) in &r.groups {
        println!("  group {n:<13} {alive} alive of {cap}");
    }
    println!("  step with events    {:.4} ms", r.seconds_per_step * 1e3);
    println!(
        "  step without        {:.4} ms (the same groups and live particles, no events)",
        r.plain_seconds_per_step * 1e3
    );
    println!(
        "  events              {:.4} ms/step for {:.1} firings and {:.1} children a step ({:.3e} firings/s)",
        r.event_seconds_per_step() * 1e3,
        r.firings_per_step,
        r.children_per_step,
        r.firings_per_second()
    );
    for (k, s) in r.order_seconds.iter().enumerate() {
        println!(
            "  order of event {k}    {:.4} ms (one per step: its firings put in id order)",
            s * 1e3
        );
    }
    print_dispatches("dispatches with events", &r.dispatches.0);
    print_dispatches("dispatches without", &r.dispatches.1);
    ExitCode::SUCCESS
}

/// Runs `plume bench`.
pub fn bench_command(args: &BenchArgs) -> ExitCode {
    if let Some((name, effect)) = load::graph_effect(&args.file, true) {
        return match effect {
            Ok(effect) => bench_graph_command(args, &name, &effect),
            Err(code) => code,
        };
    }
    let (load::Source { name, .. }, effect) = match load::checked(&args.file, args.render.is_none())
    {
        Ok(x) => x,
        Err(code) => return code,
    };
    let gpu = match load::gpu(&args.backend) {
        Ok(g) => g,
        Err(code) => return code,
    };
    if !args.json {
        eprintln!(
            "benchmarking {name} at {} particles on {} ...",
            args.particles,
            gpu.describe()
        );
        if effect
            .collide
            .iter()
            .any(|c| matches!(c, plume_compiler::colliders::Collider::SceneDepth { .. }))
        {
            let (w, h) = args.render.unwrap_or((1280, 720));
            eprintln!(
                "scene depth: the SceneDepth collider meets the effect's scene meshes drawn from its camera at {w} x {h}"
            );
        }
    }
    let options = BenchOptions {
        particles: args.particles,
        steps: args.steps,
        render: args.render,
        occupancy: args.occupancy,
        profile: args.profile,
    };
    let r = match bench(&gpu, &effect, &options) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let sort_alone = match args.sort_keys {
        Some(n) => match bench_sort(&gpu, u64::from(n), 9) {
            Ok(s) => Some(s),
            Err(e) => {
                eprintln!("{name}: error in the sort benchmark: {e}");
                return ExitCode::FAILURE;
            }
        },
        None => None,
    };
    let timing = match r.timing {
        TimingSource::Timestamps => "gpu timestamps",
        TimingSource::WallClock => "wall clock (no timestamp queries on this adapter)",
    };
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "effect": name, "adapter": r.adapter, "particles": r.particles, "steps": r.steps,
                "capacity": args.particles, "occupancy": args.occupancy,
                "bytes_per_particle": r.bytes_per_particle, "chunks": r.chunks,
                "ms_per_step": r.seconds_per_step * 1e3,
                "particle_steps_per_second": r.particle_steps_per_second(),
                "gb_per_s": r.update_gbps(), "copy_gb_per_s": r.copy_gbps(),
                "copy_ms": r.copy_seconds * 1e3,
                "copy_in_place_ms": r.copy_in_place_seconds * 1e3, "ratio": r.ratio(), "timing": timing,
                "spawn_step_ms": r.spawn_step_seconds * 1e3,
                "draw": r.render.as_ref().map(draw_json),
                "sort_radix_ms": r.sort.map(|(s, _)| s * 1e3),
                "sort_bitonic_ms": r.sort.map(|(_, s)| s * 1e3),
                "sort_radix_keys_per_s": r.sort.map(|(s, _)| r.particles as f64 / s),
                "sort_bitonic_keys_per_s": r.sort.map(|(_, s)| r.particles as f64 / s),
                "flock_mean_neighbours": r.flock.as_ref().map(|(n, _)| *n),
                "flock_search": r.flock.as_ref().map(|(_, s)| s.clone()),
                "sort_stages_ms": r.sort_stages.iter().map(|(n, s)| (n.to_string(), s * 1e3)).collect::<std::collections::BTreeMap<_, _>>(),
                "flock_stages_ms": r.flock_stages.iter().map(|(n, s)| (n.to_string(), s * 1e3)).collect::<std::collections::BTreeMap<_, _>>(),
                "field_error_max": r.field_error.map(|(m, _, _)| m),
                "field_error_rms": r.field_error.map(|(_, s, _)| s),
                "field_error_samples": r.field_error.map(|(_, _, n)| n),
                "stateless_ms_per_frame": r.stateless.as_ref().ok().map(|s| s * 1e3),
                "stateless_speedup": r.stateless.as_ref().ok().map(|s| r.seconds_per_step / s),
                "stateful_because": r.stateless.as_ref().err(),
                "fill_ms": r.fill_seconds.map(|s| s * 1e3),
                "sort_alone": sort_alone.as_ref().map(sort_json),
                "dispatches": args.profile.then(|| dispatches_json(&r.dispatches)),
                "build_ms": r.build_seconds[0] * 1e3,
                "build_again_ms": r.build_seconds[1] * 1e3,
                "build_again_uncached_ms": r.build_seconds[2] * 1e3,
            })
        );
    } else {
        println!("{name}");
        println!("  adapter             {}", r.adapter);
        println!(
            "  particles           {} ({} buffer(s))",
            r.particles, r.chunks
        );
        if args.occupancy < 1.0 {
            println!(
                "  occupancy           {} of {} slots alive",
                r.particles, args.particles
            );
        }
        println!("  bytes per particle  {}", r.bytes_per_particle);
        println!(
            "  build               {:.1} ms, again {:.1} ms with the device's cache of kernels, {:.1} ms without",
            r.build_seconds[0] * 1e3,
            r.build_seconds[1] * 1e3,
            r.build_seconds[2] * 1e3
        );
        println!(
            "  update (stateful)   {:.4} ms/step, {:.3} G particle-steps/s, {:.1} GB/s",
            r.seconds_per_step * 1e3,
            r.particle_steps_per_second() * 1e-9,
            r.update_gbps()
        );
        println!(
            "  copy kernel         {:.4} ms for the same bytes, {:.1} GB/s",
            r.copy_seconds * 1e3,
            r.copy_gbps()
        );
        println!(
            "  copy in place       {:.4} ms reading and writing one buffer, as the update does ({:.3} of the copy's speed)",
            r.copy_in_place_seconds * 1e3,
            r.copy_seconds / r.copy_in_place_seconds
        );
        println!("  ratio               {:.3} (copy time / update time; 1 = at the copy kernel's bandwidth)", r.ratio());
        println!(
            "  spawn               {:.4} ms for step 0: spawning all {} particles and one update",
            r.spawn_step_seconds * 1e3,
            r.particles
        );
        if let Some((max, rms, n)) = r.field_error {
            println!(
                "  baked field error   max {max:.3e}, RMS {rms:.3e} of the RMS evaluated acceleration, at {n} particles inside the grid (f64 reference)"
            );
        }
        match &r.stateless {
            Ok(s) => println!(
                "  stateless           {:.4} ms/frame for `evaluate` (0 bytes of state; writes the {}-byte view), {:.2}x the stateful update's speed",
                s * 1e3,
                r.bytes_per_particle,
                r.seconds_per_step / s
            ),
            Err(why) => println!("  stateless           no: {why}"),
        }
        if let Some(fill) = r.fill_seconds {
            println!(
                "  write-only kernel   {:.4} ms for the view's bytes (the stateless ceiling: it reads no state)",
                fill * 1e3
            );
        }
        if let Some((radix, bitonic)) = r.sort {
            println!(
                "  sort                radix {:.3} ms ({:.2} G keys/s), bitonic {:.3} ms ({:.2} G keys/s), depth keys included",
                radix * 1e3,
                r.particles as f64 / radix * 1e-9,
                bitonic * 1e3,
                r.particles as f64 / bitonic * 1e-9
            );
        }
        if let Some(s) = &sort_alone {
            for t in &s.times {
                let stages: Vec<String> = t
                    .stages
                    .iter()
                    .map(|(name, s)| format!("{} {:.3}", name.replace('_', " "), s * 1e3))
                    .collect();
                println!(
                    "  radix sort alone    {:.3} ms ({:.2} G keys/s): {} random pairs, {}-bit keys, {:?} ranking; first stages: {} ms",
                    t.seconds * 1e3,
                    s.keys as f64 / t.seconds * 1e-9,
                    s.keys,
                    t.key_bits,
                    t.ranking,
                    stages.join(", ")
                );
            }
        }
        if let Some((n, search)) = &r.flock {
            println!("  flock               {search}: {n:.1} neighbours per boid on average (the step time above includes the flocking pass)");
            let stages: Vec<String> = r
                .flock_stages
                .iter()
                .map(|(name, s)| format!("{name} {:.3}", s * 1e3))
                .collect();
            println!("    stages (ms)       {}", stages.join(", "));
        }
        print_dispatches("dispatches", &r.dispatches);
        if let Some(d) = &r.render {
            println!(
                "  draw                {:.3} ms for a {}x{} frame of {} particles, from the GPU buffers (render pass only)",
                d.draw * 1e3,
                d.width,
                d.height,
                d.particles
            );
            println!(
                "    scene             the effect as written, scaled to that many alive, after {} steps",
                d.steps
            );
            println!(
                "    without blending  {:.3} ms (opaque writes)",
                d.opaque * 1e3
            );
            println!(
                "    vertices only     {:.3} ms (every sprite hidden in the vertex shader: no pixels)",
                d.vertex_only * 1e3
            );
            println!(
                "    one triangle      {:.3} ms (a triangle per sprite instead of a quad)",
                d.triangle * 1e3
            );
            match d.compute {
                Some((seconds, entries)) => {
                    println!(
                        "    compute renderer     {:.3} ms for the same image in compute shaders ({entries} tile entries sorted)",
                        seconds * 1e3,
                    );
                    let stages: Vec<String> = d
                        .compute_stages
                        .iter()
                        .map(|(name, s)| format!("{name} {:.3}", s * 1e3))
                        .collect();
                    println!("      stages (ms)     {}", stages.join(", "));
                    let (faster, ratio) = if seconds < d.draw {
                        ("the compute renderer", d.draw / seconds)
                    } else {
                        ("the raster pipeline", seconds / d.draw)
                    };
                    println!(
                        "    faster here       {faster}, {ratio:.1}x (plume render --draw auto takes the compute renderer on a GPU adapter, raster on a CPU one)"
                    );
                }
                None => println!("    compute renderer     - (it does not draw this effect)"),
            }
            if let Some((draw, blur)) = d.glow {
                println!(
                    "    glow              {:.3} ms: the draw into the HDR image {:.3} ms + the bloom's two blur passes {:.3} ms",
                    (draw + blur) * 1e3,
                    draw * 1e3,
                    blur * 1e3
                );
            }
            if let Some(p) = d.prepare {
                println!(
                    "    prepare           {:.3} ms before the draw: depth keys and the radix sort",
                    p * 1e3
                );
            }
            if let Some(l) = d.light {
                println!(
                    "    particle light    {:.3} ms to pick the lights the particles give off (render.light)",
                    l * 1e3
                );
            }
            if let Some((compact, draw)) = d.compacted {
                println!(
                    "    compacted list    {:.3} ms: {:.3} ms to list the live slots (flags, scan, scatter) + {:.3} ms to draw only them",
                    (compact + draw) * 1e3,
                    compact * 1e3,
                    draw * 1e3
                );
            }
            if let Some(s) = d.stateless {
                println!(
                    "    stateless         {:.3} ms: the same particles computed from the closed form in the vertex shader, no compute pass",
                    s * 1e3
                );
            }
        }
        println!("  timing              {timing}, {} steps", r.steps);
    }
    ExitCode::SUCCESS
}
