//! The preview window: a winit application that owns a wgpu surface and runs the effect through
//! the embedding API (`GraphInstance::advance_timed`, each group's `prepare_draw` and
//! `EffectRenderer::draw`), stepping it in real time, reloading it when its file changes, and
//! showing its figures.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use plume_compiler::graph::CompiledGraph;
use plume_runtime::offscreen::read_texture;
use plume_runtime::{DrawTarget, EffectInstance, EffectRenderer, Gpu, GraphInstance};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::clock::StepClock;
use super::orbit::Orbit;
use super::overlay::{Overlay, Panel};
use super::probe::Probe;
use super::reload::{EffectFile, Outcome, Watcher};
use super::scene::Scene;
use super::Options;

const WHITE: [f32; 4] = [0.92, 0.92, 0.92, 1.0];
const DIM: [f32; 4] = [0.65, 0.68, 0.72, 1.0];
const YELLOW: [f32; 4] = [1.0, 0.85, 0.35, 1.0];
const RED: [f32; 4] = [1.0, 0.42, 0.38, 1.0];
const GREEN: [f32; 4] = [0.5, 0.9, 0.55, 1.0];

/// The keys, as `--help` and the window list them.
pub const KEYS: &str = "drag: orbit   right or middle drag: pan   wheel: zoom   space: pause   .: one step   r: restart   [ ]: half / double speed   s: screenshot   h: hide help   esc: quit";

/// The effect running now: its groups (one for an effect without groups) and their draws.
struct Loaded {
    graph: GraphInstance,
    renderers: Vec<EffectRenderer>,
    /// What the compiler chose, for the figures.
    about: String,
    /// Its warnings, rendered.
    warnings: String,
}

/// Mouse drags in progress.
#[derive(Default)]
struct Mouse {
    orbit: bool,
    pan: bool,
    at: Option<PhysicalPosition<f64>>,
}

/// Everything that exists once the window is open.
struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    scene: Scene,
    overlay: Overlay,
    probe: Probe,
    file: EffectFile,
    watcher: Option<Watcher>,
    effect: Option<Loaded>,
    /// The last reload's problem (errors, a missing file), shown until the next good one.
    problem: Option<String>,
    clock: StepClock,
    orbit: Option<Orbit>,
    mouse: Mouse,
    last_frame: Instant,
    frame_ms: f64,
    /// When the reloaded file was saved, until the new effect's first frame is shown.
    reload_started: Option<std::time::SystemTime>,
    /// Save to new frame, for the last reload.
    reload_ms: Option<f64>,
    frames: u32,
    screenshot: bool,
    help: bool,
    /// When a one-shot effect (no emitter with a rate) was first seen with nothing alive.
    finished_at: Option<Instant>,
}

struct App {
    options: Options,
    running: Option<Running>,
    result: Result<(), String>,
}

/// Opens the window and runs until it is closed (or, with `--frames`, until the frames are
/// drawn and the screenshot written).
pub fn run(options: Options) -> Result<(), String> {
    let event_loop = EventLoop::new().map_err(|e| {
        format!(
            "cannot open a window: no display ({e}). `plume preview` needs a desktop session \
             (X11 or Wayland). Without one, render the effect to a file with \
             `plume render {} --out out.gif`, or start a virtual display with `xvfb-run plume preview ...` \
             (Debian: apt-get install xvfb)",
            options.file.display()
        )
    })?;
    let mut app = App {
        options,
        running: None,
        result: Ok(()),
    };
    event_loop.run_app(&mut app).map_err(|e| e.to_string())?;
    app.result
}

