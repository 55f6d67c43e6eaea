//! An effect as an entity: [`PlumeEffect`], the component that names an effect file and says
//! how this instance of it plays, and [`PlumeBurst`], particles fired from game code.

use std::collections::BTreeMap;

use bevy::camera::visibility::{self, VisibilityClass};
use bevy::prelude::*;
use bevy::render::sync_world::SyncToRenderWorld;

use crate::asset::PlumeEffectAsset;

/// Where an effect's particles live.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
pub enum SimulationSpace {
    /// In the world: each particle starts where the entity was when it was emitted, then
    /// moves on its own, so a moving emitter leaves its particles behind (a rocket's smoke, a
    /// running character's dust). The effect's forces, colliders and kill volumes are in world
    /// coordinates. Such an effect is always stateful.
    #[default]
    World,
    /// In the entity's own space: the particles move, turn and scale with the entity (a
    /// flame on a torch that is carried, a trail of sparks on a spinning wheel's rim).
    Local,
}

/// Which of Plume's renderers draws an effect for a camera. Both draw in Bevy's transparent
/// phase into the camera's format and MSAA, every look: in 3D tested against the camera's
/// depth, in 2D sorted with the sprites by the entity's z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
pub enum PlumeDraw {
    /// The compute renderer for an effect of 65,536 particles or more on a GPU adapter,
    /// where compute beats the raster units, by far on GPUs that have few of them
    /// (docs/performance.md, "The compute renderer");
    /// the raster one for smaller effects (the compute one costs a few passes over the whole
    /// image per effect), on a CPU adapter (lavapipe, llvmpipe) and wherever the compute one
    /// cannot draw. In 2D, the raster one always (it tests the 2D depth; the compute one
    /// cannot read it).
    #[default]
    Auto,
    /// Plume's raster pipelines in the camera's transparent pass.
    Raster,
    /// The compute renderer (Plume's `Effect::compute_renderer`): after the camera's opaque pass
    /// it composites the effect into an image of its own, every pixel tested (and for
    /// `render.soft` faded) against the camera's depth, and one full-screen triangle in the
    /// transparent pass puts that image over the camera's. Where it cannot draw (a camera
    /// whose viewport is not its whole target, an effect the compute renderer refuses) the raster one
    /// draws, and the reason is logged once. In 2D it composites before the main pass with no
    /// depth to read (Bevy 0.20 keeps a 2D camera's depth a render attachment) and its image
    /// is tested against the 2D depth at the entity's depth: what is drawn in front of the
    /// entity's z hides the whole effect.
    Compute,
}

/// When an effect's time runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
pub enum PlumeSimulate {
    /// Every frame, seen or not.
    #[default]
    Always,
    /// Only in frames where some camera sees the entity (its `ViewVisibility`, from its
    /// bounds: declared in the file, or measured on the GPU). Unseen, it freezes: no steps, no
    /// spawns, its particles held where they were, and it takes up where it stopped when seen
    /// again (the time it was unseen is not caught up).
    WhenVisible,
}

/// The capacity from which `PlumeDraw::Auto` draws an effect with the compute renderer on a GPU
/// adapter. The compute renderer costs a few passes over the camera's image per effect
/// whatever its particles (clearing, merging and putting an image of 8 bytes a pixel over the
/// camera's), where the raster one costs per particle: small effects are drawn faster by the
/// raster renderer, large ones far faster by the compute one (docs/bevy.md has both measured).
pub const AUTO_COMPUTE_CAPACITY: u64 = 65_536;

