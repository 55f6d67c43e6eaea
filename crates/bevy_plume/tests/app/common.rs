//! A Bevy app for the plugin's tests: no window, Plume's plugin, one camera drawing into an
//! image over a black background, frames stepped by hand at a fixed 1/60 s, and the image
//! read back as RGBA8.

#![allow(dead_code)] // each test module uses its own part of the harness

use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bevy::asset::AssetLoadFailedEvent;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::time::TimeUpdateStrategy;
use bevy_plume::headless::{default_plugins, Headless};
use bevy_plume::{PlumeEffect, PlumeEffectAsset, PlumePlugin};

/// Runs the tests one at a time: each holds the guard while its app lives (two Bevy apps
/// would share two CPU cores and one driver).
pub fn serial() -> std::sync::MutexGuard<'static, ()> {
    static ONE_APP: Mutex<()> = Mutex::new(());
    ONE_APP
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Image size of every test.
pub const WIDTH: u32 = 160;
/// Image size of every test.
pub const HEIGHT: u32 = 90;
/// The camera's distance from the origin, on +z looking down −z.
pub const CAMERA_DISTANCE: f32 = 10.0;
/// The most frames a capture waits for its screenshot before the test fails.
const CAPTURE_FRAMES: usize = 600;

/// The test app and its target image.
pub struct Harness {
    pub app: App,
    image: Handle<Image>,
    /// Compile errors the asset server reported, as text.
    pub load_errors: Arc<Mutex<Vec<String>>>,
}

impl Harness {
    /// An app reading assets from `asset_dir`, with a camera at (0, 0, 10) looking at the
    /// origin (Bevy's default perspective, 45° vertical), MSAA off. Files are not watched
    /// (a late event from the watcher would reload an effect mid-test and restart it).
    pub fn new(asset_dir: &Path) -> Self {
        Self::with_watching(asset_dir, false)
    }

    /// An app ([`Self::new`]) in a fresh asset folder `name` (see [`asset_dir`]) that holds one
    /// effect file, `dots.plume.ron`, of `text`, and that file's handle.
    pub fn with_effect(name: &str, text: &str) -> (Self, Handle<PlumeEffectAsset>) {
        let dir = asset_dir(name);
        std::fs::write(dir.join("dots.plume.ron"), text).expect("the effect file is written");
        let mut h = Self::new(&dir);
        let handle = h.load("dots.plume.ron");
        (h, handle)
    }

    /// [`Self::new`], watching the files for changes (hot reload) when `watch`.
    pub fn with_watching(asset_dir: &Path, watch: bool) -> Self {
        Self::built(asset_dir, watch, |_| {})
    }

    /// [`Self::new`] with `extra` done to the app before it is finished (more plugins).
    pub fn with_app(asset_dir: &Path, extra: impl FnOnce(&mut App)) -> Self {
        Self::built(asset_dir, false, extra)
    }

