//! `plume run`: simulate an effect on the GPU (or with `--cpu-reference`, the CPU f64
//! reference), print a summary or JSON, and optionally export the live particles. An effect
//! with groups and events runs the same way: every group simulated together, a summary per
//! group, and an export that names each particle's group.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use plume_compiler::graph::CompiledGraph;
use plume_compiler::graph::ReferenceGraph;
use plume_compiler::reference::{ParticleRecord, ReferenceSim, Totals};
use plume_runtime::outputs::{export, export_groups, summarize};
use plume_runtime::{Effect, Gpu, GpuChoice, RuntimeError};

use crate::reports::Reported;
use crate::{load, Overrides};

/// Options of `plume run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The effect file (.ron).
    pub(crate) file: PathBuf,
    /// Steps to simulate.
    #[arg(long, default_value_t = 600)]
    pub(crate) steps: u64,
    #[command(flatten)]
    pub(crate) overrides: Overrides,
    /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
    #[arg(long)]
    pub(crate) backend: Option<String>,
    /// Write the live particles (sorted by id) to a .csv or .ply file.
    #[arg(long)]
    pub(crate) export: Option<PathBuf>,
    /// Export order: `id` (spawn order) or `draw` (back to front from the camera, sorted on
    /// the GPU; equal depths by id).
    #[arg(long, value_enum, default_value_t = Order::Id)]
    pub(crate) order: Order,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub(crate) json: bool,
    /// Run the CPU f64 reference simulator instead of the GPU.
    #[arg(long)]
    pub(crate) cpu_reference: bool,
    /// Measure the box that holds every live particle at the end of every step (on the GPU, or
    /// in f64 with --cpu-reference) and print it as a `bounds:` line for the file (the box a
    /// host culls the effect by).
    #[arg(long)]
    pub(crate) bounds: bool,
    /// Write every firing of the effect's reported events (`Event(.., report: N)`) to a .csv
    /// file: group, event, step, particle id, position and velocity, read back from the GPU
    /// after every step (or the f64 reference's firings with --cpu-reference).
    #[arg(long, value_name = "FILE")]
    pub(crate) reports: Option<PathBuf>,
}

/// The order of exported particles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    /// By id (spawn order).
    Id,
    /// Back to front as seen from the camera (the draw order of alpha blending).
    Draw,
}

/// One group's results.
struct GroupOutcome {
    name: String,
    totals: Totals,
    records: Vec<ParticleRecord>,
}

/// A run's results: the engine, every group's, and the wall time of the steps.
struct Outcome {
    engine: String,
    groups: Vec<GroupOutcome>,
    seconds: f64,
    /// With `--bounds`: the union over the steps of the boxes of every group's live particles.
    bounds: Option<Bounds>,
    /// With `--reports`: the firings of the reported events.
    reported: Option<Reported>,
}

/// A box: its corners (m).
type Bounds = plume_runtime::LiveBounds;

/// The smallest box holding `a` and `b`, where there is one.
fn union(a: Option<Bounds>, b: Option<Bounds>) -> Option<Bounds> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.union(b)),
        (a, None) => a,
        (None, b) => b,
    }
}

/// The box of `records`' finite positions (the f64 run's, rounded to f32).
fn box_of(records: &[ParticleRecord]) -> Option<Bounds> {
    records
        .iter()
        .filter(|r| r.position.is_finite())
        .map(|r| {
            let x = r.position.as_vec3().to_array();
            Bounds { min: x, max: x }
        })
        .fold(None, |acc, b| union(acc, Some(b)))
}

pub(crate) fn progress_bar(steps: u64, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(steps);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len} steps ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}