/// A Plume effect playing at this entity's [`Transform`]: the effect file's handle and how
/// this instance plays. Every instance simulates on its own, on Bevy's render device, and is
/// drawn in Bevy's transparent 3D phase for every camera that sees it.
///
/// ```no_run
/// use bevy::prelude::*;
/// use bevy_plume::{PlumeEffect, PlumeEffectAsset};
///
/// fn spawn_fountain(mut commands: Commands, assets: Res<AssetServer>) {
///     let fountain: Handle<PlumeEffectAsset> = assets.load("fountain.plume.ron");
///     commands.spawn((PlumeEffect::new(fountain), Transform::from_xyz(0.0, 0.5, 0.0)));
/// }
/// ```
#[derive(Component, Clone, Debug, Reflect)]
#[reflect(Component)]
#[require(
    Transform,
    Visibility,
    VisibilityClass,
    SyncToRenderWorld,
    PlumeThinning
)]
#[component(on_add = visibility::add_visibility_class::<PlumeEffect>)]
pub struct PlumeEffect {
    /// The effect file.
    pub handle: Handle<PlumeEffectAsset>,
    /// Where the particles live (default: the world, left behind by a moving entity).
    pub space: SimulationSpace,
    /// Which renderer draws it (default: the faster one for the adapter).
    pub draw: PlumeDraw,
    /// Whether time runs for this effect (false: it freezes, still drawn).
    pub playing: bool,
    /// Whether its time runs while no camera sees it (default: always).
    pub simulate: PlumeSimulate,
    /// How fast the effect's time runs against the app's (1: real time).
    pub time_scale: f32,
    /// The fraction of its spawns this instance keeps (0 to 1; default 1, all): fewer
    /// particles, each as the file makes it, from the next step on. Its level of detail and
    /// the game's budget thin it further ([`PlumeThinning`]).
    pub spawn_scale: f32,
    /// Replaces the file's `seed` for this instance (the effect is compiled again for it,
    /// once per distinct seed), so two instances of one file need not look alike.
    pub seed: Option<u32>,
    /// Seconds of the effect's life simulated at once when it starts (or restarts), so that
    /// it appears already running.
    pub warm_up: f32,
    /// Bumped by [`Self::restart`]: each change starts the effect again from nothing.
    pub generation: u32,
    /// Values for the file's `params`, read by its custom forces at run time: change one and
    /// the particles feel it from the next frame, with no recompiling. An instance with any
    /// value here is compiled to read params at run time (once per file); the first value set
    /// on an instance that had none rebuilds it (it starts again), so set them at spawn
    /// ([`Self::with_param`]) when they will change later.
    pub params: BTreeMap<String, f32>,
    /// Whether the instance takes bursts from code ([`Self::with_bursts`]). It then is never
    /// stateless (a closed form cannot know when a burst comes).
    pub takes_bursts: bool,
    /// Bursts fired and not yet taken ([`Self::burst`]): the render world takes them all at
    /// the frame's extraction and spawns them at the effect's next step. Bursts fired before
    /// the effect's file has loaded are dropped.
    pub bursts: Vec<PlumeBurst>,
    /// A Bevy mesh every particle of the file's top group is drawn as, instead of its sprite
    /// or its file's mesh ([`Self::with_mesh`]).
    pub mesh: Option<Handle<Mesh>>,
}

/// Particles fired from game code (an impact, a footstep): `count` particles of one of the
/// effect's emitters (its shape, speeds, lifetime and looks) spawned at the next step, moved
/// by `position` and given `velocity` more. Both are in the entity's space: for an entity at
/// the origin with no rotation or scale, `position` is the world position.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
pub struct PlumeBurst {
    /// How many particles.
    pub count: u32,
    /// Added to each spawn position (m, in the entity's space).
    pub position: Vec3,
    /// Added to each spawn velocity (m/s, in the entity's space).
    pub velocity: Vec3,
    /// Which of the group's emitters spawns them (default 0, the first).
    pub emitter: u32,
    /// Which group of a graph effect (default 0, the top level).
    pub group: usize,
}

impl PlumeBurst {
    /// The runtime's burst: the same count, emitter, offset and added velocity.
    pub(crate) fn to_runtime(self) -> plume_compiler::bursts::Burst {
        plume_compiler::bursts::Burst::new(self.emitter, self.count)
            .at(self.position.to_array())
            .with_velocity(self.velocity.to_array())
    }

    /// `count` particles of the first emitter, where and as fast as it spawns them.
    pub fn new(count: u32) -> Self {
        Self {
            count,
            position: Vec3::ZERO,
            velocity: Vec3::ZERO,
            emitter: 0,
            group: 0,
        }
    }

    /// Moved by `position` (in the entity's space).
    pub fn at(self, position: Vec3) -> Self {
        Self { position, ..self }
    }

    /// With `velocity` added to each particle's.
    pub fn with_velocity(self, velocity: Vec3) -> Self {
        Self { velocity, ..self }
    }