    fn built(asset_dir: &Path, watch: bool, extra: impl FnOnce(&mut App)) -> Self {
        let headless = Headless {
            out: "unused.png".into(),
            frames: 0,
            size: UVec2::new(WIDTH, HEIGHT),
            window: false,
        };
        let mut app = App::new();
        let asset_dir = asset_dir.to_str().expect("a UTF-8 path");
        app.add_plugins(
            default_plugins(Some(&headless), asset_dir).set(AssetPlugin {
                file_path: asset_dir.to_string(),
                watch_for_changes_override: Some(watch),
                ..default()
            }),
        )
        .add_plugins(PlumePlugin)
        .insert_resource(ClearColor(Color::BLACK))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 60.0,
        )));
        let load_errors = Arc::new(Mutex::new(Vec::new()));
        let errors = load_errors.clone();
        app.add_systems(
            Update,
            move |mut failed: MessageReader<AssetLoadFailedEvent<PlumeEffectAsset>>| {
                for event in failed.read() {
                    errors.lock().unwrap().push(event.error.to_string());
                }
            },
        );
        extra(&mut app);
        app.finish();
        app.cleanup();
        let image = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba8UnormSrgb, None);
        let image = app.world_mut().resource_mut::<Assets<Image>>().add(image);
        app.world_mut().spawn((
            Camera3d::default(),
            Msaa::Off,
            RenderTarget::Image(image.clone().into()),
            Transform::from_xyz(0.0, 0.0, CAMERA_DISTANCE).looking_at(Vec3::ZERO, Vec3::Y),
        ));
        Self {
            app,
            image,
            load_errors,
        }
    }

    /// Runs `frames` frames.
    pub fn update(&mut self, frames: u32) {
        for _ in 0..frames {
            self.app.update();
        }
    }

    /// Runs frames until `done` holds (at most `limit` frames, sleeping `pause` between
    /// them: file watching needs real time); whether it held.
    pub fn update_until(
        &mut self,
        limit: u32,
        pause: Duration,
        mut done: impl FnMut(&mut Self) -> bool,
    ) -> bool {
        for _ in 0..limit {
            self.app.update();
            if done(self) {
                return true;
            }
            std::thread::sleep(pause);
        }
        false
    }

    /// Loads the effect file at `path` (relative to the asset folder) and runs frames until it
    /// has loaded or failed (at most 10 s: loading runs on other threads, slower on a busy
    /// machine), so that a test's frame counts start from a loaded effect.
    pub fn load(&mut self, path: &str) -> Handle<PlumeEffectAsset> {
        let handle: Handle<PlumeEffectAsset> = self
            .app
            .world()
            .resource::<AssetServer>()
            .load(path.to_string());
        let settled = self.update_until(2_000, Duration::from_millis(5), |h| {
            let server = h.app.world().resource::<AssetServer>();
            server.is_loaded_with_dependencies(&handle)
                || matches!(
                    server.load_state(&handle),
                    bevy::asset::LoadState::Failed(_)
                )
        });
        assert!(settled, "{path} did not load within 10 s");
        handle
    }

    /// Another camera at `transform`, MSAA off, drawing into an image of its own (returned,
    /// for [`Self::capture_of`]) over the same black.
    pub fn add_camera(&mut self, transform: Transform) -> Handle<Image> {
        let image = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba8UnormSrgb, None);
        let image = self
            .app
            .world_mut()
            .resource_mut::<Assets<Image>>()
            .add(image);
        self.app.world_mut().spawn((
            Camera3d::default(),
            Msaa::Off,
            RenderTarget::Image(image.clone().into()),
            transform,
        ));
        image
    }

    /// The next frame's image (runs frames until the capture comes back).
    pub fn capture(&mut self) -> image::RgbaImage {
        self.capture_of(self.image.clone())
    }

    /// The next frame's image of the camera drawing into `target`.
    pub fn capture_of(&mut self, target: Handle<Image>) -> image::RgbaImage {
        let slot: Arc<Mutex<Option<Image>>> = Arc::default();
        let sink = slot.clone();
        self.app
            .world_mut()
            .spawn(Screenshot::image(target))
            .observe(move |captured: On<ScreenshotCaptured>| {
                *sink.lock().unwrap() = Some(captured.image.clone());
            });
        // Usually two or three frames; lavapipe on a busy two-core machine has taken more than
        // 60 (a CI run at 6bdd6d1), so the bound is there only to end a capture that never comes.
        for _ in 0..CAPTURE_FRAMES {
            self.app.update();
            if let Some(image) = slot.lock().unwrap().take() {
                let dynamic = image.try_into_dynamic().expect("an RGBA8 image");
                return dynamic.to_rgba8();
            }
        }
        panic!("the screenshot did not come back within {CAPTURE_FRAMES} frames");
    }
}

impl Harness {
    /// Swaps the harness's 3D camera for a `Camera2d` drawing into the same image: Bevy's
    /// default orthographic view, one world unit a pixel, the origin at the image's centre,
    /// y up. MSAA off.
    pub fn use_2d(&mut self) {
        let camera = self.camera();
        self.app.world_mut().despawn(camera);
        self.app.world_mut().spawn((
            Camera2d,
            Msaa::Off,
            RenderTarget::Image(self.image.clone().into()),
        ));
    }

    /// The harness's camera (its one `Camera3d`).
    pub fn camera(&mut self) -> Entity {
        self.app
            .world_mut()
            .query_filtered::<Entity, With<Camera3d>>()
            .single(self.app.world())
            .expect("one camera")
    }

