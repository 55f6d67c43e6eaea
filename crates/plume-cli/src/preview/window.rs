//! The preview window: a winit application that owns a wgpu surface and runs the effect through
//! the embedding API (`Effect::advance_timed`, `Effect::prepare_draw` and
//! `EffectRenderer::draw`), stepping it in real time, reloading it when its file changes, and
//! showing its figures.

use std::sync::Arc;
use std::time::Instant;

use plume_runtime::Gpu;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::clock::StepClock;
use super::frame_target::FrameTarget;
use super::overlay::Overlay;
use super::probe::Probe;
use super::reload::{EffectFile, Watcher};
use super::state::{Mouse, Running};
use super::Options;

/// The keys, as `--help` and the window list them.
pub const KEYS: &str = "drag: orbit   right or middle drag: pan   wheel: zoom   space: pause   .: one step   r: restart   [ ]: half / double speed   s: screenshot   h: hide help   esc: quit";

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
            target: FrameTarget::new(&gpu.device, config.format, (config.width, config.height)),
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
            draw: self.options.draw,
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
impl Running {
    pub(super) fn key(&mut self, key: &Key) -> bool {
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

    pub(super) fn mouse_moved(&mut self, at: PhysicalPosition<f64>) {
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