    /// From emitter `emitter` of group `group`.
    pub fn from_emitter(self, group: usize, emitter: u32) -> Self {
        Self {
            group,
            emitter,
            ..self
        }
    }
}

impl PlumeEffect {
    /// The effect file `handle`, playing at real time from its start, the file's seed.
    pub fn new(handle: Handle<PlumeEffectAsset>) -> Self {
        Self {
            handle,
            space: SimulationSpace::World,
            draw: PlumeDraw::Auto,
            playing: true,
            simulate: PlumeSimulate::Always,
            time_scale: 1.0,
            spawn_scale: 1.0,
            seed: None,
            warm_up: 0.0,
            generation: 0,
            params: BTreeMap::new(),
            takes_bursts: false,
            bursts: Vec::new(),
            mesh: None,
        }
    }

    /// With every particle of the file's top group drawn as `mesh` (a triangle list with
    /// positions in the main world, such as `meshes.add(Sphere::new(0.5))`): placed, turned,
    /// sized, coloured and lit as the file's `render.mesh` draws an OBJ file's, one unit of
    /// the mesh the particle's size. The file is compiled again with it, off the main thread;
    /// the entity draws nothing until that is done.
    pub fn with_mesh(self, mesh: Handle<Mesh>) -> Self {
        Self {
            mesh: Some(mesh),
            ..self
        }
    }

    /// Taking bursts from code ([`Self::burst`]).
    pub fn with_bursts(self) -> Self {
        Self {
            takes_bursts: true,
            ..self
        }
    }

    /// With the file's param `name` set to `value`, read at run time (see [`Self::params`]).
    pub fn with_param(mut self, name: impl Into<String>, value: f32) -> Self {
        self.params.insert(name.into(), value);
        self
    }

    /// Sets the file's param `name` to `value` from the next frame on.
    pub fn set_param(&mut self, name: impl Into<String>, value: f32) {
        self.params.insert(name.into(), value);
    }

    /// Fires `burst` at the next frame (the effect must take bursts: [`Self::with_bursts`];
    /// otherwise the render world says so once).
    pub fn burst(&mut self, burst: PlumeBurst) {
        self.bursts.push(burst);
    }

    /// With its particles in `space`.
    pub fn with_space(self, space: SimulationSpace) -> Self {
        Self { space, ..self }
    }

    /// Whether it steps this frame, seen by a camera or not: while playing, and unseen only
    /// when it simulates always.
    pub(crate) fn steps_when(&self, seen: bool) -> bool {
        self.playing && (seen || self.simulate == PlumeSimulate::Always)
    }

    /// Simulated as `simulate` says (only while seen: [`PlumeSimulate::WhenVisible`]).
    pub fn with_simulate(self, simulate: PlumeSimulate) -> Self {
        Self { simulate, ..self }
    }

    /// Keeping `spawn_scale` (0 to 1) of its spawns ([`Self::spawn_scale`]).
    pub fn with_spawn_scale(self, spawn_scale: f32) -> Self {
        Self {
            spawn_scale,
            ..self
        }
    }

    /// Drawn by `draw`'s renderer.
    pub fn with_draw(self, draw: PlumeDraw) -> Self {
        Self { draw, ..self }
    }

    /// With `seed` instead of the file's.
    pub fn with_seed(self, seed: u32) -> Self {
        Self {
            seed: Some(seed),
            ..self
        }
    }

    /// Starting as if it had already run for `seconds`.
    pub fn with_warm_up(self, seconds: f32) -> Self {
        Self {
            warm_up: seconds,
            ..self
        }
    }

    /// With its time running `scale` times as fast as the app's.
    pub fn with_time_scale(self, scale: f32) -> Self {
        Self {
            time_scale: scale,
            ..self
        }
    }

    /// Starts the effect again from nothing (its warm-up included) on the next frame.
    pub fn restart(&mut self) {
        self.generation = self.generation.wrapping_add(1);
    }
}

/// The bursts fired this frame, by effect entity: taken from the entities in `Last`
/// ([`take_bursts`]) and read by the render world at extraction.
#[derive(Resource, Default)]
pub(crate) struct FiredBursts(pub Vec<(Entity, Vec<PlumeBurst>)>);