    /// An unlit wall Bevy draws (a `width` x `width` square 0.2 m thick, facing the camera)
    /// of `color`, centred at `at`.
    pub fn spawn_wall(&mut self, width: f32, color: Color, at: Vec3) -> Entity {
        let world = self.app.world_mut();
        let mesh = world
            .resource_mut::<Assets<Mesh>>()
            .add(Cuboid::new(width, width, 0.2));
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: color,
                unlit: true,
                ..default()
            });
        world
            .spawn((
                Mesh3d(mesh),
                MeshMaterial3d(material),
                Transform::from_translation(at),
            ))
            .id()
    }

    /// Runs frames until Bevy has compiled every pipeline it was asked for (it compiles in the
    /// background: a mesh spawned now is drawn, and its depth there to meet, only then); fails
    /// the test after 600 frames.
    pub fn wait_for_pipelines(&mut self) {
        self.update(5);
        let ready = self.update_until(600, Duration::from_millis(2), |h| {
            h.app
                .sub_app(bevy::render::RenderApp)
                .world()
                .resource::<bevy::render::render_resource::PipelineCache>()
                .waiting_pipelines()
                .count()
                == 0
        });
        assert!(ready, "Bevy's pipelines were not ready within 600 frames");
    }

    /// Whether Bevy's device has timestamp queries (lavapipe has): what the GPU times need.
    pub fn has_timestamps(&self) -> bool {
        self.app
            .sub_app(bevy::render::RenderApp)
            .world()
            .resource::<bevy::render::renderer::RenderDevice>()
            .features()
            .contains(bevy::render::render_resource::WgpuFeatures::TIMESTAMP_QUERY)
    }

    /// Runs frames until every effect entity has a running instance (a world-space effect,
    /// one with a seed or params of its own, compiles its variant on Bevy's async pool first:
    /// a frame or two, many more on a busy machine, where a fixed count of frames was not
    /// always enough); fails the test after 600 frames. For tests whose effects all load.
    pub fn wait_for_effects(&mut self) {
        let ready = self.update_until(600, Duration::from_millis(2), |h| {
            let world = h.app.world_mut();
            let effects: Vec<Entity> = world
                .query_filtered::<Entity, With<PlumeEffect>>()
                .iter(world)
                .collect();
            let render = h.app.sub_app(bevy::render::RenderApp).world();
            effects
                .iter()
                .all(|&e| bevy_plume::read_totals(render, e, 0).is_some())
        });
        assert!(ready, "the effects did not start within 600 frames");
    }

    /// The next frame's image once every effect entity runs ([`Self::wait_for_effects`]).
    pub fn capture_running(&mut self) -> image::RgbaImage {
        self.wait_for_effects();
        self.capture()
    }
}

/// Pixels whose red or green or blue channel exceeds `threshold`: (count, mean x, mean y).
pub fn lit_pixels(image: &image::RgbaImage, threshold: u8) -> (u32, f32, f32) {
    let (mut n, mut sx, mut sy) = (0u32, 0f64, 0f64);
    for (x, y, p) in image.enumerate_pixels() {
        if p.0[..3].iter().any(|&c| c > threshold) {
            n += 1;
            sx += f64::from(x) + 0.5;
            sy += f64::from(y) + 0.5;
        }
    }
    match n {
        0 => (0, f32::NAN, f32::NAN),
        _ => (n, (sx / f64::from(n)) as f32, (sy / f64::from(n)) as f32),
    }
}

/// Where a world point (x, y, 0) lands in the image, in pixels, for the harness's camera.
pub fn project(x: f32, y: f32) -> (f32, f32) {
    let half_height = CAMERA_DISTANCE * (std::f32::consts::FRAC_PI_4 / 2.0).tan();
    let half_width = half_height * WIDTH as f32 / HEIGHT as f32;
    (
        (0.5 + 0.5 * x / half_width) * WIDTH as f32,
        (0.5 - 0.5 * y / half_height) * HEIGHT as f32,
    )
}

/// A fresh asset folder under the system's temporary directory.
pub fn asset_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_plume-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    dir
}

/// A small effect: `count` particles in one burst at the origin, barely moving (drag stops
/// them within 0.13 m), living `life` seconds, of colour `rgb`, 0.15 m across.
pub fn dots(count: u32, life: f64, rgb: (f64, f64, f64)) -> String {
    let (r, g, b) = rgb;
    format!(
        r#"Effect(name: "dots", capacity: {count}, seed: 7,
    emitters: [Emitter(burst: {count}, shape: Point((0.0, 0.0, 0.0)),
        velocity: Radial(speed: (0.0, 0.5)), lifetime: Some(({life:?}, {life:?})))],
    forces: [Drag(k: 4.0)],
    render: Render(
        color: [(0.0, ({r:?}, {g:?}, {b:?}, 1.0)), (1.0, ({r:?}, {g:?}, {b:?}, 1.0))],
        size: [(0.0, 0.15), (1.0, 0.15)],
        blend: Additive))
"#
    )
}