/// Runs `graph` on the CPU f64 reference: the single-system simulator for an effect without
/// groups (sorted back to front for `--order draw`), the reference graph otherwise.
fn simulate_cpu(args: &RunArgs, graph: &CompiledGraph, bar: &ProgressBar) -> Outcome {
    bar.set_message("cpu reference");
    let start = Instant::now();
    let mut bounds = None;
    let mut reported = args.reports.as_ref().map(|_| Reported::default());
    let groups = if load::single(graph) {
        let effect = &graph.groups[0].effect;
        let mut sim = ReferenceSim::new(&effect.ir);
        for step in 0..args.steps {
            sim.step();
            if args.bounds {
                bounds = union(bounds, box_of(&sim.records()));
            }
            if let Some(r) = &mut reported {
                r.take_reference(graph, |_, j| sim.fired(j), step);
            }
            bar.inc(1);
        }
        let mut records = sim.records();
        if args.order == Order::Draw {
            // The reference sorts in f64 on the CPU: farthest first, equal depths by id.
            let cam = effect.ir.camera;
            let forward = (cam.target - cam.eye).normalize_or_zero();
            records.sort_by(|a, b| {
                let da = (a.position - cam.eye).dot(forward);
                let db = (b.position - cam.eye).dot(forward);
                db.total_cmp(&da).then(a.id.cmp(&b.id))
            });
        }
        vec![GroupOutcome {
            name: graph.groups[0].name.clone(),
            totals: sim.totals(),
            records,
        }]
    } else {
        let mut sim = ReferenceGraph::new(graph);
        for step in 0..args.steps {
            sim.step();
            if args.bounds {
                for g in 0..graph.groups.len() {
                    bounds = union(bounds, box_of(&sim.records(g)));
                }
            }
            if let Some(r) = &mut reported {
                r.take_reference(graph, |g, j| sim.group(g).fired(j), step);
            }
            bar.inc(1);
        }
        (0..graph.groups.len())
            .map(|g| GroupOutcome {
                name: graph.groups[g].name.clone(),
                totals: sim.totals(g),
                records: sim.records(g),
            })
            .collect()
    };
    bar.finish_and_clear();
    Outcome {
        engine: "cpu reference (f64)".into(),
        groups,
        seconds: start.elapsed().as_secs_f64(),
        bounds,
        reported,
    }
}

fn simulate(args: &RunArgs, graph: CompiledGraph) -> Result<Outcome, RuntimeError> {
    let bar = progress_bar(args.steps, args.json);
    if args.cpu_reference {
        return Ok(simulate_cpu(args, &graph, &bar));
    }
    let gpu = Gpu::new(&GpuChoice {
        backend: args.backend.clone(),
    })?;
    bar.set_message("gpu");
    let mut sim = Effect::from_graph(&gpu, graph)?;
    // A SceneDepth collider meets the effect's scene as its camera sees it at 1280 x 720.
    let size = (1280, 720);
    let camera = plume_runtime::Camera::from_effect(
        &sim.compiled().ir.camera,
        size.0 as f32 / size.1 as f32,
    );
    let _scene = crate::scene_depth::bind_effect_scene(&gpu, &mut sim, &camera, size)?;
    let start = Instant::now();
    let mut bounds = None;
    let mut reported = None;
    if args.reports.is_some() {
        // A step at a time, its firings read back after it (and the box measured).
        reported = Some(crate::reports::run_gpu(
            &mut sim,
            args.steps,
            |sim, done| {
                if args.bounds {
                    bounds = union(bounds, sim.live_bounds()?);
                }
                bar.set_position(done);
                Ok(())
            },
        )?);
    } else if args.bounds {
        // A step at a time, the box measured after each (24 bytes read back a step).
        for done in 1..=args.steps {
            sim.run(1, |_| {})?;
            bounds = union(bounds, sim.live_bounds()?);
            bar.set_position(done);
        }
    } else {
        sim.run(args.steps, |done| bar.set_position(done))?;
    }
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let mut groups = Vec::new();
    for (g, name) in sim.group_names().iter().enumerate() {
        groups.push(GroupOutcome {
            name: name.clone(),
            totals: sim.group_totals(g)?,
            records: match args.order {
                Order::Id => sim.group_records(g)?,
                Order::Draw => sim.records_in_draw_order()?,
            },
        });
    }
    Ok(Outcome {
        engine: gpu.describe(),
        groups,
        seconds,
        bounds,
        reported,
    })
}

