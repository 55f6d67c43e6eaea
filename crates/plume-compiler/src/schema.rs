//! The effect file format, v1: serde types that mirror the RON document one to one.
//!
//! Field and variant names are a contract with users' files and other tools: extend, never rename.
//! Unknown fields and variants are rejected. Semantic checks live in [`crate::validate`];
//! force schemas live with the rest of each force in [`crate::forces`].

use glam::DVec3;
use serde::Deserialize;

use crate::forces::Force;

/// A 3-vector written `(x, y, z)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Vec3(pub f64, pub f64, pub f64);

impl Vec3 {
    /// As a glam f64 vector.
    pub fn d(self) -> DVec3 {
        DVec3::new(self.0, self.1, self.2)
    }
}

/// A `(min, max)` interval; values are drawn uniformly from it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub struct Range(pub f64, pub f64);

/// Three counts written `(nx, ny, nz)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub struct Counts(pub u32, pub u32, pub u32);

pub(crate) fn default_dt() -> f64 {
    1.0 / 60.0
}

pub(crate) fn default_substeps() -> u32 {
    1
}

/// A whole effect file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effect {
    /// A name for messages and outputs.
    pub name: String,
    /// Most live particles at once.
    pub capacity: u32,
    /// Seed of every random draw.
    #[serde(default)]
    pub seed: u32,
    /// Seconds per step.
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Integration substeps per step.
    #[serde(default = "default_substeps")]
    pub substeps: u32,
    /// Where particles come from, in id order.
    #[serde(default)]
    pub emitters: Vec<Emitter>,
    /// Accelerations, summed.
    #[serde(default)]
    pub forces: Vec<Force>,
    /// Named constants that custom expressions may use: `params: {"k": 0.4}`.
    #[serde(default)]
    pub params: std::collections::BTreeMap<String, f64>,
    /// Speed limit applied after every velocity update.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// How positions and velocities advance.
    #[serde(default)]
    pub integrator: Integrator,
    /// Surfaces particles bounce off.
    #[serde(default)]
    pub collide: Vec<Collider>,
    /// Volumes that kill particles at the end of a step.
    #[serde(default)]
    pub kill: Vec<KillVolume>,
    /// Draw back to front as seen from `camera`.
    #[serde(default)]
    pub sort: bool,
    /// Evaluate position-dependent forces per particle (default) or bake them into a grid.
    #[serde(default)]
    pub field: crate::field::Field,
    /// Keep per-particle state, or compute each particle from its id and age (see [`State`]).
    #[serde(default)]
    pub state: State,
    /// The viewpoint for sorting and rendering.
    #[serde(default)]
    pub camera: Camera,
    /// How particles look when rendered (an extension of v1; defaults when absent).
    #[serde(default)]
    pub render: Render,
    /// Events this (top-level) group's particles fire into other groups.
    #[serde(default)]
    pub events: Vec<crate::events::Event>,
    /// More particle groups, each with its own capacity, emitters, forces and look; the
    /// top-level fields are the first group, named `name` (see [`crate::graph`]).
    #[serde(default)]
    pub groups: Vec<crate::graph::Group>,
    /// The directory files the effect names (`render.texture.file`) are resolved against: the
    /// effect file's directory, set by whoever read the file; the current directory when None.
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

/// An RGBA colour written `(r, g, b, a)`, each in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Rgba(pub f64, pub f64, pub f64, pub f64);

/// A colour at a fraction of a particle's life, written `(t, (r, g, b, a))`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct ColorStop(pub f64, pub Rgba);

/// A sprite diameter in metres at a fraction of a particle's life, written `(t, size)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct SizeStop(pub f64, pub f64);

/// How sprites combine with what is behind them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Blend {
    /// `over` compositing: order matters, so use `sort: true`.
    #[default]
    Alpha,
    /// Colours add up (fire, sparks); order does not matter.
    Additive,
}

fn default_colors() -> Vec<ColorStop> {
    vec![
        ColorStop(0.0, Rgba(1.0, 1.0, 1.0, 1.0)),
        ColorStop(1.0, Rgba(1.0, 1.0, 1.0, 0.0)),
    ]
}

