//! The preview's state once the window is open: the window and its surface, the device, the
//! effect running now and its draw, the clock, the camera and the figures' sources. What the
//! window does with it is in `window` (events), `live` (loading the effect), `frame` (drawing
//! one frame) and `figures` (the on-screen text).

use std::sync::Arc;
use std::time::Instant;

use plume_runtime::{Effect, EffectRenderer, Gpu};
use winit::dpi::PhysicalPosition;
use winit::window::Window;

use super::clock::StepClock;
use super::frame_target::FrameTarget;
use super::orbit::Orbit;
use super::overlay::Overlay;
use super::probe::Probe;
use super::reload::{EffectFile, Watcher};

/// The effect running now (one group or several) and its draw.
pub(super) struct Loaded {
    pub(super) effect: Effect,
    pub(super) renderer: EffectRenderer,
    /// What the renderer draws into (a compute renderer is made again for a new size).
    pub(super) target: plume_runtime::DrawTarget,
    /// The meshes the effect names, drawn around it (None: it names none).
    pub(super) meshes: Option<plume_runtime::outputs::Scene>,
    /// The meshes' lights (the file's, or the plain ones), and the pick of the lights its
    /// particles give off (`render.light`), added to them as readings come back.
    pub(super) scene_lights: plume_runtime::Lights,
    pub(super) particle_lights: Option<plume_runtime::ParticleLights>,
    /// What the compiler chose, for the figures.
    pub(super) about: String,
    /// Its warnings, rendered.
    pub(super) warnings: String,
}

/// Mouse drags in progress.
#[derive(Default)]
pub(super) struct Mouse {
    pub(super) orbit: bool,
    pub(super) pan: bool,
    pub(super) at: Option<PhysicalPosition<f64>>,
}

/// Everything that exists once the window is open.
pub(super) struct Running {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) gpu: Gpu,
    pub(super) target: FrameTarget,
    pub(super) overlay: Overlay,
    pub(super) probe: Probe,
    pub(super) file: EffectFile,
    pub(super) watcher: Option<Watcher>,
    pub(super) effect: Option<Loaded>,
    /// The last reload's problem (errors, a missing file), shown until the next good one.
    pub(super) problem: Option<String>,
    pub(super) clock: StepClock,
    pub(super) orbit: Option<Orbit>,
    pub(super) mouse: Mouse,
    pub(super) last_frame: Instant,
    pub(super) frame_ms: f64,
    /// When the reloaded file was saved, until the new effect's first frame is shown.
    pub(super) reload_started: Option<std::time::SystemTime>,
    /// Save to new frame, for the last reload.
    pub(super) reload_ms: Option<f64>,
    pub(super) frames: u32,
    pub(super) screenshot: bool,
    pub(super) help: bool,
    /// When a one-shot effect (no emitter with a rate) was first seen with nothing alive.
    pub(super) finished_at: Option<Instant>,
    /// How the particles are drawn (`--draw`).
    pub(super) draw: crate::render::DrawMethod,
}