/// Takes every effect's fired bursts into [`FiredBursts`] (so each spawns once, whenever in the
/// frame it was fired). Only effects that fired any are touched, so change detection sees no
/// others.
pub(crate) fn take_bursts(
    mut effects: Query<(Entity, &mut PlumeEffect)>,
    mut fired: ResMut<FiredBursts>,
) {
    fired.0.clear();
    for (entity, mut effect) in &mut effects {
        if !effect.bursts.is_empty() {
            fired.0.push((entity, std::mem::take(&mut effect.bursts)));
        }
    }
}

/// Makes every 3D camera's depth texture bindable while an effect may be drawn by the compute
/// renderer, which copies the depth after the opaque pass (Bevy makes it a render attachment
/// only, unless asked).
pub(crate) fn bindable_camera_depth(
    mut cameras: Query<&mut Camera3d>,
    effects: Query<&PlumeEffect>,
) {
    use bevy::render::render_resource::TextureUsages;
    if effects.iter().all(|e| e.draw == PlumeDraw::Raster) {
        return;
    }
    for mut camera in &mut cameras {
        let usages = TextureUsages::from(camera.depth_texture_usages);
        if !usages.contains(TextureUsages::TEXTURE_BINDING) {
            camera.depth_texture_usages = (usages | TextureUsages::TEXTURE_BINDING).into();
        }
    }
}

/// How much of its spawns an effect keeps this frame, and why: written by the plugin each
/// frame ([`crate::PlumeSystems::Thinning`]) on every effect entity, reflected so an inspector
/// shows it.
#[derive(Component, Clone, Copy, Debug, PartialEq, Reflect)]
#[reflect(Component)]
pub struct PlumeThinning {
    /// The fraction of every spawn kept: the entity's `spawn_scale`, times its level of
    /// detail, times its share of the budget.
    pub scale: f32,
    /// Logical pixels across its bounds on the camera where they are largest: 0 when no
    /// camera sees it, infinite when it has no bounds or a camera is inside them.
    pub pixels: f32,
    /// Particles its file keeps alive unthinned (estimated: `Effect::expected_alive`).
    pub expected_alive: u64,
    /// Its steps paused by the budget's GPU time ([`crate::PlumeBudget::step_gpu_ms`]): an
    /// unseen effect that stands still until seen or allowed again.
    pub paused: bool,
}

impl Default for PlumeThinning {
    fn default() -> Self {
        Self {
            scale: 1.0,
            pixels: f32::INFINITY,
            expected_alive: 0,
            paused: false,
        }
    }
}

/// Asks for an effect entity's GPU time. While [`crate::PlumeDiagnosticsPlugin`] is added
/// and the device has timestamp queries, the entity's steps are recorded apart (never batched,
/// in compute passes of their own between two timestamps, rather than in the pass the other
/// effects share) and `steps_ms` holds their GPU time, read back without waiting (a frame or
/// two old). Where the device also writes timestamps inside passes, `draw_ms` holds its draws'
/// GPU time, summed over the cameras that draw it: each camera's preparation (depth sort,
/// culling, the compute renderer's passes) and its draw inside Bevy's transparent pass.
/// Recording apart costs a little CPU and GPU time of its own, so ask for it on the effects
/// you look at, not on every one.
///
/// ```no_run
/// # use bevy::prelude::*;
/// # use bevy_plume::{PlumeEffect, PlumeGpuTime};
/// # fn spawn(mut commands: Commands, assets: Res<AssetServer>) {
/// commands.spawn((PlumeEffect::new(assets.load("smoke.plume.ron")), PlumeGpuTime::default()));
/// # }
/// fn report(timed: Query<(&Name, &PlumeGpuTime)>) {
///     for (name, time) in &timed {
///         if let (Some(steps), Some(draws)) = (time.steps_ms, time.draw_ms) {
///             info!("{name}: {steps:.3} ms of steps, {draws:.3} ms of draws");
///         }
///     }
/// }
/// ```
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Reflect)]
#[reflect(Component)]
pub struct PlumeGpuTime {
    /// GPU milliseconds of the entity's last timed frame of steps (None before the first
    /// reading, and where the device has no timestamp queries).
    pub steps_ms: Option<f32>,
    /// GPU milliseconds of the entity's draws in its last timed frame, over every camera
    /// that drew it (None before the first reading, while no camera draws it, and where the
    /// device has no timestamps inside passes).
    pub draw_ms: Option<f32>,
}
