//! `plume run`: simulate an effect on the GPU (or with `--cpu-reference`, the CPU f64
//! reference), print a summary or JSON, and optionally export the live particles.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use plume_compiler::reference::{ParticleRecord, ReferenceSim, Totals};
use plume_compiler::CompiledEffect;
use plume_runtime::export::{export, summarize};
use plume_runtime::{EffectInstance, Gpu, GpuChoice, RuntimeError};

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
}

/// The order of exported particles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    /// By id (spawn order).
    Id,
    /// Back to front as seen from the camera (the draw order of alpha blending).
    Draw,
}

struct Outcome {
    engine: String,
    totals: Totals,
    records: Vec<ParticleRecord>,
    seconds: f64,
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

fn simulate(args: &RunArgs, effect: CompiledEffect) -> Result<Outcome, RuntimeError> {
    let bar = progress_bar(args.steps, args.json);
    if args.cpu_reference {
        bar.set_message("cpu reference");
        let start = Instant::now();
        let mut sim = ReferenceSim::new(&effect.ir);
        for _ in 0..args.steps {
            sim.step();
            bar.inc(1);
        }
        bar.finish_and_clear();
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
        return Ok(Outcome {
            engine: "cpu reference (f64)".into(),
            totals: sim.totals(),
            records,
            seconds: start.elapsed().as_secs_f64(),
        });
    }
    let gpu = Gpu::new(&GpuChoice {
        backend: args.backend.clone(),
    })?;
    bar.set_message("gpu");
    let mut sim = EffectInstance::new(&gpu, effect)?;
    let start = Instant::now();
    sim.run(args.steps, |done| bar.set_position(done))?;
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    Ok(Outcome {
        engine: gpu.describe(),
        totals: sim.totals()?,
        records: match args.order {
            Order::Id => sim.records()?,
            Order::Draw => sim.records_in_draw_order()?,
        },
        seconds,
    })
}

/// Runs `plume run`.
pub fn run(args: &RunArgs) -> ExitCode {
    let mut options = args.overrides.options();
    if args.order == Order::Draw {
        options.sort = Some(true);
    }
    let (load::Source { name, .. }, mut graph) = match load::compiled_graph(&args.file, &options) {
        Ok(x) => x,
        Err(code) => return code,
    };
    if !load::single(&graph) {
        return crate::run_graph::run_graph(args, &name, graph);
    }
    let effect = graph.groups.remove(0).effect;
    let dt = effect.ir.dt;
    let state = match (&effect.ir.stateless, args.cpu_reference) {
        (Some(_), false) => {
            "stateless (each step is bookkeeping; positions are computed once, when read)"
        }
        (Some(_), true) => "stateless on the GPU; the CPU reference steps it",
        (None, _) => "stateful",
    };
    let outcome = match simulate(args, effect) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(path) = &args.export {
        if let Err(e) = export(path, &outcome.records, &[args.file.as_path()]) {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }
    let s = summarize(&outcome.records);
    let t = outcome.totals;
    if args.json {
        let v = serde_json::json!({
            "steps": t.steps,
            "alive": t.alive,
            "spawned": t.spawned,
            "died": t.died,
            "dropped": t.dropped,
            "nonfinite": s.nonfinite,
            "bbox_min": [s.bbox_min.x, s.bbox_min.y, s.bbox_min.z],
            "bbox_max": [s.bbox_max.x, s.bbox_max.y, s.bbox_max.z],
            "mean_speed": s.mean_speed,
            "seconds": outcome.seconds,
            "adapter": outcome.engine,
            "stateless": state.starts_with("stateless ("),
        });
        println!("{v}");
    } else {
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
                outcome.records.len(),
                path.display()
            );
        }
    }
    ExitCode::SUCCESS
}
