//! `plume render`: simulate on the GPU and draw frames headless, straight from the particle
//! buffers (the same draw an embedding application records), to a PNG (last frame, or a
//! contact sheet with `--sheet`) or an animated GIF. Only the finished images are read back.

use std::path::PathBuf;
use std::process::ExitCode;

use indicatif::{ProgressBar, ProgressStyle};
use plume_compiler::graph::CompiledGraph;
use plume_runtime::outputs::{
    contact_sheet, gif, png, write_atomically, ComputeOffscreen, Frame8, Offscreen, Scene,
};
use plume_runtime::{Effect, Gpu, GpuChoice, RuntimeError};

use crate::{load, Overrides};

/// Options of `plume render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The effect file (.ron).
    file: PathBuf,
    /// Frames to render.
    #[arg(long, default_value_t = 60)]
    frames: u32,
    /// Simulation steps between frames (the first frame is taken after this many steps).
    #[arg(long, default_value_t = 2)]
    every: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Output: .png (the last frame, or a contact sheet with --sheet) or .gif (the animation).
    #[arg(long)]
    out: PathBuf,
    /// With a .png output: tile every frame into one contact sheet.
    #[arg(long)]
    sheet: bool,
    /// How frames are drawn: `raster` (the render pipeline an embedding host uses), `compute`
    /// (the compute renderer: compute shaders only, the same image; faster where raster units
    /// are few, as on an H100), or `auto`: the compute renderer on a GPU where it draws the
    /// effect, else raster.
    #[arg(long, value_enum, default_value_t = DrawMethod::Auto)]
    draw: DrawMethod,
    /// Leave out the scene: without it, the meshes the effect names (its mesh colliders and
    /// mesh emitters) are drawn, plain grey, behind and in front of the particles.
    #[arg(long)]
    no_scene: bool,
    /// Backends to search: vulkan, gl, metal, dx12 (comma-separated); default WGPU_BACKEND or all.
    #[arg(long)]
    backend: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
}

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size `{s}` must look like 640x360"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size `{s}` must look like 640x360"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 {
        return Err(format!("size `{s}` must be at least 1x1"));
    }
    Ok((w, h))
}

/// How `plume render` draws its frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DrawMethod {
    /// The compute renderer where it is faster and draws the effect, else the render pipeline.
    Auto,
    /// The render pipeline: the effect's draw module, as an embedding host draws it.
    Raster,
    /// The compute renderer: the same image from compute shaders only.
    Compute,
}

impl DrawMethod {
    /// The method `auto` stands for on `gpu` for `graph`, and why. The compute renderer is far faster than
    /// the raster pipeline on GPUs whose raster units are few (docs/performance.md, "The compute
    /// renderer") and slower on llvmpipe, whose raster path is the CPU's; it draws every group's
    /// sprites (any texture, orientation, rotation and height, glowing or not), ribbons and
    /// solid mesh particles; the scene's meshes are drawn by the raster pipeline first and the
    /// compute renderer tests their depth (`Effect::compute_renderer`).
    pub(crate) fn resolve(self, gpu: &Gpu, graph: &CompiledGraph) -> (Self, String) {
        if self != DrawMethod::Auto {
            return (self, "as asked".into());
        }
        let irs: Vec<&plume_compiler::EffectIr> =
            graph.groups.iter().map(|g| &g.effect.ir).collect();
        let why_not = if gpu.info.device_type == wgpu::DeviceType::Cpu {
            Some("a CPU adapter rasterises faster than it splats")
        } else {
            ComputeOffscreen::why_not(&irs)
        };
        match why_not {
            Some(why) => (DrawMethod::Raster, format!("auto: {why}")),
            None => (
                DrawMethod::Compute,
                "auto: a GPU adapter, where compute beats its raster units".into(),
            ),
        }
    }
}

enum Format {
    Png,
    Gif,
}

