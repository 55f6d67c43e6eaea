//! `plume`: check, compile, run, render, preview, benchmark and measure the accuracy of
//! particle effects.

mod accuracy;
mod bench;
mod load;
mod preview;
mod render;
mod reports;
mod run;
mod scene_depth;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use plume_compiler::graph::compile_graph_str;
use plume_compiler::schema::State;
use plume_compiler::{CompileOptions, Integrator};

/// Plume compiles declarative particle effects (RON) into fused, validated WGSL compute kernels.
#[derive(Parser, Debug)]
#[command(name = "plume", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check effect files: errors and warnings with their locations; exit 1 on any error.
    Check {
        /// Effect files (.ron).
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Compile one effect and print its WGSL (compute or draw module), IR or layout.
    Compile {
        /// The effect file (.ron).
        file: PathBuf,
        /// Write to this file instead of standard output.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// What to print.
        #[arg(long, value_enum, default_value_t = Emit::Wgsl)]
        emit: Emit,
        /// For an effect with groups: the group to print (default: the top-level one).
        #[arg(long)]
        group: Option<String>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Run an effect on the GPU (or the CPU reference) and print a summary; optionally export.
    Run(run::RunArgs),
    /// Time the update against a copy kernel moving the same bytes.
    Bench(bench::BenchArgs),
    /// Measure every integrator's error against time per step.
    Accuracy(accuracy::AccuracyArgs),
    /// Simulate and render headless to a PNG (last frame or --sheet) or an animated GIF.
    Render(render::RenderArgs),
    /// Show the effect live in a window, reloading it whenever its file changes.
    Preview(preview::PreviewArgs),
    /// List the adapters wgpu sees.
    Adapters {
        /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
        #[arg(long)]
        backend: Option<String>,
    },
}

/// What `plume compile` prints.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum Emit {
    /// The WGSL compute module (spawn_prepare, spawn and update kernels, or a stateless evaluate).
    Wgsl,
    /// The WGSL draw module (the vertex shader that reads particles from the GPU buffers, and
    /// the sprite's fragment shader).
    Draw,
    /// The WGSL trail draw module (effects with `render.trail`: the ribbons' vertex and
    /// fragment shaders).
    Trail,
    /// The WGSL module of the flock's grid search (effects with `Flock(neighbors: Grid(..))`).
    FlockSearch,
    /// The IR after the passes.
    Ir,
    /// The particle struct, bytes of state per particle and the bindings.
    Layout,
}

/// Values that replace the effect file's own.
#[derive(clap::Args, Debug, Default)]
pub(crate) struct Overrides {
    /// Seconds per step.
    #[arg(long)]
    dt: Option<f64>,
    /// Random seed.
    #[arg(long)]
    seed: Option<u32>,
    /// Integrator: Euler, SemiImplicitEuler, Verlet, Midpoint, Rk4, Exact or Auto.
    #[arg(long, value_parser = parse_integrator)]
    integrator: Option<Integrator>,
    /// Integration substeps per step.
    #[arg(long)]
    substeps: Option<u32>,
    /// State: Auto (stateless where exact), Stateful or Stateless.
    #[arg(long, value_parser = parse_state)]
    state: Option<State>,
}

impl Overrides {
    pub(crate) fn options(&self) -> CompileOptions {
        CompileOptions {
            dt: self.dt,
            seed: self.seed,
            integrator: self.integrator,
            substeps: self.substeps,
            sort: None,
            state: self.state,
            base_dir: None,
            placed: false,
            bursts: false,
            live_params: false,
            step_only: false,
            files: None,
            receive_shadows: false,
            accuracy_camera: None,
        }
    }
}

pub(crate) fn parse_integrator(s: &str) -> Result<Integrator, String> {
    Integrator::from_name(s).ok_or_else(|| {
        format!("unknown integrator `{s}`; expected Euler, SemiImplicitEuler, Verlet, Midpoint, Rk4, Exact or Auto")
    })
}

pub(crate) fn parse_state(s: &str) -> Result<State, String> {
    State::from_name(s)
        .ok_or_else(|| format!("unknown state `{s}`; expected Auto, Stateful or Stateless"))
}