impl App {
    fn open(&self, event_loop: &ActiveEventLoop) -> Result<Running, String> {
        let (w, h) = self.options.size;
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title(format!("plume preview: {}", self.options.file.display()))
                        .with_inner_size(PhysicalSize::new(w, h)),
                )
                .map_err(|e| format!("cannot open a window: {e}"))?,
        );
        let backends = self.options.backends();
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ));
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| format!("cannot draw into the window: {e}"))?;
        let (gpu, adapter) =
            Gpu::for_surface(&instance, &surface, backends).map_err(|e| e.to_string())?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("the window's surface is not supported by the adapter")?;
        // Effect colours are plain 8-bit values (as in `plume render`'s images): no sRGB.
        if let Some(plain) = surface
            .get_capabilities(&adapter)
            .formats
            .into_iter()
            .find(|f| !f.is_srgb())
        {
            config.format = plain;
        }
        surface.configure(&gpu.device, &config);
        eprintln!("adapter: {}", gpu.describe());
        let mut running = Running {
            scene: Scene::new(&gpu.device, config.format, (config.width, config.height)),
            overlay: Overlay::new(&gpu.device, &gpu.queue, config.format),
            probe: Probe::new(&gpu.device, &gpu.queue, gpu.has_timestamps()),
            file: EffectFile::new(&self.options.file, self.options.overrides.clone()),
            watcher: match Watcher::new(&self.options.file) {
                Ok(w) => Some(w),
                Err(e) => {
                    eprintln!("warning: {e}; the file will not be reloaded");
                    None
                }
            },
            window,
            surface,
            config,
            gpu,
            effect: None,
            problem: None,
            clock: StepClock::new(1.0 / 60.0),
            orbit: None,
            mouse: Mouse::default(),
            last_frame: Instant::now(),
            frame_ms: 0.0,
            reload_started: None,
            reload_ms: None,
            frames: 0,
            screenshot: false,
            help: true,
            finished_at: None,
        };
        running.reload(None);
        if running.effect.is_none() {
            // Nothing to show at start: the first load failed. Its diagnostics are printed.
            return Err(running
                .problem
                .unwrap_or_else(|| "the effect did not compile".into()));
        }
        Ok(running)
    }
}

impl Loaded {
    /// The top-level group: its clock, counters and background are the effect's.
    fn instance(&self) -> &EffectInstance {
        &self.graph.groups()[0]
    }
}

impl Running {
    /// Reloads the file (`noticed`: when a change was seen; None for the first load).
    fn reload(&mut self, noticed: Option<Instant>) {
        match self.file.reload() {
            Outcome::Unchanged => {}
            Outcome::Replaced(compiled, warnings) => {
                if !warnings.is_empty() {
                    eprintln!("{warnings}");
                }
                match self.load(*compiled, warnings) {
                    Ok(()) => {
                        eprintln!("{}: loaded", self.file.name());
                        self.problem = None;
                        // Timed from the save itself (the file's modification time), which
                        // includes the watcher's debounce and the frame in progress.
                        self.reload_started = noticed.and(self.file.saved_at());
                    }
                    Err(e) => {
                        eprintln!("{}: error: {e}", self.file.name());
                        self.problem = Some(e);
                    }
                }
            }
            Outcome::Invalid(diagnostics) | Outcome::Unreadable(diagnostics) => {
                eprintln!("{diagnostics}");
                if self.effect.is_some() {
                    eprintln!("{}: the last good effect keeps running", self.file.name());
                }
                self.problem = Some(diagnostics);
            }
        }
    }