fn default_sizes() -> Vec<SizeStop> {
    vec![SizeStop(0.0, 0.1)]
}

fn default_background() -> Vec3 {
    Vec3(0.02, 0.02, 0.04)
}

/// The `render:` section: colour and size over life, blending and background.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Render {
    /// Colour gradient over the life fraction age / lifetime (0 for immortal particles).
    #[serde(default = "default_colors")]
    pub color: Vec<ColorStop>,
    /// Sprite diameter (m) over the life fraction.
    #[serde(default = "default_sizes")]
    pub size: Vec<SizeStop>,
    /// The sprite's height (its y axis) over the life fraction, when it differs from its
    /// width: then `size` is the width. For `Velocity` sprites, the length before stretching.
    #[serde(default)]
    pub size_y: Option<Vec<SizeStop>>,
    /// Opacity over the life fraction with stops of its own, `(t, alpha)`: replaces the colour
    /// stops' alpha.
    #[serde(default)]
    pub alpha: Option<Vec<SizeStop>>,
    /// Alpha or Additive.
    #[serde(default)]
    pub blend: Blend,
    /// Background colour `(r, g, b)`.
    #[serde(default = "default_background")]
    pub background: Vec3,
    /// Which way each sprite faces: the camera, stretched along the velocity, or a fixed plane.
    #[serde(default)]
    pub orient: Orient,
    /// A sprite texture (optionally a flipbook atlas) instead of the soft round dot.
    #[serde(default)]
    pub texture: Option<Texture>,
    /// Each sprite turned in its plane by a random starting angle and spin.
    #[serde(default)]
    pub rotation: Option<Rotation>,
    /// Soft particles: where a host's depth buffer is bound, a sprite fades out over this many
    /// metres in front of the scene's surfaces instead of cutting into them.
    #[serde(default)]
    pub soft: Option<f64>,
    /// Glow: `plume render` draws into an HDR image and adds a blurred copy of what is brighter
    /// than a threshold (bloom), so that bright, dense additive sprites look like light.
    #[serde(default)]
    pub glow: Option<Glow>,
    /// Trails: a ribbon behind each particle through its recent positions.
    #[serde(default)]
    pub trail: Option<Trail>,
    /// A colour per particle, picked from these by its id, that its colour over life is
    /// multiplied by (and that children of events with `inherit_color` take on).
    #[serde(default)]
    pub palette: Option<Vec<Vec3>>,
}

/// Trails (`render.trail`): a camera-facing ribbon through each particle's position now and
/// its `points - 1` most recent samples, taken every `every` steps. The samples live in a ring
/// buffer the update writes, so an effect with a trail keeps 16 bytes per past position per
/// particle more state, and is stateful.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trail {
    /// Positions the ribbon joins, the particle's own included (2 to 64).
    #[serde(default = "default_trail_points")]
    pub points: u32,
    /// Steps between two samples (1: every step).
    #[serde(default = "default_trail_every")]
    pub every: u32,
    /// Ribbon width (m) along the trail, `(t, width)`: t = 0 at the particle, 1 at the tail.
    #[serde(default = "default_trail_width")]
    pub width: Vec<SizeStop>,
    /// Colour along the trail, `(t, (r, g, b, a))`, multiplying the particle's own colour.
    #[serde(default = "default_colors")]
    pub color: Vec<ColorStop>,
}

fn default_trail_points() -> u32 {
    16
}

fn default_trail_every() -> u32 {
    1
}

fn default_trail_width() -> Vec<SizeStop> {
    vec![SizeStop(0.0, 0.05), SizeStop(1.0, 0.0)]
}

/// Bloom in `plume render`'s images (`render.glow`); an embedding host does its own
/// post-processing.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Glow {
    /// Light above this level (per channel, in the HDR image) glows.
    #[serde(default = "default_glow_threshold")]
    pub threshold: f64,
    /// How much of the blurred light is added back.
    #[serde(default = "default_glow_strength")]
    pub strength: f64,
    /// The blur's standard deviation, as a fraction of the image height.
    #[serde(default = "default_glow_radius")]
    pub radius: f64,
}

