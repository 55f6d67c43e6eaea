//! The effect file format, v1: serde types that mirror the RON document one to one.
//!
//! Field and variant names are a contract with users' files and other tools: extend, never rename.
//! Unknown fields and variants are rejected. Semantic checks live in [`crate::stages::validate`];
//! force schemas live with the rest of each force in [`crate::features::forces`].

use serde::Deserialize;

use crate::base::values::default_colors;
pub(crate) use crate::base::values::{ColorStop, SizeStop};
pub use crate::base::values::{Counts, Integrator, Range, Rgba, State, Vec3};
pub use crate::features::colliders::Collider;
pub use crate::features::emitter::{Emitter, Shape, Velocity};
pub use crate::features::events::Event;
use crate::features::forces::Force;
pub use crate::features::looks::glow::Glow;
pub(crate) use crate::features::looks::orient::Orient;
pub use crate::features::looks::rotation::Rotation;
pub use crate::features::looks::texture::Texture;
pub use crate::features::looks::trail::Trail;
pub use crate::features::looks::Blend;

/// A param's value as written: a number, or a vector of three.
enum ParamValue {
    Number(f64),
    Vector((f64, f64, f64)),
}

impl<'de> Deserialize<'de> for ParamValue {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = ParamValue;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, or a vector of three numbers `(x, y, z)`")
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<ParamValue, E> {
                Ok(ParamValue::Number(x))
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<ParamValue, E> {
                Ok(ParamValue::Number(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> Result<ParamValue, E> {
                Ok(ParamValue::Number(x as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<ParamValue, A::Error> {
                let mut next = |i| {
                    seq.next_element::<f64>()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))
                };
                let v = (next(0)?, next(1)?, next(2)?);
                if seq.next_element::<f64>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(ParamValue::Vector(v))
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// Reads `params`, each vector as its three components `NAME.x`, `NAME.y` and `NAME.z`.
fn deserialize_params<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<std::collections::BTreeMap<String, f64>, D::Error> {
    let written = std::collections::BTreeMap::<String, ParamValue>::deserialize(d)?;
    let mut params = std::collections::BTreeMap::new();
    for (name, value) in written {
        match value {
            ParamValue::Number(x) => {
                params.insert(name, x);
            }
            ParamValue::Vector((x, y, z)) => {
                for (c, v) in ["x", "y", "z"].into_iter().zip([x, y, z]) {
                    params.insert(format!("{name}.{c}"), v);
                }
            }
        }
    }
    Ok(params)
}

pub(crate) fn default_dt() -> f64 {
    1.0 / 60.0
}

pub(crate) fn default_substeps() -> u32 {
    1
}

/// A whole effect file as parsed (`Effect(...)` in RON), before it is checked and lowered:
/// what the file says, not a running effect (the runtime's `Effect`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Effect")]
pub struct EffectSpec {
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
    /// Numbers and vectors each particle carries, by name (see
    /// [`crate::features::attributes`]).
    #[serde(default)]
    pub attributes: crate::features::attributes::Declared,
    /// Named expressions that every expression of the effect may read by name:
    /// `define: {"r": "length(x)"}` (see [`crate::expr::define`]).
    #[serde(default)]
    pub define: std::collections::BTreeMap<String, String>,
    /// Named constants that custom expressions may use: `params: {"k": 0.4}`. A vector,
    /// `"wind": (1.0, 0.0, 0.0)`, is held as its three components `wind.x`, `wind.y` and
    /// `wind.z` (each a param a host may set), which expressions read together as `wind`.
    #[serde(default, deserialize_with = "deserialize_params")]
    pub params: std::collections::BTreeMap<String, f64>,
    /// Speed limit applied after every velocity update.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// How positions and velocities advance.
    #[serde(default)]
    pub integrator: Integrator,
    /// The error the author accepts (see [`crate::features::accuracy`]): with it,
    /// `integrator: Auto` becomes the integrator and substeps that meet it most cheaply.
    #[serde(
        default,
        deserialize_with = "crate::features::accuracy::deserialize_budget"
    )]
    pub accuracy: Option<crate::features::accuracy::Accuracy>,
    /// Surfaces particles bounce off.
    #[serde(default)]
    pub collide: Vec<Collider>,
    /// Volumes that kill particles at the end of a step.
    #[serde(default)]
    pub(crate) kill: Vec<KillVolume>,
    /// Meshes drawn around the effect and not simulated: what a `SceneDepth` collider meets
    /// in `plume render` and `plume preview` (see `features::scene`).
    #[serde(default)]
    pub(crate) scene: Vec<crate::features::scene::SceneMesh>,
    /// What lights the sprites of a lit look (`render.lit`): directional, point and ambient
    /// lights (see [`crate::features::lights`]); a white sun and some ambient light when none
    /// is named.
    #[serde(default)]
    pub lights: Vec<crate::features::lights::Light>,
    /// Draw back to front as seen from `camera`.
    #[serde(default)]
    pub sort: bool,
    /// Evaluate position-dependent forces per particle (default) or bake them into a grid.
    #[serde(default)]
    pub field: crate::features::field::Field,
    /// Keep per-particle state, or compute each particle from its id and age (see [`State`]).
    #[serde(default)]
    pub state: State,
    /// The viewpoint for sorting and rendering.
    #[serde(default)]
    pub camera: Camera,
    /// How particles look when rendered (an extension of v1; defaults when absent).
    #[serde(default)]
    pub render: Render,
    /// A box, in the effect's own space, that the author says holds every live particle: a
    /// host culls the effect when the box is out of view (the Bevy plugin gives the entity
    /// this `Aabb`). Plume's own simulation and outputs do not read it.
    #[serde(default)]
    pub bounds: Option<Bounds>,
    /// Events this (top-level) group's particles fire into other groups.
    #[serde(default)]
    pub events: Vec<crate::features::events::Event>,
    /// More particle groups, each with its own capacity, emitters, forces and look; the
    /// top-level fields are the first group, named `name` (see [`crate::graph`]).
    #[serde(default)]
    pub groups: Vec<Group>,
    /// The directory files the effect names (`render.texture.file`) are resolved against: the
    /// effect file's directory, set by whoever read the file; the current directory when None.
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
    /// Where those files are read from: a host's source, or the disk when None; set by
    /// `CompileOptions::files`, never by the file.
    #[serde(skip)]
    pub files: Option<crate::base::files::Files>,
    /// Lit looks read a shadow map given at run time: set by
    /// `CompileOptions::receive_shadows`, never by the file.
    #[serde(skip)]
    pub receive_shadows: bool,
    /// Placed in a host's world by a transform set at run time (world space; see
    /// `features::placement`): set by `CompileOptions::placed`, never by the file.
    #[serde(skip)]
    pub placed: bool,
    /// Takes bursts fired from code at run time (see `features::bursts`): set by
    /// `CompileOptions::bursts`, never by the file.
    #[serde(skip)]
    pub bursts: bool,
    /// Reads `params` at run time, so a host can change them without recompiling: set by
    /// `CompileOptions::live_params`, never by the file.
    #[serde(skip)]
    pub live_params: bool,
    /// Compiled to be stepped, not drawn: set by `CompileOptions::step_only`, never by the
    /// file.
    #[serde(skip)]
    pub step_only: bool,
    /// The sample that an accuracy budget of a group fed by events alone is calibrated and
    /// measured on (`features::accuracy`): one burst of its event's spawn rule where and as
    /// fast as the parent first fires, found by an f64 run of the graph. Set by the graph's
    /// compiler and by `plume accuracy`, never by the file.
    #[serde(skip)]
    pub sample_burst: Option<crate::features::bursts::Burst>,
    /// The camera a pixel budget is measured through instead of `camera`: set by
    /// `CompileOptions::accuracy_camera` (a host's), never by the file.
    #[serde(skip)]
    pub accuracy_camera: Option<Camera>,
}

/// An axis-aligned box: `bounds: Some(Bounds(min: (-5.0, 0.0, -5.0), max: (5.0, 12.0, 5.0)))`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// The lower corner.
    pub min: Vec3,
    /// The upper corner (>= min on every axis).
    pub max: Vec3,
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
    pub(crate) color: Vec<ColorStop>,
    /// Sprite diameter (m) over the life fraction.
    #[serde(default = "default_sizes")]
    pub(crate) size: Vec<SizeStop>,
    /// The sprite's height (its y axis) over the life fraction, when it differs from its
    /// width: then `size` is the width. For `Velocity` sprites, the length before stretching.
    #[serde(default)]
    pub(crate) size_y: Option<Vec<SizeStop>>,
    /// Opacity over the life fraction with stops of its own, `(t, alpha)`: replaces the colour
    /// stops' alpha.
    #[serde(default)]
    pub(crate) alpha: Option<Vec<SizeStop>>,
    /// Alpha or Additive.
    #[serde(default)]
    pub blend: Blend,
    /// Background colour `(r, g, b)`.
    #[serde(default = "default_background")]
    pub background: Vec3,
    /// Which way each sprite faces: the camera, stretched along the velocity, or a fixed plane.
    #[serde(default)]
    pub(crate) orient: Orient,
    /// What the size stops measure: metres (`World`) or fractions of the image's height
    /// (`Screen`; see `features::looks::screen_size`).
    #[serde(default)]
    pub size_in: crate::features::looks::screen_size::SizeIn,
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
    /// An expression (vec3) of the particle that its colour's RGB is multiplied by
    /// (`features/looks/by.rs`).
    #[serde(default)]
    pub color_by: Option<String>,
    /// An expression (f32) of the particle that its alpha is multiplied by.
    #[serde(default)]
    pub alpha_by: Option<String>,
    /// An expression (f32) of the particle that its size is multiplied by.
    #[serde(default)]
    pub size_by: Option<String>,
    /// An expression (f32) of the particle: the t at which its colour (and opacity) stops are
    /// read instead of its life fraction (colour from speed, from heat), kept within [0, 1].
    #[serde(default)]
    pub color_t: Option<String>,
    /// An expression (f32) of the particle: the flipbook frame it shows (its whole part,
    /// wrapped around the frames), instead of the texture's `play`.
    #[serde(default)]
    pub frame_by: Option<String>,
    /// Sprites shaded by the effect's lights, with a normal at every pixel (see
    /// `features::looks::lit`).
    #[serde(default)]
    pub lit: Option<crate::features::looks::lit::Lit>,
    /// The brightest particles give off light (`features::looks::particle_light`).
    #[serde(default)]
    pub light: Option<crate::features::looks::particle_light::ParticleLight>,
    /// The particles drawn as ribbons joining each to the one spawned before it
    /// (`features::looks::ribbon`), instead of sprites.
    #[serde(default)]
    pub ribbon: Option<crate::features::looks::ribbon::Ribbon>,
    /// The particles drawn as a triangle mesh from an OBJ file
    /// (`features::looks::particle_mesh`), instead of sprites.
    #[serde(default)]
    pub mesh: Option<crate::features::looks::particle_mesh::ParticleMesh>,
}

impl Render {
    /// The strings of `color_by`, `alpha_by`, `size_by` and `color_t`.
    pub(crate) fn written_by(&self) -> crate::features::looks::by_expression::Written<'_> {
        [
            self.color_by.as_deref(),
            self.alpha_by.as_deref(),
            self.size_by.as_deref(),
            self.color_t.as_deref(),
            self.frame_by.as_deref(),
        ]
    }
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
            size_in: Default::default(),
            texture: None,
            rotation: None,
            soft: None,
            glow: None,
            trail: None,
            palette: None,
            color_by: None,
            alpha_by: None,
            size_by: None,
            color_t: None,
            frame_by: None,
            lit: None,
            light: None,
            ribbon: None,
            mesh: None,
        }
    }
}

/// Volumes that kill particles at the end of a step.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) enum KillVolume {
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

/// A particle group beside the top-level one: the fields of an effect that belong to one
/// particle system.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Group {
    /// The name events target it by (unique in the file).
    pub name: String,
    /// Most live particles of this group at once.
    pub capacity: u32,
    /// Its own emitters (a group fed by events has none).
    #[serde(default)]
    pub emitters: Vec<Emitter>,
    /// Accelerations, summed.
    #[serde(default)]
    pub forces: Vec<Force>,
    /// Numbers and vectors each of its particles carries, by name.
    #[serde(default)]
    pub attributes: crate::features::attributes::Declared,
    /// Speed limit applied after every velocity update.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// How positions and velocities advance.
    #[serde(default)]
    pub integrator: Integrator,
    /// Integration substeps per step.
    #[serde(default = "default_substeps")]
    pub substeps: u32,
    /// Surfaces its particles bounce off.
    #[serde(default)]
    pub collide: Vec<Collider>,
    /// Volumes that kill its particles at the end of a step.
    #[serde(default)]
    pub(crate) kill: Vec<KillVolume>,
    /// Draw back to front.
    #[serde(default)]
    pub sort: bool,
    /// Evaluate position-dependent forces per particle or bake them into a grid.
    #[serde(default)]
    pub field: crate::features::field::Field,
    /// Keep per-particle state or not.
    #[serde(default)]
    pub state: State,
    /// How its particles look.
    #[serde(default)]
    pub render: Render,
    /// Events its particles fire.
    #[serde(default)]
    pub events: Vec<Event>,
}