/// Runs `plume run`.
pub fn run(args: &RunArgs) -> ExitCode {
    let mut options = args.overrides.options();
    // Nothing is drawn: a sprite texture need not be there.
    options.step_only = true;
    if args.order == Order::Draw {
        options.sort = Some(true);
    }
    let (load::Source { name, .. }, graph) = match load::compiled_graph(&args.file, &options) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let single = load::single(&graph);
    if args.reports.is_some() && !crate::reports::any(&graph) {
        eprintln!("{name}: error: --reports: no event of this effect is reported (give an event `report: N`, docs/effect-format.md, \"Reported events\")");
        return ExitCode::FAILURE;
    }
    if !single && args.order == Order::Draw {
        eprintln!("{name}: error: --order draw: an effect with groups exports by group and id (each group sorts its own draw)");
        return ExitCode::FAILURE;
    }
    let top = &graph.groups[0].effect.ir;
    let dt = top.dt;
    let state = match (&top.stateless, args.cpu_reference) {
        (Some(_), false) => {
            "stateless (each step is bookkeeping; positions are computed once, when read)"
        }
        (Some(_), true) => "stateless on the GPU; the CPU reference steps it",
        (None, _) => "stateful",
    };
    let outcome = match simulate(args, graph) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(path) = &args.export {
        let written = match single {
            true => export(path, &outcome.groups[0].records, &[args.file.as_path()]),
            false => {
                let parts: Vec<(&str, &[ParticleRecord])> = outcome
                    .groups
                    .iter()
                    .map(|g| (g.name.as_str(), g.records.as_slice()))
                    .collect();
                export_groups(path, &parts, &[args.file.as_path()])
            }
        };
        if let Err(e) = written {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }
    if let (Some(path), Some(reported)) = (&args.reports, &outcome.reported) {
        let names: Vec<String> = outcome.groups.iter().map(|g| g.name.clone()).collect();
        if let Err(e) = crate::reports::write(path, reported, &names, &args.file) {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
        // One warning per event: its firings past the bound, over the steps that had some.
        let mut missed = std::collections::BTreeMap::<(usize, usize), (u64, u64)>::new();
        for &(g, j, n) in &reported.missed {
            let entry = missed.entry((g, j)).or_default();
            *entry = (entry.0 + n, entry.1 + 1);
        }
        for ((g, j), (n, steps)) in missed {
            eprintln!(
                "{name}: warning: {}.events[{j}]: {n} firings past its report bound, in {steps} steps, were counted, not kept",
                names[g]
            );
        }
        if !args.json {
            println!(
                "reported: {} firings written to {}",
                reported.rows.len(),
                path.display()
            );
        }
    }
    match (single, args.json) {
        (true, true) => print_json(&outcome, state),
        (true, false) => print_summary(args, &name, &outcome, state, dt),
        (false, true) => print_groups_json(&outcome),
        (false, false) => print_groups(args, &name, &outcome, dt),
    }
    if args.bounds && !args.json {
        print_bounds(args.steps, outcome.bounds);
    }
    ExitCode::SUCCESS
}

/// The measured box as a line for the file: its corners rounded outward to the centimetre.
fn print_bounds(steps: u64, bounds: Option<Bounds>) {
    match bounds {
        Some(Bounds { min, max }) => {
            let out = |v: [f32; 3], round: fn(f64) -> f64| {
                let c = v.map(|x| round(f64::from(x) * 100.0) / 100.0);
                format!("({:.2}, {:.2}, {:.2})", c[0], c[1], c[2])
            };
            println!(
                "live bounds over {steps} steps (every live particle at the end of every step):\n  bounds: Some(Bounds(min: {}, max: {})),",
                out(min, f64::floor),
                out(max, f64::ceil)
            );
        }
        None => {
            println!("live bounds over {steps} steps: no particle was alive at the end of any step")
        }
    }
}

/// One JSON object for an effect without groups.
fn print_json(outcome: &Outcome, state: &str) {
    let g = &outcome.groups[0];
    let mut v = group_json(g);
    v.insert("steps".into(), g.totals.steps.into());
    v.insert("seconds".into(), outcome.seconds.into());
    v.insert("adapter".into(), outcome.engine.clone().into());
    v.insert("stateless".into(), state.starts_with("stateless (").into());
    if let Some(Bounds { min, max }) = outcome.bounds {
        v.insert(
            "live_bounds".into(),
            serde_json::json!({ "min": min, "max": max }),
        );
    }
    println!("{}", serde_json::Value::Object(v));
}

/// A group's counts and the summary of its particles, as JSON fields.
fn group_json(g: &GroupOutcome) -> serde_json::Map<String, serde_json::Value> {
    let s = summarize(&g.records);
    let t = g.totals;
    let serde_json::Value::Object(fields) = serde_json::json!({
        "alive": t.alive,
        "spawned": t.spawned,
        "died": t.died,
        "dropped": t.dropped,
        "nonfinite": s.nonfinite,
        "bbox_min": [s.bbox_min.x, s.bbox_min.y, s.bbox_min.z],
        "bbox_max": [s.bbox_max.x, s.bbox_max.y, s.bbox_max.z],
        "mean_speed": s.mean_speed,
    }) else {
        unreachable!("json! of an object literal is an object")
    };
    fields
}

/// The summary of an effect without groups.
fn print_summary(args: &RunArgs, name: &str, outcome: &Outcome, state: &str, dt: f64) {
    let g = &outcome.groups[0];
    let s = summarize(&g.records);
    let t = g.totals;
    let v = |v: glam::DVec3| format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z);
    println!("{name}");
    println!("  adapter     {}", outcome.engine);
    println!("  state       {state}");
    println!(
        "  steps       {} ({:.3} s simulated, dt {} s)",
        t.steps,
        t.steps as f64 * dt,
        dt
    );
    println!("  alive       {}", t.alive);
    println!("  spawned     {}", t.spawned);
    println!("  died        {}", t.died);
    println!("  dropped     {}", t.dropped);
    println!("  nonfinite   {}", s.nonfinite);
    println!("  bbox        {} .. {}", v(s.bbox_min), v(s.bbox_max));
    println!("  mean speed  {:.4} m/s", s.mean_speed);
    println!("  wall time   {:.3} s", outcome.seconds);
    if let Some(path) = &args.export {
        println!(
            "  exported    {} particles to {}",
            g.records.len(),
            path.display()
        );
    }
}

/// One JSON object for an effect with groups, a summary per group.
fn print_groups_json(outcome: &Outcome) {
    let per_group: Vec<serde_json::Value> = outcome
        .groups
        .iter()
        .map(|g| {
            let mut fields = group_json(g);
            fields.insert("name".into(), g.name.clone().into());
            serde_json::Value::Object(fields)
        })
        .collect();
    let mut v = serde_json::json!({
        "steps": outcome.groups[0].totals.steps,
        "groups": per_group,
        "seconds": outcome.seconds,
        "adapter": outcome.engine,
    });
    if let Some(Bounds { min, max }) = outcome.bounds {
        v["live_bounds"] = serde_json::json!({ "min": min, "max": max });
    }
    println!("{v}");
}

/// The summary of an effect with groups: a table, a row per group.
fn print_groups(args: &RunArgs, name: &str, outcome: &Outcome, dt: f64) {
    let steps = outcome.groups[0].totals.steps;
    println!("{name}");
    println!("  adapter     {}", outcome.engine);
    println!(
        "  steps       {steps} ({:.3} s simulated, dt {dt} s)",
        steps as f64 * dt
    );
    println!(
        "  {:<12} {:>9} {:>9} {:>9} {:>9} {:>9}  mean speed",
        "group", "alive", "spawned", "died", "dropped", "nonfinite"
    );
    for g in &outcome.groups {
        let s = summarize(&g.records);
        let t = g.totals;
        println!(
            "  {:<12} {:>9} {:>9} {:>9} {:>9} {:>9}  {:.4} m/s",
            g.name, t.alive, t.spawned, t.died, t.dropped, s.nonfinite, s.mean_speed
        );
    }
    println!("  wall time   {:.3} s", outcome.seconds);
    if let Some(path) = &args.export {
        let total: usize = outcome.groups.iter().map(|g| g.records.len()).sum();
        println!("  exported    {total} particles to {}", path.display());
    }
}