fn default_glow_threshold() -> f64 {
    0.8
}

fn default_glow_strength() -> f64 {
    1.0
}

fn default_glow_radius() -> f64 {
    0.01
}

/// Sprite rotation (`render.rotation`): each particle draws a starting angle and a spin from
/// its id, uniform in the ranges.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Starting angle range (degrees, counter-clockwise).
    #[serde(default)]
    pub angle: Range,
    /// Spin range (degrees per second, counter-clockwise).
    #[serde(default)]
    pub spin: Range,
}

impl Default for Render {
    fn default() -> Self {
        Self {
            color: default_colors(),
            size: default_sizes(),
            size_y: None,
            alpha: None,
            blend: Blend::Alpha,
            background: default_background(),
            orient: Orient::Camera,
            texture: None,
            rotation: None,
            soft: None,
            glow: None,
            trail: None,
            palette: None,
        }
    }
}

/// A sprite texture (`render.texture`): a PNG whose texels multiply the sprite's colour, or an
/// atlas of flipbook frames played over each particle's life or at a fixed rate.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Texture {
    /// The PNG file, relative to the effect file's directory.
    pub file: String,
    /// The atlas grid `(columns, rows)`: frames read left to right, top to bottom.
    #[serde(default = "one_frame")]
    pub frames: (u32, u32),
    /// How the frames play.
    #[serde(default)]
    pub play: Play,
    /// With `Rate`: each particle starts the loop at a frame drawn from its id, so particles
    /// born together do not play in step (a flock's wing beats).
    #[serde(default)]
    pub random_start: bool,
}

fn one_frame() -> (u32, u32) {
    (1, 1)
}

/// How a flipbook's frames play (`render.texture.play`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub enum Play {
    /// Once over each particle's life: frame k of n from life fraction k/n (frame 0 for a
    /// particle that never dies).
    #[default]
    OverLife,
    /// At this many frames per second of the particle's age, looping.
    Rate(f64),
}

/// How a sprite's quad is oriented (`render.orient`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Orient {
    /// Parallel to the image plane: a round dot from every side.
    #[default]
    Camera,
    /// Facing the camera, its long axis along the velocity's component in the image plane:
    /// length = max(size, min(size + stretch · speed, max_length)), width = size.
    Velocity {
        /// Metres of length per m/s of image-plane speed (seconds), >= 0.
        stretch: f64,
        /// Longest a sprite gets (m), > 0.
        max_length: f64,
    },
    /// Lying in the world plane through the particle perpendicular to this normal (a ripple
    /// on the ground: `Fixed((0.0, 1.0, 0.0))`).
    Fixed(Vec3),
}

/// One particle source.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Emitter {
    /// Particles spawned once, at step 0.
    #[serde(default)]
    pub burst: u32,
    /// Particles per second; the fractional remainder carries to the next step.
    #[serde(default)]
    pub rate: f64,
    /// Where particles start.
    pub shape: Shape,
    /// How fast and where they start moving.
    pub velocity: Velocity,
    /// Lifetime range in seconds; `None` lives forever.
    #[serde(default)]
    pub lifetime: Option<Range>,
}

/// Spawn positions.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// Every particle at one point.
    Point(Vec3),
    /// Uniform in the ball's volume.
    Sphere {
        /// Centre of the ball.
        center: Vec3,
        /// Radius (>= 0).
        radius: f64,
    },
    /// Uniform in an axis-aligned box.
    Box {
        /// Lower corner.
        min: Vec3,
        /// Upper corner.
        max: Vec3,
    },
    /// Uniform in a flat disc.
    Disc {
        /// Centre of the disc.
        center: Vec3,
        /// The disc's normal (any length but zero).
        normal: Vec3,
        /// Radius (>= 0).
        radius: f64,
    },
    /// Deterministic lattice points, handed out in x-then-y-then-z order.
    Grid {
        /// First lattice corner.
        min: Vec3,
        /// Last lattice corner.
        max: Vec3,
        /// Points per axis (>= 1 each).
        counts: Counts,
    },
    /// Listed points, handed out in order.
    Points(Vec<Vec3>),
}

