//! `plume accuracy`: each integrator x step size, the position error at the end against the
//! closed form or an f64 RK4 at 1/64 of the smallest step, the time per step and the observed
//! order; a table, JSON, and an SVG plot with the Pareto front. An effect with an accuracy
//! budget is first checked against it on the GPU (a non-zero exit when it is exceeded).

use std::path::PathBuf;
use std::process::ExitCode;

use indicatif::{ProgressBar, ProgressStyle};
use plume_compiler::Integrator;
use plume_runtime::bench::{
    accuracy_svg, check_budget, field_sweep, measure, pareto_front, AccuracyPlan, Engine,
    ReferenceKind,
};
use plume_runtime::outputs::write_atomically;

use crate::load;

/// Options of `plume accuracy`.
#[derive(clap::Args, Debug)]
pub struct AccuracyArgs {
    /// The effect file (.ron).
    file: PathBuf,
    /// Step sizes in seconds, comma-separated [default: the file's dt x 4, 2, 1, 1/2, 1/4].
    #[arg(long, value_delimiter = ',')]
    dt_list: Option<Vec<f64>>,
    /// Integrators, comma-separated [default: all; Exact only where it is allowed].
    #[arg(long, value_delimiter = ',', value_parser = crate::parse_integrator)]
    integrators: Option<Vec<Integrator>>,
    /// Measure after this many steps of the file's dt [default: 120].
    #[arg(long, conflicts_with = "duration")]
    steps: Option<u64>,
    /// Measure after this many seconds (a multiple of every dt).
    #[arg(long)]
    duration: Option<f64>,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the error-vs-time plot (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Run the integrators on the CPU reference (f64) instead of the GPU (f32).
    #[arg(long)]
    cpu: bool,
    /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
    #[arg(long)]
    backend: Option<String>,
    /// Instead of the integrators: the error of a baked field against evaluated forces, at
    /// each resolution of --resolutions, nearest and trilinear, over the file's field bounds.
    #[arg(long)]
    field_sweep: bool,
    /// Nodes per axis for --field-sweep, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [16u32, 32, 64, 128])]
    resolutions: Vec<u32>,
}

/// Runs `plume accuracy`: on the effect, or on each group of an effect with groups.
pub fn accuracy(args: &AccuracyArgs) -> ExitCode {
    if let Some((name, graph)) = load::graph_effect(&args.file, true) {
        return match graph {
            Ok(effect) => accuracy_of_groups(args, &name, &effect),
            Err(code) => code,
        };
    }
    let (load::Source { name, .. }, effect) = match load::checked(&args.file, true) {
        Ok(x) => x,
        Err(code) => return code,
    };
    accuracy_of(args, &name, &effect, args.plot.clone())
}

/// An effect with groups, group by group: each group that has emitters of its own runs as it
/// would alone (the events it fires and receives left out: its own particles, its own forces,
/// integrator, colliders and budget), through the same measurements as a one-group effect; a
/// group fed by events alone has no particles of its own and is listed as not measured. The
/// plot of group `g` goes to the plot's name with `-g` before its extension.
fn accuracy_of_groups(
    args: &AccuracyArgs,
    name: &str,
    effect: &plume_compiler::EffectSpec,
) -> ExitCode {
    let mut failed = false;
    let groups = plume_compiler::graph::group_effects(effect);
    // The sample bursts of the groups fed by events alone come from an f64 run of the whole graph.
    let graph = match plume_compiler::graph::compile_graph(effect, "") {
        Ok(graph) => graph,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    for (g, mut group) in groups.clone().into_iter().enumerate() {
        group.events.clear();
        let label = format!("{name} group {:?}", group.name);
        if group.emitters.is_empty() {
            match plume_compiler::graph::reference::sampled_group(
                &groups,
                &graph,
                g,
                plume_runtime::bench::CHECKED,
            ) {
                Some(sampled) => group = sampled,
                None => {
                    eprintln!(
                        "{label}: note: fed by events alone, and no event into it fired within {} steps of an f64 run: not measured",
                        plume_compiler::graph::reference::SAMPLE_SEARCH_STEPS
                    );
                    continue;
                }
            }
            if !args.json {
                let b = group.sample_burst.expect("a sample burst");
                println!(
                    "== {label} (fed by events: {} particles of its spawn rule at ({:.2}, {:.2}, {:.2}), where its parent first fires in f64, with {:?} m/s of the parent's velocity)",
                    b.count, b.offset[0], b.offset[1], b.offset[2], b.velocity
                );
            }
        } else if !args.json {
            println!("== {label} (alone: its events left out)");
        }
        let plot = args.plot.as_ref().map(|p| {
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_else(|| "svg".into());
            p.with_file_name(format!("{stem}-{g}.{ext}"))
        });
        if accuracy_of(args, &label, &group, plot) != ExitCode::SUCCESS {
            failed = true;
        }
    }
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// `plume accuracy` of one group's effect `effect` (named `name` in messages), its plot to
/// `plot`.
fn accuracy_of(
    args: &AccuracyArgs,
    name: &str,
    effect: &plume_compiler::EffectSpec,
    plot: Option<PathBuf>,
) -> ExitCode {
    let name = name.to_string();
    let effect = effect.clone();
    let dts = args.dt_list.clone().unwrap_or_else(|| {
        [4.0, 2.0, 1.0, 0.5, 0.25]
            .iter()
            .map(|f| effect.dt * f)
            .collect()
    });
    if dts.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
        eprintln!("error: every --dt-list value must be a positive number");
        return ExitCode::FAILURE;
    }
    let duration = args
        .duration
        .unwrap_or_else(|| effect.dt * args.steps.unwrap_or(120) as f64);
    let plan = AccuracyPlan {
        integrators: args
            .integrators
            .clone()
            .unwrap_or_else(|| Integrator::CONCRETE.to_vec()),
        dts,
        duration,
    };
    let gpu = if args.cpu {
        None
    } else {
        match load::gpu(&args.backend) {
            Ok(g) => Some(g),
            Err(code) => return code,
        }
    };
    let engine = match &gpu {
        Some(g) => Engine::Gpu(g),
        None => Engine::Cpu,
    };
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(0)
    };
    if args.field_sweep {
        return field_sweep_report(args, &name, &effect, &engine, &bar, duration, &gpu);
    }
    // The effect's own budget, on the GPU, before the sweep.
    let budget = match (&gpu, &effect.accuracy) {
        (Some(g), Some(_)) => {
            if !args.json {
                eprintln!("{name}: checking the accuracy budget on the GPU ...");
            }
            match check_budget(g, &effect) {
                Ok(b) => b,
                Err(e) => {
                    eprintln!("{name}: error: {e}");
                    return ExitCode::FAILURE;
                }
            }
        }
        (None, Some(_)) => {
            eprintln!("{name}: note: --cpu: the accuracy budget is checked on the GPU only");
            None
        }
        _ => None,
    };
    bar.set_style(
        ProgressStyle::with_template("measuring [{bar:30}] {pos}/{len} runs ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let (rows, kind) = match measure(&engine, &effect, &plan, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }) {
        Ok(r) => r,
        Err(e) => {
            bar.finish_and_clear();
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    bar.finish_and_clear();
    let engine_name = gpu
        .as_ref()
        .map(|g| g.describe())
        .unwrap_or_else(|| "cpu reference (f64)".into());
    let reference = match kind {
        ReferenceKind::ClosedForm => "the closed form (Exact in f64)".to_string(),
        ReferenceKind::Rk4(h) => format!("RK4 in f64 at dt = {h:.3e} s"),
    };
    if rows.iter().any(|r| r.compared == 0) {
        eprintln!(
            "{name}: warning: some runs had no particle alive at the end in both runs (lifetimes or kill volumes); use a shorter --duration"
        );
    }
    let front = pareto_front(&rows);
    if args.json {
        let items: Vec<_> = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                serde_json::json!({
                    "integrator": r.integrator.name(), "dt": r.dt, "steps": r.steps,
                    "max_error": r.max_error, "rms_error": r.rms_error,
                    "seconds_per_step": r.seconds_per_step, "order": r.order,
                    "compared": r.compared, "pareto": front.contains(&i),
                })
            })
            .collect();
        let budget_json = budget.as_ref().map(|b| {
            serde_json::json!({
                "chosen": b.chosen, "budget": b.budget, "unit": b.unit, "over": b.over, "measured": b.measured,
                "truth_uncertainty": b.truth_uncertainty, "particles": b.particles,
                "steps": b.steps, "met": b.met(),
            })
        });
        println!(
            "{}",
            serde_json::json!({ "effect": name, "engine": engine_name, "reference": reference,
                                "duration": duration, "rows": items, "budget": budget_json })
        );
    } else {
        if let Some(b) = &budget {
            println!("{name}: {}", b.chosen);
            println!(
                "budget: {} {:.3e} {u} measured on the GPU against {:.3e} {u} allowed, over the first {} s ({} steps) of {} particles (the f64 truth within {:.1e} {u})",
                if b.met() { "met:" } else { "EXCEEDED:" },
                b.measured,
                b.budget,
                b.over,
                b.steps,
                b.particles,
                b.truth_uncertainty,
                u = b.unit,
            );
        }
        println!("{name}: position error after {duration:.4} s against {reference}");
        println!("engine: {engine_name}; * marks the Pareto front (no row is both faster and more accurate)");
        println!(
            "{:<18} {:>10} {:>6} {:>12} {:>12} {:>12} {:>7} {:>6}",
            "integrator", "dt (s)", "steps", "max err (m)", "rms err (m)", "us/step", "order", "n"
        );
        for (i, r) in rows.iter().enumerate() {
            let order = r
                .order
                .map(|o| format!("{o:.2}"))
                .unwrap_or_else(|| "-".into());
            println!(
                "{:<18} {:>10.5} {:>6} {:>12.3e} {:>12.3e} {:>12.1} {:>7} {:>6}{}",
                r.integrator.name(),
                r.dt,
                r.steps,
                r.max_error,
                r.rms_error,
                r.seconds_per_step * 1e6,
                order,
                r.compared,
                if front.contains(&i) { " *" } else { "" }
            );
        }
    }
    if let Some(path) = &plot {
        let title = format!("{name}: error after {duration:.3} s vs time per step");
        if let Err(e) = write_atomically(
            path,
            accuracy_svg(&rows, &title).as_bytes(),
            &[args.file.as_path()],
        ) {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
        if !args.json {
            println!("plot written to {}", path.display());
        }
    }
    match budget {
        Some(b) if !b.met() => {
            eprintln!(
                "{name}: error: the accuracy budget is exceeded: {:.3e} {u} against {:.3e} {u}",
                b.measured,
                b.budget,
                u = b.unit
            );
            ExitCode::FAILURE
        }
        _ => ExitCode::SUCCESS,
    }
}

/// `--field-sweep`: the baked field's error against evaluated forces, per resolution and filter.
fn field_sweep_report(
    args: &AccuracyArgs,
    name: &str,
    effect: &plume_compiler::EffectSpec,
    engine: &Engine,
    bar: &ProgressBar,
    duration: f64,
    gpu: &Option<plume_runtime::Gpu>,
) -> ExitCode {
    if args.resolutions.iter().any(|&n| !(2..=256).contains(&n)) {
        eprintln!("error: every --resolutions value must be in 2..=256");
        return ExitCode::FAILURE;
    }
    bar.set_style(
        ProgressStyle::with_template("baking [{bar:30}] {pos}/{len} runs ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let result = field_sweep(
        engine,
        effect,
        &args.resolutions,
        duration,
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    let (rows, evaluated) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let engine_name = gpu
        .as_ref()
        .map(|g| g.describe())
        .unwrap_or_else(|| "cpu reference (f64)".into());
    if args.json {
        let items: Vec<_> = rows
            .iter()
            .map(|r| {
                serde_json::json!({
                    "resolution": r.resolution, "filter": format!("{:?}", r.filter),
                    "max_error": r.max_error, "rms_error": r.rms_error,
                    "seconds_per_step": r.seconds_per_step,
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({ "effect": name, "engine": engine_name, "duration": duration,
                                "evaluated_seconds_per_step": evaluated, "rows": items })
        );
        return ExitCode::SUCCESS;
    }
    println!(
        "{name}: position error after {duration:.4} s of the baked field against every force evaluated per particle"
    );
    println!(
        "engine: {engine_name}; evaluated: {:.1} us/step",
        evaluated * 1e6
    );
    println!(
        "{:>10}  {:<10} {:>12} {:>12} {:>12}",
        "nodes", "filter", "max err (m)", "rms err (m)", "us/step"
    );
    for r in &rows {
        println!(
            "{:>10}  {:<10} {:>12.3e} {:>12.3e} {:>12.1}",
            format!("{0}^3", r.resolution),
            format!("{:?}", r.filter),
            r.max_error,
            r.rms_error,
            r.seconds_per_step * 1e6
        );
    }
    ExitCode::SUCCESS
}