    /// Replaces the running effect by `compiled`, from t = 0; the camera stays where the user
    /// put it (it starts as the effect's own).
    fn load(&mut self, compiled: CompiledGraph, warnings: String) -> Result<(), String> {
        let top = &compiled.groups[0].effect.ir;
        let mut about = format!(
            "{}: integrator {}; {}",
            top.name,
            top.integrator.name(),
            if top.stateless.is_some() {
                "stateless (0 bytes of state)"
            } else {
                "stateful"
            }
        );
        if compiled.groups.len() > 1 {
            let names: Vec<&str> = compiled.groups[1..]
                .iter()
                .map(|g| g.name.as_str())
                .collect();
            about.push_str(&format!(
                "; groups {} ({} events)",
                names.join(", "),
                compiled.streams.len()
            ));
        }
        let dt = top.dt;
        let camera = top.camera;
        let glow = top.render.glow;
        let graph = GraphInstance::new(&self.gpu, compiled).map_err(|e| e.to_string())?;
        let target = DrawTarget::new(Scene::draw_format(glow.as_ref()));
        let renderers = graph
            .groups()
            .iter()
            .map(|g| g.renderer(&target))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        // Last, and all or nothing: the old effect keeps drawing into a matching scene if this
        // fails.
        self.scene.set_glow(&self.gpu, glow)?;
        self.effect = Some(Loaded {
            graph,
            renderers,
            about,
            warnings,
        });
        // Counters read from the old effect mean nothing for the new one.
        self.probe.totals = None;
        let mut clock = StepClock::new(dt);
        clock.scale = self.clock.scale;
        clock.paused = self.clock.paused;
        self.clock = clock;
        self.orbit
            .get_or_insert_with(|| Orbit::from_effect(&camera));
        Ok(())
    }