/// Spawn velocities.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Velocity {
    /// The same velocity for every particle.
    Constant(Vec3),
    /// Uniform directions within a cone around `axis`.
    Cone {
        /// Cone axis (any length but zero).
        axis: Vec3,
        /// Half-angle in degrees, in [0, 180].
        angle: f64,
        /// Speed range (m/s).
        speed: Range,
    },
    /// Away from the shape's centre.
    Radial {
        /// Speed range (m/s).
        speed: Range,
    },
}

/// The integration scheme.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Integrator {
    /// Explicit (forward) Euler: first order, unstable for oscillation.
    Euler,
    /// Symplectic Euler: first order, bounded energy.
    SemiImplicitEuler,
    /// Latta's position Verlet (displacement form): second order.
    Verlet,
    /// Midpoint RK2: second order.
    Midpoint,
    /// Classic RK4: fourth order.
    Rk4,
    /// The closed-form solution (gravity, drag, noiseless wind only).
    Exact,
    /// Let the compiler choose: Exact where allowed, else SemiImplicitEuler.
    #[default]
    Auto,
}

impl Integrator {
    /// Every concrete integrator (not Auto), in order of increasing cost.
    pub const CONCRETE: [Integrator; 6] = [
        Integrator::Euler,
        Integrator::SemiImplicitEuler,
        Integrator::Verlet,
        Integrator::Midpoint,
        Integrator::Rk4,
        Integrator::Exact,
    ];

    /// The name as written in effect files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "Euler",
            Integrator::SemiImplicitEuler => "SemiImplicitEuler",
            Integrator::Verlet => "Verlet",
            Integrator::Midpoint => "Midpoint",
            Integrator::Rk4 => "Rk4",
            Integrator::Exact => "Exact",
            Integrator::Auto => "Auto",
        }
    }

    /// Parses a name as written in effect files (case-insensitive, for the command line).
    pub fn from_name(s: &str) -> Option<Self> {
        [Integrator::Auto]
            .into_iter()
            .chain(Self::CONCRETE)
            .find(|i| i.name().eq_ignore_ascii_case(s))
    }
}

/// Whether particles keep state between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum State {
    /// Stateless wherever it is exact (the Exact integrator, no kills, no sort, no drops),
    /// else stateful.
    #[default]
    Auto,
    /// Always keep position and velocity per particle (to compare against the stateless
    /// kernel, or to sort by draw order).
    Stateful,
    /// Require the stateless kernel: an error naming the cause where it cannot be used.
    Stateless,
}

impl State {
    /// The name as written in effect files.
    pub fn name(self) -> &'static str {
        match self {
            State::Auto => "Auto",
            State::Stateful => "Stateful",
            State::Stateless => "Stateless",
        }
    }

    /// Parses a name as written in effect files (case-insensitive, for the command line).
    pub fn from_name(s: &str) -> Option<Self> {
        [State::Auto, State::Stateful, State::Stateless]
            .into_iter()
            .find(|i| i.name().eq_ignore_ascii_case(s))
    }
}

pub use crate::colliders::Collider;

/// Volumes that kill particles at the end of a step.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum KillVolume {
    /// Kills particles inside the box.
    InsideBox {
        /// Lower corner.
        min: Vec3,
        /// Upper corner.
        max: Vec3,
    },
    /// Kills particles outside the box.
    OutsideBox {
        /// Lower corner.
        min: Vec3,
        /// Upper corner.
        max: Vec3,
    },
    /// Kills particles inside the ball.
    InsideSphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f64,
    },
    /// Kills particles outside the ball.
    OutsideSphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f64,
    },
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Where the camera is.
    pub eye: Vec3,
    /// What it looks at.
    pub target: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    #[serde(default = "default_fov")]
    pub fov_y: f64,
}

fn default_fov() -> f64 {
    45.0
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: Vec3(0.0, 2.0, 10.0),
            target: Vec3(0.0, 1.0, 0.0),
            fov_y: default_fov(),
        }
    }
}
