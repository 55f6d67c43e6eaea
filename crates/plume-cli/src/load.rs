//! The steps every command starts with: read the file, compile or check it, print its
//! diagnostics, open a GPU. Each returns `Err(ExitCode::FAILURE)` after printing why.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use plume_compiler::graph::{compile_graph_str, CompiledGraph};
use plume_compiler::{compile_effect, parse, CompileOptions, EffectSpec};
use plume_runtime::{Gpu, GpuChoice};

/// An effect file's display name and text.
pub struct Source {
    /// The path as given, for messages.
    pub name: String,
    /// The file's text.
    pub text: String,
}

/// Reads `file`.
pub fn read(file: &Path) -> Result<Source, ExitCode> {
    let name = file.display().to_string();
    match std::fs::read_to_string(file) {
        Ok(text) => Ok(Source { name, text }),
        Err(e) => {
            eprintln!("{name}: error: cannot read file: {e}");
            Err(ExitCode::FAILURE)
        }
    }
}

/// The directory files named in `file` (a texture) are relative to: the file's own.
pub fn base_dir(file: &Path) -> Option<PathBuf> {
    file.parent().map(Path::to_path_buf)
}

/// `options` for compiling `file`: its files resolved from its directory.
pub fn options_for(file: &Path, options: &CompileOptions) -> CompileOptions {
    CompileOptions {
        base_dir: base_dir(file),
        ..options.clone()
    }
}

/// Reads and compiles `file` with `options` as a graph of one or more groups; prints every
/// warning.
pub fn compiled_graph(
    file: &Path,
    options: &CompileOptions,
) -> Result<(Source, CompiledGraph), ExitCode> {
    let src = read(file)?;
    match compile_graph_str(&src.text, &options_for(file, options)) {
        Ok(g) => {
            let warnings = g.all_warnings();
            if !warnings.is_empty() {
                eprintln!("{}", warnings.render(&src.name, &src.text));
            }
            Ok((src, g))
        }
        Err(e) => {
            eprintln!("{}", e.render(&src.name, &src.text));
            Err(ExitCode::FAILURE)
        }
    }
}

/// For a file with groups or events: its name and the parsed effect, checked to compile as
/// written (errors printed; Err holds the exit code). None for a file of one group, or one
/// that does not parse (the single-group path reports that). `step_only`: compiled to be
/// stepped, not drawn (`CompileOptions::step_only`: a missing sprite texture is no error).
pub fn graph_effect(
    file: &Path,
    step_only: bool,
) -> Option<(String, Result<EffectSpec, ExitCode>)> {
    let src = read(file).ok()?;
    let mut effect = parse(&src.text).ok()?;
    plume_compiler::graph::graph_field(&effect)?;
    effect.base_dir = base_dir(file);
    effect.step_only = step_only;
    let checked = match plume_compiler::graph::compile_graph(&effect, &src.text) {
        Ok(_) => Ok(effect),
        Err(e) => {
            eprintln!("{}", e.render(&src.name, &src.text));
            Err(ExitCode::FAILURE)
        }
    };
    Some((src.name, checked))
}

/// Whether a compiled graph is a plain effect (one group, no events).
pub fn single(graph: &CompiledGraph) -> bool {
    graph.groups.len() == 1 && graph.streams.is_empty()
}

/// Reads and parses `file`, and checks it compiles as written (so errors point at the file),
/// for commands that derive their own variants of the effect. `step_only`: as for
/// [`graph_effect`].
pub fn checked(file: &Path, step_only: bool) -> Result<(Source, EffectSpec), ExitCode> {
    let src = read(file)?;
    let mut effect = match parse(&src.text) {
        Ok(e) => e,
        Err(d) => {
            eprintln!("{}", d.render(&src.name, &src.text));
            return Err(ExitCode::FAILURE);
        }
    };
    effect.base_dir = base_dir(file);
    effect.step_only = step_only;
    if plume_compiler::graph::graph_field(&effect).is_some() {
        eprintln!(
            "{}: error: this command does not run effects with groups or events yet (plume check, compile, run, render, preview and bench do)",
            src.name
        );
        return Err(ExitCode::FAILURE);
    }
    if let Err(e) = compile_effect(&effect, &src.text) {
        eprintln!("{}", e.render(&src.name, &src.text));
        return Err(ExitCode::FAILURE);
    }
    Ok((src, effect))
}

/// Opens the best adapter among `backend` (or `WGPU_BACKEND`, or all).
pub fn gpu(backend: &Option<String>) -> Result<Gpu, ExitCode> {
    Gpu::new(&GpuChoice {
        backend: backend.clone(),
    })
    .map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::FAILURE
    })
}