/// Where `plume` remembers accuracy calibrations between runs: `$PLUME_CACHE_DIR` (empty:
/// nowhere), else `$XDG_CACHE_HOME/plume`, else `$HOME/.cache/plume`.
fn cache_dir() -> Option<PathBuf> {
    let var = |name| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(dir) = std::env::var_os("PLUME_CACHE_DIR") {
        return (!dir.is_empty()).then(|| PathBuf::from(dir));
    }
    var("XDG_CACHE_HOME")
        .map(|d| PathBuf::from(d).join("plume"))
        .or_else(|| var("HOME").map(|h| PathBuf::from(h).join(".cache").join("plume")))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    plume_compiler::calibration::cache::remember_calibrations_in(cache_dir());
    match cli.command {
        Command::Check { files } => check(&files),
        Command::Compile {
            file,
            output,
            emit,
            group,
            overrides,
        } => compile(
            &file,
            output.as_deref(),
            emit,
            group.as_deref(),
            &overrides.options(),
        ),
        Command::Run(args) => run::run(&args),
        Command::Render(args) => render::render(&args),
        Command::Preview(args) => preview::preview(&args),
        Command::Accuracy(args) => accuracy::accuracy(&args),
        Command::Bench(args) => bench::bench_command(&args),
        Command::Adapters { backend } => {
            let adapters = plume_runtime::GpuChoice { backend }.list_adapters();
            if adapters.is_empty() {
                eprintln!("no adapters found; without a GPU install Mesa (Debian: `apt-get install mesa-vulkan-drivers` or `libegl1 libgl1-mesa-dri`)");
                return ExitCode::FAILURE;
            }
            for a in adapters {
                println!("{a}");
            }
            ExitCode::SUCCESS
        }
    }
}

fn check(files: &[PathBuf]) -> ExitCode {
    let (mut failed, mut warnings) = (0usize, 0usize);
    for file in files {
        let Ok(load::Source { name, text: source }) = load::read(file) else {
            failed += 1;
            continue;
        };
        match compile_graph_str(
            &source,
            &load::options_for(file, &CompileOptions::default()),
        ) {
            Ok(compiled) => {
                let found = compiled.all_warnings();
                warnings += found.items.len();
                if !found.is_empty() {
                    eprintln!("{}", found.render(&name, &source));
                }
                print_accuracy(&name, &compiled);
            }
            Err(e) => {
                failed += 1;
                eprintln!("{}", e.render(&name, &source));
            }
        }
    }
    let ok = files.len() - failed;
    eprintln!(
        "checked {} file(s): {ok} ok, {failed} with errors, {warnings} warning(s)",
        files.len()
    );
    if failed > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// Prints what each group's accuracy budget chose (`plume check`, `plume compile`).
fn print_accuracy(name: &str, graph: &plume_compiler::graph::CompiledGraph) {
    for group in &graph.groups {
        if let Some(budget) = &group.effect.ir.accuracy {
            match graph.groups.len() {
                1 => eprintln!("{name}: note: {}", budget.describe()),
                _ => eprintln!(
                    "{name}: note: group {:?}: {}",
                    group.name,
                    budget.describe()
                ),
            }
        }
    }
}

fn compile(
    file: &Path,
    output: Option<&Path>,
    emit: Emit,
    group: Option<&str>,
    options: &CompileOptions,
) -> ExitCode {
    let (load::Source { name, .. }, graph) = match load::compiled_graph(file, options) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let names: Vec<&str> = graph.groups.iter().map(|g| g.name.as_str()).collect();
    let index = match group {
        None => 0,
        Some(wanted) => match names.iter().position(|n| *n == wanted) {
            Some(i) => i,
            None => {
                eprintln!(
                    "{name}: error: --group {wanted:?}: no such group (the groups are {})",
                    names.join(", ")
                );
                return ExitCode::FAILURE;
            }
        },
    };
    if names.len() > 1 {
        eprintln!(
            "{name}: note: group {:?} of {} ({}; --group picks another)",
            names[index],
            names.len(),
            names.join(", ")
        );
    }
    print_accuracy(&name, &graph);
    let compiled = graph.groups[index].effect.clone();
    eprintln!(
        "{name}: note: integrator {} ({})",
        compiled.ir.integrator.name(),
        compiled.ir.integrator_reason
    );
    eprintln!(
        "{name}: note: {} ({})",
        if compiled.ir.stateless.is_some() {
            "stateless"
        } else {
            "stateful"
        },
        compiled.ir.state_reason
    );
    let text = match emit {
        Emit::Wgsl => compiled.wgsl,
        Emit::Draw => compiled.draw_wgsl,
        Emit::Trail => match compiled.trail_wgsl {
            Some(text) => text,
            None => {
                return no_module(
                    &name,
                    "trail",
                    "no render.trail, so it has no trail draw module",
                )
            }
        },
        Emit::FlockSearch => match compiled.flock_search_wgsl {
            Some(text) => text,
            None => {
                return no_module(
                    &name,
                    "flock-search",
                    "no Flock force with a Grid search, so it has no search module",
                )
            }
        },
        Emit::Ir => compiled.ir.to_string(),
        Emit::Layout => compiled.layout.to_string(),
    };
    match output {
        None => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Some(out) => {
            match plume_runtime::outputs::write_atomically(out, text.as_bytes(), &[file]) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

/// `--emit KIND` of an effect without that module: says why, and fails.
fn no_module(name: &str, kind: &str, why: &str) -> ExitCode {
    eprintln!("{name}: error: --emit {kind}: the effect has {why}");
    ExitCode::FAILURE
}
