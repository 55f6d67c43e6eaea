//! `plume preview FILE`: a live window for effect authors. The effect runs in real time through
//! the embedding API, the file is watched and hot-reloaded (a valid change restarts the effect,
//! an invalid one keeps the last good effect and shows where the error is), the camera orbits,
//! pans and zooms with the mouse, and the figures (live and dropped particles, GPU time per
//! step and per draw, the integrator, whether it is stateless, warnings) are on screen.
//!
//! One module per job: `clock` (real time to fixed steps), `orbit` (the camera), `reload`
//! (watching and recompiling), `frame_target` (the frame texture and its copy to the window),
//! `overlay` (on-screen text), `probe` (GPU figures read without waiting), and the winit
//! application that ties them together: `state` (what exists once the window is open),
//! `window` (opening it and its events), `live` (loading, reloading and restarting the
//! effect), `frame` (one frame's steps and draw, screenshots) and `figures` (the text shown).

mod clock;
mod figures;
mod frame;
mod frame_target;
mod live;
mod orbit;
mod overlay;
mod probe;
mod reload;
mod state;
mod window;

use std::path::PathBuf;
use std::process::ExitCode;

use plume_compiler::CompileOptions;
use plume_runtime::GpuChoice;

use crate::render::DrawMethod;
use crate::Overrides;

/// Options of `plume preview`.
#[derive(clap::Args, Debug)]
#[command(after_help = format!("Keys and mouse in the window:\n  {}", window::KEYS.replace("   ", "\n  ")))]
pub struct PreviewArgs {
    /// The effect file (.ron); it is reloaded whenever it changes on disk.
    file: PathBuf,
    /// Window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = crate::render::parse_size)]
    size: (u32, u32),
    /// Draw this many frames (one step each), then close: for scripts and tests.
    #[arg(long)]
    frames: Option<u32>,
    /// With --frames: write the last frame (the effect's image, without the on-screen text) to
    /// this PNG before closing.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
    #[arg(long)]
    backend: Option<String>,
    /// How the particles are drawn: `raster` (the render pipeline), `compute` (the compute
    /// renderer of the embedding API, tested against the scene's meshes), or `auto`: compute on
    /// a GPU where it draws the effect, else raster. The figures say which.
    #[arg(long, value_enum, default_value_t = DrawMethod::Auto)]
    draw: DrawMethod,
    #[command(flatten)]
    overrides: Overrides,
}

/// What the window needs from the command line.
pub struct Options {
    file: PathBuf,
    overrides: CompileOptions,
    backend: Option<String>,
    frames: Option<u32>,
    screenshot: Option<PathBuf>,
    size: (u32, u32),
    draw: DrawMethod,
}

impl Options {
    fn backends(&self) -> wgpu::Backends {
        GpuChoice {
            backend: self.backend.clone(),
        }
        .backends()
    }
}

/// Runs `plume preview`.
pub fn preview(args: &PreviewArgs) -> ExitCode {
    if args.frames == Some(0) {
        eprintln!("error: --frames must be at least 1");
        return ExitCode::FAILURE;
    }
    if let Some(out) = &args.screenshot {
        if out
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
            != Some("png")
        {
            eprintln!(
                "{}: error: the screenshot must be a .png file",
                out.display()
            );
            return ExitCode::FAILURE;
        }
    }
    let options = Options {
        file: args.file.clone(),
        overrides: args.overrides.options(),
        backend: args.backend.clone(),
        frames: args.frames,
        screenshot: args.screenshot.clone(),
        size: args.size,
        draw: args.draw,
    };
    match window::run(options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