/// Simulates `graph` and draws its frames: every group in one pass each frame, in group
/// order, from the top-level group's camera, over its background (and its glow, if any).
fn render_frames(args: &RenderArgs, graph: CompiledGraph) -> Result<Vec<Frame8>, RuntimeError> {
    let gpu = Gpu::new(&GpuChoice {
        backend: args.backend.clone(),
    })?;
    eprintln!("adapter: {}", gpu.describe());
    let (draw, why) = args.draw.resolve(&gpu, &graph);
    eprintln!(
        "draw: {} ({why})",
        match draw {
            DrawMethod::Compute => "the compute renderer",
            _ => "the raster pipeline",
        }
    );
    let (w, h) = args.size;
    // An effect that glows is drawn into an HDR image and bloomed (render.glow).
    let glow = graph.groups[0].effect.ir.render.glow;
    let target = Offscreen::with_glow(&gpu, w, h, glow.as_ref())?;
    let triangles: Vec<_> = graph
        .groups
        .iter()
        .flat_map(|g| g.effect.ir.scene_triangles())
        .collect();
    let mut scene = match args.no_scene {
        false => Scene::new(&gpu, &triangles, target.target().color_format, (w, h))?,
        true => None,
    };
    if scene.is_some() {
        eprintln!(
            "scene: {} triangles of the meshes the effect names (--no-scene leaves them out)",
            triangles.len()
        );
    }
    // The scene's lights: the file's when it names any or its look is lit (they light what its
    // particles meet too), else the plain ones; particles that give off light add theirs each
    // frame.
    let top = &graph.groups[0].effect.ir;
    let scene_lights = match top.render.lit.is_some() || top.lights_named {
        true => top.lights.clone(),
        false => Scene::plain_lights(),
    };
    // A light that casts a shadow is blocked by the meshes' shadow map.
    let scene_lights = match &mut scene {
        Some(scene) => scene.cast_shadow(&scene_lights)?,
        None => scene_lights,
    };
    if let Some(scene) = &scene {
        scene.set_lights(&scene_lights);
    }
    let mut sim = Effect::from_graph(&gpu, graph)?;
    // Over the scene's meshes the compute renderer is the embedding API's compute renderer, which tests
    // their depth; without meshes, the compute renderer draws the image alone.
    let mut renderer = match (&scene, draw) {
        (Some(_), DrawMethod::Compute) => {
            sim.compute_renderer(&Scene::target(target.target()), w, h)?
        }
        (Some(_), _) => sim.renderer(&Scene::target(target.target()))?,
        // Opaque meshes write depth into a buffer of the frame's own (Offscreen::target_for).
        (None, _) => sim.renderer(&target.target_for(&sim))?,
    };
    if let Some(scene) = &scene {
        // Soft particles fade where they meet the meshes, and lit ones are in their shadow.
        scene.bind_to(&mut renderer, &scene_lights)?;
    }
    let mut splat = match (draw, &scene) {
        (DrawMethod::Compute, None) => Some(ComputeOffscreen::new(&sim, w, h)?),
        _ => None,
    };
    let camera = target.effect_camera(&sim);
    // A SceneDepth collider meets the scene's depth: the one drawn with the frames (drawn
    // once now, so the first steps meet it too), or with splat one drawn for it alone.
    let _depth_only = match &scene {
        Some(scene) if sim.collides_with_scene_depth() => {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            scene.record(&mut encoder, target.attachment(glam::DVec3::ZERO), &camera);
            sim.set_scene_depth(
                &mut encoder,
                scene.depth_texture(),
                camera.view,
                camera.proj,
            )?;
            gpu.queue.submit([encoder.finish()]);
            None
        }
        None if !args.no_scene => {
            crate::scene_depth::bind_effect_scene(&gpu, &mut sim, &camera, (w, h))?
        }
        _ => {
            if sim.collides_with_scene_depth() {
                eprintln!("note: --no-scene: the SceneDepth collider meets nothing");
            }
            None
        }
    };
    let particle_lights = match &scene {
        Some(_) => Some(sim.particle_lights()?).filter(|p| !p.is_empty()),
        None => None,
    };
    let bar = frames_bar(args.frames);
    let mut frames = Vec::with_capacity(args.frames as usize);
    for _ in 0..args.frames {
        sim.run(u64::from(args.every), |_| {})?;
        if let (Some(scene), Some(particles)) = (&scene, &particle_lights) {
            scene.set_lights(&scene_lights.with_sources(particles.read(&sim)?));
        }
        // Drawn from the GPU buffers (sorted on the GPU with sort: true); only the image is
        // read back.
        let pixels = match &mut splat {
            Some(splat) => splat.render(&sim, &camera)?,
            None => match &scene {
                Some(scene) => target.render_over_scene(&sim, &renderer, &camera, scene)?,
                None => target.render(&sim, &renderer, &camera)?,
            },
        };
        frames.push(Frame8 {
            width: w,
            height: h,
            pixels,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(frames)
}

fn frames_bar(frames: u32) -> ProgressBar {
    let bar = ProgressBar::new(u64::from(frames));
    bar.set_style(
        ProgressStyle::with_template("rendering [{bar:30}] {pos}/{len} frames ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}

/// Runs `plume render`.
pub fn render(args: &RenderArgs) -> ExitCode {
    let name = args.file.display().to_string();
    let format = match args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") => Format::Png,
        Some("gif") => Format::Gif,
        _ => {
            eprintln!(
                "{}: error: the output must be a .png or .gif file",
                args.out.display()
            );
            return ExitCode::FAILURE;
        }
    };
    if args.frames == 0 || args.every == 0 {
        eprintln!("error: --frames and --every must be at least 1");
        return ExitCode::FAILURE;
    }
    let (_, graph) = match load::compiled_graph(&args.file, &args.overrides.options()) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let dt = graph.groups[0].effect.ir.dt;
    let delay_ms = ((f64::from(args.every) * dt * 1000.0).round() as u32).max(20);
    let frames = render_frames(args, graph);
    let encoded = frames.and_then(|frames| match format {
        Format::Png if args.sheet => png(&contact_sheet(&frames)?),
        Format::Png => png(frames.last().expect("at least one frame")),
        Format::Gif => gif(&frames, delay_ms),
    });
    let bytes = match encoded {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = write_atomically(&args.out, &bytes, &[args.file.as_path()]) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    eprintln!("wrote {} ({} bytes)", args.out.display(), bytes.len());
    ExitCode::SUCCESS
}
