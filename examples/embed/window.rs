//! The embed example's window: the host's surface, depth buffer and real-time loop (the
//! headless mode, which tests/embed.rs runs, draws through the same `Host`).

use super::*;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

struct Open {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    depth: wgpu::TextureView,
    host: Host,
    start: Instant,
    steps: u64,
}

struct App {
    path: PathBuf,
    /// What is drawn, and with which renderer.
    layers: Layers,
    open: Option<Open>,
    error: Option<Box<dyn Error>>,
}

fn depth_view(device: &wgpu::Device, w: u32, h: u32) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("host depth"),
            size: wgpu::Extent3d {
                width: w.max(1),
                height: h.max(1),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            // Bindable: the compute renderer copies it (`--draw compute`).
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

impl App {
    fn open(&self, event_loop: &ActiveEventLoop) -> Result<Open, Box<dyn Error>> {
        let window = Arc::new(
            event_loop.create_window(
                Window::default_attributes()
                    .with_title(format!("Plume embedded: {}", self.path.display())),
            )?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(window.clone())?;
        let (adapter, device, queue) = host_device(&instance, Some(&surface))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("the window's surface is not supported by the adapter")?;
        // Effect colours are plain 8-bit values (as in `plume render`'s images): prefer a
        // surface format without sRGB encoding, so the window looks like the renders.
        if let Some(linear) = surface
            .get_capabilities(&adapter)
            .formats
            .into_iter()
            .find(|f| !f.is_srgb())
        {
            config.format = linear;
        }
        surface.configure(&device, &config);
        let host = Host::new(&device, &queue, &self.path, config.format, self.layers)?;
        Ok(Open {
            depth: depth_view(&device, config.width, config.height),
            window,
            surface,
            config,
            device,
            host,
            start: Instant::now(),
            steps: 0,
        })
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.open.is_none() {
            match self.open(event_loop) {
                Ok(open) => self.open = Some(open),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(open) = &mut self.open else {
            return;
        };
        match event {
            WindowEvent::CloseRequested
            | WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        logical_key: Key::Named(NamedKey::Escape),
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            } => event_loop.exit(),
            WindowEvent::Resized(size) => {
                open.config.width = size.width.max(1);
                open.config.height = size.height.max(1);
                open.surface.configure(&open.device, &open.config);
                open.depth = depth_view(&open.device, open.config.width, open.config.height);
            }
            WindowEvent::RedrawRequested => {
                // Fixed steps of the effect's dt, as many as the wall clock has passed.
                // Past 8 behind, the rest are dropped (slow motion, never a spiral).
                let due = (open.start.elapsed().as_secs_f64() / open.host.dt()) as u64;
                let steps = due.saturating_sub(open.steps).min(8);
                open.steps = due;
                let frame = match open.surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(f)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
                    _ => {
                        open.surface.configure(&open.device, &open.config);
                        open.window.request_redraw();
                        return;
                    }
                };
                let view = frame.texture.create_view(&Default::default());
                let aspect = open.config.width as f32 / open.config.height as f32;
                let camera = open.host.camera(aspect);
                if let Err(e) = open
                    .host
                    .frame(&view, &open.depth, &camera, steps, self.layers)
                {
                    self.error = Some(e);
                    event_loop.exit();
                    return;
                }
                open.host.present(frame);
                open.window.request_redraw();
            }
            _ => {}
        }
    }
}

/// Opens the window and runs until it is closed.
pub fn run(path: PathBuf, layers: Layers) -> Result<(), Box<dyn Error>> {
    let event_loop = EventLoop::new().map_err(|e| {
        format!(
            "cannot open a window ({e}): no display? Use --headless OUT.png, or run under xvfb-run"
        )
    })?;
    let mut app = App {
        path,
        layers,
        open: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