    /// Draws one frame. Returns false when the preview should close.
    fn frame(&mut self, options: &Options) -> Result<bool, String> {
        if let Some(noticed) = self.watcher.as_ref().and_then(Watcher::changed) {
            self.reload(Some(noticed));
        }
        let now = Instant::now();
        let elapsed = now - self.last_frame;
        self.last_frame = now;
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * elapsed.as_secs_f64() * 1e3;
        // A scripted run takes one step per frame, so its frames are the same every run.
        let steps = match options.frames {
            Some(_) => 1,
            None => self.clock.steps_due(elapsed),
        };
        let (w, h) = (self.config.width, self.config.height);
        self.scene.resize(&self.gpu, (w, h))?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let mut stepped = None;
        let mut drawn = false;
        let mut counters = None;
        if let Some(loaded) = &mut self.effect {
            let recorded = loaded
                .graph
                .advance_timed(&mut encoder, steps, self.probe.step_writes())
                .map_err(|e| e.to_string())?;
            stepped = recorded.then_some(steps);
            let camera = self
                .orbit
                .as_ref()
                .expect("an orbit exists once an effect is loaded")
                .camera(w as f32 / h.max(1) as f32);
            for (group, renderer) in loaded.graph.groups().iter().zip(&loaded.renderers) {
                group
                    .prepare_draw(&mut encoder, renderer, &camera)
                    .map_err(|e| e.to_string())?;
            }
            let bg = loaded.instance().effect().ir.render.background;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("effect"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: self.scene.view(),
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: bg.x,
                            g: bg.y,
                            b: bg.z,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: self.probe.draw_writes(),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            for renderer in &loaded.renderers {
                renderer.draw(&mut pass);
            }
            drop(pass);
            self.scene.finish(&mut encoder);
            drawn = true;
            let top = loaded.instance();
            counters = top
                .counters()
                .map(|c| (c, top.steps_done(), top.effect().ir.capacity));
        }
        self.probe.record(&mut encoder, stepped, drawn, counters);
        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            _ => {
                self.surface.configure(&self.gpu.device, &self.config);
                None
            }
        };
        if let Some(texture) = &surface_texture {
            let view = texture.texture.create_view(&Default::default());
            let panels = self.panels();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.scene.blit(&mut pass);
            self.overlay.draw(
                &self.gpu.device,
                &self.gpu.queue,
                &mut pass,
                (w, h),
                &panels,
            );
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.probe.submitted();
        self.gpu.take_error().map_err(|e| e.to_string())?;
        if let Some(texture) = surface_texture {
            self.window.pre_present_notify();
            self.gpu.queue.present(texture);
        }
        if let Some(saved) = self.reload_started.take() {
            self.reload_ms = Some(saved.elapsed().map_or(0.0, |d| d.as_secs_f64() * 1e3));
            eprintln!(
                "{}: reloaded, {:.0} ms from save to new frame",
                self.file.name(),
                self.reload_ms.unwrap_or(0.0)
            );
        }
        self.probe.collect(&self.gpu.device);
        self.loop_if_finished(options);
        self.frames += 1;
        if std::mem::take(&mut self.screenshot) {
            let path = screenshot_path(&self.file.name(), self.effect.as_ref());
            self.save_screenshot(&path)?;
            eprintln!("wrote {}", path.display());
        }
        if let Some(n) = options.frames {
            if self.frames >= n {
                if let Some(path) = &options.screenshot {
                    self.save_screenshot(path)?;
                    eprintln!("wrote {} ({} frames)", path.display(), self.frames);
                }
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Writes the last frame (the effect's image, without the on-screen text) as a PNG.
    fn save_screenshot(&self, path: &std::path::Path) -> Result<(), String> {
        let (w, h) = self.scene.size();
        let pixels =
            read_texture(&self.gpu, self.scene.texture(), w, h).map_err(|e| e.to_string())?;
        let png = plume_runtime::images::png(&plume_runtime::images::Frame8 {
            width: w,
            height: h,
            pixels,
        })
        .map_err(|e| e.to_string())?;
        plume_runtime::export::write_atomically(
            path,
            &png,
            &[std::path::Path::new(&self.file.name())],
        )
        .map_err(|e| e.to_string())
    }

    /// The on-screen text: figures, warnings, errors and the keys.
    fn panels(&mut self) -> Vec<Panel> {
        let mut lines: Vec<(String, [f32; 4])> = Vec::new();
        if let Some(loaded) = &mut self.effect {
            let i = loaded.instance();
            let state = if self.clock.paused { "  paused" } else { "" };
            lines.push((
                format!(
                    "{}   t = {:.2} s (step {})   speed x{}{state}",
                    self.file.name(),
                    i.time(),
                    i.steps_done(),
                    self.clock.scale
                ),
                WHITE,
            ));
            lines.push((loaded.about.clone(), DIM));
            // A stateless effect counts on the CPU; a stateful one's counters come back
            // from the GPU a frame or two late.
            let totals = match i.counters() {
                Some(_) => self.probe.totals,
                None => i.totals().ok(),
            };
            if let Some(t) = totals {
                let whose = match loaded.graph.groups().len() {
                    1 => String::new(),
                    _ => format!(" ({})", loaded.graph.names()[0]),
                };
                lines.push((
                    format!("live {}   dropped {}{whose}", t.alive, t.dropped),
                    WHITE,
                ));
            }
            let stateless = loaded.graph.groups().iter().all(|g| g.is_stateless());
            let steps = match (stateless, self.probe.step_ms) {
                (true, _) => "steps: bookkeeping only (stateless: no GPU work)".to_string(),
                (false, Some(ms)) => format!(
                    "steps {ms:.3} ms GPU ({} in that frame)",
                    self.probe.steps_timed
                ),
                (false, None) => "steps -".to_string(),
            };
            let timing = match self.probe.draw_ms {
                None if !self.gpu.has_timestamps() => format!(
                    "frame {:.1} ms (no GPU timestamps on this adapter)",
                    self.frame_ms
                ),
                draw => format!(
                    "{steps}   draw {}   frame {:.1} ms",
                    draw.map_or("-".into(), |d| format!("{d:.3} ms GPU")),
                    self.frame_ms
                ),
            };
            lines.push((timing, WHITE));
            if let Some(ms) = self.reload_ms {
                lines.push((
                    format!("reloaded: {ms:.0} ms from save to new frame"),
                    GREEN,
                ));
            }
            for w in loaded.warnings.lines().take(8) {
                lines.push((w.to_string(), YELLOW));
            }
        }
        if let Some(problem) = &self.problem {
            for l in problem.lines().take(14) {
                lines.push((l.to_string(), RED));
            }
            if self.effect.is_some() {
                lines.push(("(the last good effect keeps running)".into(), RED));
            }
        }
        let mut panels = vec![Panel {
            lines,
            bottom: false,
        }];
        if self.help {
            // The keys, grouped so that a line never splits one.
            panels.push(Panel {
                lines: vec![(KEYS.replace("   ", " | "), DIM)],
                bottom: true,
            });
        }
        panels
    }

    /// Restarts the last good effect from t = 0 (the camera stays).
    fn restart(&mut self) {
        if let Some(good) = self.file.good().cloned() {
            let warnings = self
                .effect
                .as_ref()
                .map(|l| l.warnings.clone())
                .unwrap_or_default();
            if let Err(e) = self.load(good, warnings) {
                self.problem = Some(e);
            }
            self.clock.restart();
        }
        self.finished_at = None;
    }

    /// A one-shot effect (bursts only) whose particles have all died starts again half a
    /// second later, so the window never sits empty. Not in scripted runs.
    fn loop_if_finished(&mut self, options: &Options) {
        if options.frames.is_some() || self.clock.paused {
            return;
        }
        let Some(loaded) = &self.effect else {
            return;
        };
        // With groups, the top group's end is not the effect's (its children live on).
        let top = loaded.instance();
        let one_shot = loaded.graph.groups().len() == 1
            && top.effect().ir.emitters.iter().all(|e| e.rate <= 0.0);
        let totals = match top.counters() {
            Some(_) => self.probe.totals,
            None => top.totals().ok(),
        };
        let done =
            one_shot && top.steps_done() > 0 && totals.is_some_and(|t| t.alive == 0 && t.steps > 0);
        if !done {
            self.finished_at = None;
            return;
        }
        let since = *self.finished_at.get_or_insert_with(Instant::now);
        if since.elapsed().as_secs_f64() > 0.5 {
            self.restart();
        }
    }

    fn key(&mut self, key: &Key) -> bool {
        match key {
            Key::Named(NamedKey::Escape) => return false,
            Key::Named(NamedKey::Space) => self.clock.paused = !self.clock.paused,
            Key::Character(c) => match c.as_str() {
                "." => self.clock.step_once(),
                "r" => self.restart(),
                "[" => self.clock.slower(),
                "]" => self.clock.faster(),
                "s" => self.screenshot = true,
                "h" => self.help = !self.help,
                _ => {}
            },
            _ => {}
        }
        true
    }

    fn mouse_moved(&mut self, at: PhysicalPosition<f64>) {
        if let (Some(last), Some(orbit)) = (self.mouse.at, &mut self.orbit) {
            let (dx, dy) = (at.x - last.x, at.y - last.y);
            if self.mouse.orbit {
                orbit.orbit(dx, dy);
            } else if self.mouse.pan {
                orbit.pan(dx, dy, f64::from(self.config.height));
            }
        }
        self.mouse.at = Some(at);
    }
}

/// `name-STEP.png` beside the current directory's files, for the `s` key.
fn screenshot_path(file: &str, loaded: Option<&Loaded>) -> PathBuf {
    let stem = std::path::Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "effect".into());
    let step = loaded.map_or(0, |l| l.instance().steps_done());
    PathBuf::from(format!("{stem}-{step:06}.png"))
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(r) => {
                r.window.request_redraw();
                self.running = Some(r);
            }
            Err(e) => {
                self.result = Err(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = &mut self.running else {
            return;
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                r.config.width = size.width.max(1);
                r.config.height = size.height.max(1);
                r.surface.configure(&r.gpu.device, &r.config);
            }
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        logical_key,
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            // `key` acts on the key; it answers false for the one that closes the window.
            } if !r.key(&logical_key) => event_loop.exit(),
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => r.mouse.orbit = down,
                    MouseButton::Right | MouseButton::Middle => r.mouse.pan = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => r.mouse_moved(position),
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if let Some(orbit) = &mut r.orbit {
                    orbit.zoom(notches);
                }
            }
            WindowEvent::RedrawRequested => match r.frame(&self.options) {
                Ok(true) => r.window.request_redraw(),
                Ok(false) => event_loop.exit(),
                Err(e) => {
                    self.result = Err(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        // Keep drawing: the effect runs in real time.
        if let Some(r) = &self.running {
            r.window.request_redraw();
        }
    }
}
