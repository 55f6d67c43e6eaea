//! Running an app without a window: the examples' `--headless OUT.png --frames N`, which CI
//! and benchmarks use. Every 3D camera draws into an image instead of a window; after the
//! effects have loaded (or failed to), N frames run at a fixed 1/60 s each, then the image is
//! written as a PNG and the app exits. `--window-shot OUT.png --frames N` does the same in a
//! window: its N-th frame, as the window shows it.

use std::path::PathBuf;
use std::time::Duration;

use bevy::app::{PluginGroupBuilder, ScheduleRunnerPlugin};
use bevy::asset::LoadState;
use bevy::camera::RenderTarget;
use bevy::image::Image;
use bevy::prelude::*;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{save_to_disk, Screenshot, ScreenshotCaptured};
use bevy::time::TimeUpdateStrategy;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

use crate::effect::PlumeEffect;

/// Frames allowed for the screenshot to come back before the app gives up.
const CAPTURE_GRACE_FRAMES: u32 = 240;

/// What a headless run writes and how long it runs.
#[derive(Clone, Debug, Resource)]
pub struct Headless {
    /// The PNG written at the end.
    pub out: PathBuf,
    /// Frames run once the effects have loaded.
    pub frames: u32,
    /// The image's size in pixels.
    pub size: UVec2,
    /// Whether the app keeps its window and the shot is of the window (`--window-shot`).
    pub window: bool,
}

impl Headless {
    /// Reads `--headless OUT.png [--frames N] [--size WxH]` from the command line: None
    /// without `--headless` (run in a window); an error message for a malformed value.
    pub fn from_args() -> Result<Option<Self>, String> {
        Self::parse(std::env::args().skip(1))
    }

    /// [`Self::from_args`] on any argument list (without the program name).
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Option<Self>, String> {
        let mut out = None;
        let mut window = false;
        let mut frames = 120;
        let mut size = UVec2::new(1280, 720);
        let mut args = args.into_iter();
        while let Some(arg) = args.next() {
            let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
            match arg.as_str() {
                "--headless" => out = Some(PathBuf::from(value("--headless")?)),
                "--window-shot" => {
                    out = Some(PathBuf::from(value("--window-shot")?));
                    window = true;
                }
                "--frames" => {
                    let v = value("--frames")?;
                    frames = v
                        .parse()
                        .map_err(|_| format!("--frames {v}: not a whole number"))?;
                }
                "--size" => {
                    let v = value("--size")?;
                    let (w, h) = v
                        .split_once('x')
                        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
                        .filter(|&(w, h): &(u32, u32)| w > 0 && h > 0 && w <= 8192 && h <= 8192)
                        .ok_or(format!("--size {v}: expected WIDTHxHEIGHT, 1 to 8192 each"))?;
                    size = UVec2::new(w, h);
                }
                other => return Err(format!("unknown argument {other:?}")),
            }
        }
        Ok(out.map(|out| Self {
            out,
            frames,
            size,
            window,
        }))
    }
}

/// Bevy's default plugins with assets read from `asset_dir` (watched for changes, so effect
/// files hot-reload); without a window or pipelined rendering when `headless` (so frame N
/// draws frame N's simulation).
pub fn default_plugins(headless: Option<&Headless>, asset_dir: &str) -> PluginGroupBuilder {
    let plugins = DefaultPlugins.set(AssetPlugin {
        file_path: asset_dir.to_string(),
        watch_for_changes_override: Some(true),
        ..default()
    });
    match headless {
        None => plugins,
        Some(h) if h.window => plugins.disable::<PipelinedRenderingPlugin>(),
        Some(_) => plugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .disable::<WinitPlugin>()
            .disable::<PipelinedRenderingPlugin>(),
    }
}

/// Runs the app without a window as [`Headless`] says (add it with [`default_plugins`]).
pub struct HeadlessPlugin(pub Headless);

impl Plugin for HeadlessPlugin {
    fn build(&self, app: &mut App) {
        if !self.0.window {
            app.add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
                .add_systems(PostStartup, draw_into_image)
                .add_systems(Update, redirect_new_cameras.before(count_frames));
        }
        app.insert_resource(self.0.clone())
            .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
                1.0 / 60.0,
            )))
            .init_resource::<Progress>()
            .add_systems(Update, count_frames);
    }
}

/// The image every camera draws into, and how far the run is.
#[derive(Resource, Default)]
struct Progress {
    image: Option<Handle<Image>>,
    /// Frames counted since every effect loaded (or failed to).
    frames: u32,
    /// Frames since the screenshot was asked for.
    waiting: Option<u32>,
}

/// Makes the target image.
fn draw_into_image(
    mut progress: ResMut<Progress>,
    headless: Res<Headless>,
    mut images: ResMut<Assets<Image>>,
) {
    let image = Image::new_target_texture(
        headless.size.x,
        headless.size.y,
        TextureFormat::Rgba8UnormSrgb,
        None,
    );
    progress.image = Some(images.add(image));
}

/// Points every camera (those spawned later too) at the target image.
fn redirect_new_cameras(
    mut commands: Commands,
    progress: Res<Progress>,
    cameras: Query<(Entity, Option<&RenderTarget>), With<Camera>>,
) {
    let Some(image) = &progress.image else {
        return;
    };
    for (camera, target) in &cameras {
        let ours = matches!(target, Some(RenderTarget::Image(t)) if t.handle == *image);
        if !ours {
            commands
                .entity(camera)
                .insert(RenderTarget::Image(image.clone().into()));
        }
    }
}

/// Counts frames once the effects are in, asks for the screenshot after N of them, and exits
/// when it is written (or, with an error, when it never comes).
fn count_frames(
    mut commands: Commands,
    mut progress: ResMut<Progress>,
    headless: Res<Headless>,
    effects: Query<&PlumeEffect>,
    assets: Res<AssetServer>,
    mut exit: MessageWriter<AppExit>,
) {
    if let Some(waited) = progress.waiting.as_mut() {
        *waited += 1;
        if *waited > CAPTURE_GRACE_FRAMES {
            error!("headless: the screenshot never came back");
            exit.write(AppExit::from_code(2));
        }
        return;
    }
    let settled = effects.iter().all(|e| {
        matches!(
            assets.load_state(&e.handle),
            LoadState::Loaded | LoadState::Failed(_)
        )
    });
    if !settled {
        return;
    }
    progress.frames += 1;
    if progress.frames < headless.frames {
        return;
    }
    let shot = match (&progress.image, headless.window) {
        (_, true) => Screenshot::primary_window(),
        (Some(image), false) => Screenshot::image(image.clone()),
        (None, false) => return,
    };
    progress.waiting = Some(0);
    let out = headless.out.clone();
    commands
        .spawn(shot)
        .observe(save_to_disk(out.clone()))
        .observe(
            move |_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
                info!("wrote {}", out.display());
                exit.write(AppExit::Success);
            },
        );
}
