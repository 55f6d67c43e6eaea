//! Lights (`lights: [...]` in the file, or a host's): what lights the sprites of an effect whose
//! look is lit (`render.lit`, [`crate::features::looks::lit`]). Directional lights (the sun),
//! point lights (a lamp, a fire) and ambient light, each a colour times an intensity. This
//! module owns their schema, their checks, the uniform the draw reads them from, and the f64
//! light a surface receives ([`Lights::received`]), the twin of the WGSL `received_light`.
//!
//! A point light's intensity is the light it gives a surface facing it 1 m away; it falls off
//! as 1 / d² (no nearer than 10 cm: closer surfaces get what one 10 cm away gets, so a sprite
//! through the light never turns infinite) and smoothly to zero at its `range`.

use glam::{DMat4, DVec3};
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, Writer};
use crate::features::shadow::{
    shadow_declarations_wgsl, Shadow, ShadowAt, SHADOW_BYTES, SHADOW_FIELDS_WGSL, SHADOW_WGSL,
};

/// Most light sources (directional and point) one draw reads.
pub const LIGHTS_MOST: usize = 8;

/// Bytes of the lights uniform: the ambient light and the source count (32),
/// [`LIGHTS_MOST`] sources of two vec4s each, then the shadow (`SHADOW_BYTES`).
pub const LIGHTS_BYTES: u64 = 32 + 32 * LIGHTS_MOST as u64 + SHADOW_BYTES;

/// Binding of the lights uniform in a lit effect's draw module.
pub const LIGHTS_BINDING: u32 = 36;

/// The nearest a point light counts a surface (m): nearer, the light is what it is here.
pub(crate) const POINT_NEAREST: f64 = 0.1;

/// A light as written in an effect file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Light {
    /// Parallel light from far away (the sun).
    Directional {
        /// The way the light travels: `(0.0, -1.0, 0.0)` shines straight down.
        direction: Vec3,
        /// Its colour, each channel >= 0.
        #[serde(default = "white")]
        color: Vec3,
        /// Its strength: a surface facing it receives colour · intensity.
        #[serde(default = "one")]
        intensity: f64,
        /// Whether the scene's meshes cast its shadow (at most one light of a file).
        #[serde(default)]
        shadow: bool,
    },
    /// Light from a point, falling off with distance.
    Point {
        /// Where the light is (m).
        position: Vec3,
        /// Its colour, each channel >= 0.
        #[serde(default = "white")]
        color: Vec3,
        /// The light a surface facing it receives 1 m away.
        #[serde(default = "one")]
        intensity: f64,
        /// The distance (m) at which its light has faded to nothing.
        #[serde(default = "default_range")]
        range: f64,
    },
    /// Light from every side, on every surface alike.
    Ambient {
        /// Its colour, each channel >= 0.
        #[serde(default = "white")]
        color: Vec3,
        /// Its strength.
        #[serde(default = "one")]
        intensity: f64,
    },
}

fn white() -> Vec3 {
    Vec3(1.0, 1.0, 1.0)
}

fn one() -> f64 {
    1.0
}

fn default_range() -> f64 {
    20.0
}

/// A light source that comes from somewhere (ambient light is [`Lights::ambient`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// Parallel light travelling along `direction` (a unit vector).
    Directional {
        /// The way the light travels (unit length).
        direction: DVec3,
        /// Colour times intensity.
        color: DVec3,
    },
    /// Light from `position`, falling off as 1 / d² and to zero at `range`.
    Point {
        /// Where the light is (m).
        position: DVec3,
        /// Colour times intensity: the light 1 m away.
        color: DVec3,
        /// Where its light has faded to nothing (m, > 0).
        range: f64,
    },
}

/// The lights a lit effect is drawn with, in world space: an effect file's `lights`, or a
/// host's (`EffectRenderer::set_lights` in the runtime; the Bevy plugin passes Bevy's).
#[derive(Clone, Debug, PartialEq)]
pub struct Lights {
    /// Ambient light: colour times intensity, summed over the ambient entries.
    pub ambient: DVec3,
    /// Directional and point lights, at most [`LIGHTS_MOST`] (the draw reads the first that
    /// many).
    pub sources: Vec<LightSource>,
    /// The shadow map that blocks one directional light, if any.
    pub shadow: Option<Shadow>,
}

impl Default for Lights {
    /// What a lit effect that names no lights is drawn with: a white sun from above, a little
    /// in front and to the left, and a fifth of it as ambient light.
    fn default() -> Self {
        Self {
            ambient: DVec3::splat(0.2),
            sources: vec![LightSource::Directional {
                direction: DVec3::new(0.4, -1.0, -0.3).normalize(),
                color: DVec3::ONE,
            }],
            shadow: None,
        }
    }
}

impl Lights {
    /// The lights an effect file names (the default ones when it names none).
    pub fn lower(written: &[Light]) -> Self {
        if written.is_empty() {
            return Self::default();
        }
        let mut lights = Self {
            ambient: DVec3::ZERO,
            sources: Vec::new(),
            shadow: None,
        };
        for light in written {
            match *light {
                Light::Directional {
                    direction,
                    color,
                    intensity,
                    shadow,
                } => {
                    if shadow && lights.shadow.is_none() {
                        lights.shadow = Some(Shadow::of_source(lights.sources.len()));
                    }
                    lights.sources.push(LightSource::Directional {
                        direction: direction.d().normalize_or_zero(),
                        color: color.d() * intensity,
                    })
                }
                Light::Point {
                    position,
                    color,
                    intensity,
                    range,
                } => lights.sources.push(LightSource::Point {
                    position: position.d(),
                    color: color.d() * intensity,
                    range,
                }),
                Light::Ambient { color, intensity } => lights.ambient += color.d() * intensity,
            }
        }
        lights
    }

    /// Whether one of the lights a file names casts a shadow (`shadow: true`).
    pub(crate) fn casts_shadow(written: &[Light]) -> bool {
        written
            .iter()
            .any(|l| matches!(l, Light::Directional { shadow: true, .. }))
    }

    /// The lights as every pixel of a particle centred at `centre` receives them where its
    /// look says `shadow_at: Particle`: the shadowed source dimmed by the map's verdict at the
    /// centre ([`Shadow::visibility`]), and no map left to look up. The f64 twin of
    /// `particle_shadow`.
    pub fn seen_from_particle(&self, centre: DVec3) -> Lights {
        let mut lights = self.clone();
        if let Some(shadow) = lights.shadow.take() {
            let seen = shadow.visibility(centre);
            if let Some(LightSource::Directional { color, .. }) =
                lights.sources.get_mut(shadow.source)
            {
                *color *= seen;
            }
        }
        lights
    }

    /// The light (per channel) that a surface at `p` with unit normal `n` receives, both in
    /// world space: the ambient light plus, for each source, its light times
    /// max((n · l + wrap) / (1 + wrap), 0), with l the unit vector toward the source. `wrap`
    /// in [0, 1] lets light reach round the terminator of thin volumes (0: Lambert's law).
    pub fn received(&self, n: DVec3, p: DVec3, wrap: f64) -> DVec3 {
        let mut light = self.ambient;
        for (toward, color) in self.incoming(p) {
            let facing = ((n.dot(toward) + wrap) / (1.0 + wrap)).max(0.0);
            light += color * facing;
        }
        light
    }

    /// Each source's light arriving at `p`: (the unit vector toward the source, its colour
    /// there: a point light's fallen off with distance and range, the shadowed one's times
    /// [`Shadow::visibility`]). The first [`LIGHTS_MOST`], as the draw reads them; the twin
    /// of [`emit_incoming`]'s WGSL.
    pub(crate) fn incoming(&self, p: DVec3) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
        let shadowed = self.shadow.as_ref().map(|s| (s.source, s.visibility(p)));
        self.sources
            .iter()
            .take(LIGHTS_MOST)
            .enumerate()
            .map(move |(i, source)| match *source {
                LightSource::Directional { direction, color } => {
                    let seen = match shadowed {
                        Some((source, seen)) if source == i => seen,
                        _ => 1.0,
                    };
                    (-direction.normalize_or_zero(), color * seen)
                }
                LightSource::Point {
                    position,
                    color,
                    range,
                } => {
                    let d = position - p;
                    let d2 = d.length_squared().max(POINT_NEAREST * POINT_NEAREST);
                    (d / d2.sqrt(), color * range_window(d2, range) / d2)
                }
            })
    }

    /// The lights uniform's bytes ([`LIGHTS_BYTES`]): the ambient light (w unused), the
    /// source count, then each source as (unit direction the light travels or position, 0
    /// for directional or 1 for point) and (colour times intensity, range), in whatever space
    /// they are (a draw's uniform holds them in its view).
    pub fn uniform_bytes(&self) -> Vec<u8> {
        let mut words: Vec<f32> = Vec::with_capacity(LIGHTS_BYTES as usize / 4);
        let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        words.extend(f(self.ambient));
        words.push(0.0);
        let count = self.sources.len().min(LIGHTS_MOST) as u32;
        words.extend([f32::from_bits(count), 0.0, 0.0, 0.0]);
        for source in self.sources.iter().take(LIGHTS_MOST) {
            match *source {
                LightSource::Directional { direction, color } => {
                    words.extend(f(direction.normalize_or_zero()));
                    words.extend([0.0]);
                    words.extend(f(color));
                    words.extend([0.0]);
                }
                LightSource::Point {
                    position,
                    color,
                    range,
                } => {
                    words.extend(f(position));
                    words.extend([1.0]);
                    words.extend(f(color));
                    words.extend([range as f32]);
                }
            }
        }
        words.resize((LIGHTS_BYTES - SHADOW_BYTES) as usize / 4, 0.0);
        words.extend(Shadow::uniform_words(self.shadow.as_ref()));
        words.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    /// These lights and `more` sources after them, as many as a draw reads ([`LIGHTS_MOST`]).
    pub fn with_sources(&self, more: Vec<LightSource>) -> Self {
        let mut sources = self.sources.clone();
        sources.extend(more);
        sources.truncate(LIGHTS_MOST);
        Self {
            ambient: self.ambient,
            sources,
            shadow: self.shadow.clone(),
        }
    }

    /// The same lights moved by `m` (world to an effect's own space, or to a view): directions
    /// turned, positions moved, the shadow map's projections made to start from the new
    /// space; colours and ranges kept.
    pub fn transformed(&self, m: DMat4) -> Self {
        Self {
            ambient: self.ambient,
            shadow: self.shadow.as_ref().map(|s| s.transformed(m)),
            sources: self
                .sources
                .iter()
                .map(|s| match *s {
                    LightSource::Directional { direction, color } => LightSource::Directional {
                        direction: m.transform_vector3(direction).normalize_or_zero(),
                        color,
                    },
                    LightSource::Point {
                        position,
                        color,
                        range,
                    } => LightSource::Point {
                        position: m.transform_point3(position),
                        color,
                        range,
                    },
                })
                .collect(),
        }
    }
}

impl std::fmt::Display for Lights {
    /// One line: the ambient light, then each source, to four decimals.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = |v: DVec3| {
            let c = |x: f64| format!("{}", (x * 1e4).round() / 1e4);
            format!("({}, {}, {})", c(v.x), c(v.y), c(v.z))
        };
        write!(f, "lights: ambient {}", v(self.ambient))?;
        for source in &self.sources {
            match *source {
                LightSource::Directional { direction, color } => write!(
                    f,
                    ", directional along {} colour {}",
                    v(direction),
                    v(color)
                )?,
                LightSource::Point {
                    position,
                    color,
                    range,
                } => write!(
                    f,
                    ", point at {} colour {} range {range} m",
                    v(position),
                    v(color)
                )?,
            }
        }
        if let Some(shadow) = &self.shadow {
            write!(f, ", source {} casts a shadow", shadow.source)?;
        }
        Ok(())
    }
}

/// A point light's fade to its range: (1 − (d / range)⁴)², clamped to [0, 1]; 1 near the
/// light, 0 from `range` on, with no step at the range.
pub(crate) fn range_window(d2: f64, range: f64) -> f64 {
    let q = d2 / (range * range);
    (1.0 - q * q).clamp(0.0, 1.0).powi(2)
}

/// Checks the file's lights: colours and intensities >= 0, directions that are not zero,
/// ranges > 0, at most [`LIGHTS_MOST`] sources.
pub(crate) fn check(lights: &[Light], c: &mut Checker) {
    let root = ValuePath::root().field("lights");
    let mut sources = 0;
    let mut shadows = 0;
    for (i, light) in lights.iter().enumerate() {
        let at = root.index(i);
        let (name, color, intensity) = match *light {
            Light::Directional {
                direction,
                color,
                intensity,
                shadow,
            } => {
                c.direction(&at.variant("Directional").field("direction"), direction);
                shadows += usize::from(shadow);
                if shadow && shadows == 2 {
                    c.error(
                        &at.variant("Directional").field("shadow"),
                        "only one light casts a shadow; set `shadow: true` on one directional light",
                    );
                }
                ("Directional", color, intensity)
            }
            Light::Point {
                position,
                color,
                intensity,
                range,
            } => {
                let p = at.variant("Point");
                c.vec3(&p.field("position"), position);
                c.positive(&p.field("range"), range);
                ("Point", color, intensity)
            }
            Light::Ambient { color, intensity } => ("Ambient", color, intensity),
        };
        let p = at.variant(name);
        c.non_negative(&p.field("intensity"), intensity);
        for (j, (channel, x)) in [("r", color.0), ("g", color.1), ("b", color.2)]
            .into_iter()
            .enumerate()
        {
            c.non_negative(&p.field("color").component(j, channel), x);
        }
        if name != "Ambient" {
            sources += 1;
            if sources == LIGHTS_MOST + 1 {
                c.error(
                    &at,
                    format!("a draw reads at most {LIGHTS_MOST} directional and point lights; merge or drop some"),
                );
            }
        }
    }
}

/// Emits the lights uniform's declarations (binding [`LIGHTS_BINDING`]) and
/// `received_light(n, p)`: the light a surface at view-space point `p` with unit normal `n`
/// receives, the WGSL twin of [`Lights::received`]. The runtime writes the uniform in the
/// view each frame ([`Lights::transformed`] by the camera's view), so no pixel moves a light;
/// `wrap` is a constant of the look.
pub(crate) fn emit_received_light(w: &mut Writer, wrap: f64, shadows: Option<ShadowAt>) {
    w.comment("A light source: (direction the light travels, 0) or (position, 1); (colour · intensity, range).");
    w.block("struct LightSource", |w| {
        w.line("place: vec4<f32>,");
        w.line("color: vec4<f32>,");
    });
    w.block("struct Lights", |w| {
        w.line("ambient: vec4<f32>,");
        w.line("count: vec4<u32>,");
        w.line(format!("sources: array<LightSource, {LIGHTS_MOST}>,"));
        for field in SHADOW_FIELDS_WGSL.lines() {
            w.line(field.trim());
        }
    });
    w.line(format!(
        "@group(0) @binding({LIGHTS_BINDING}) var<uniform> lights: Lights;"
    ));
    if let Some(at) = shadows {
        for line in shadow_declarations_wgsl().lines() {
            w.line(line);
        }
        w.blank();
        for line in SHADOW_WGSL.lines() {
            w.line(line);
        }
        if at == ShadowAt::Particle {
            w.comment("The shadowed source's light at the particle being lit (render.lit.shadow_at: Particle): set from shadow_visibility at its centre before its pixels are lit.");
            w.line("var<private> particle_shadow: f32 = 1.0;");
        }
    }
    w.line(format!("const LIGHT_WRAP: f32 = {};", f32_lit(wrap)));
    w.line(format!(
        "const POINT_NEAREST2: f32 = {};",
        f32_lit(POINT_NEAREST * POINT_NEAREST)
    ));
    w.blank();
    w.comment("The light a surface at view-space p with unit normal n receives (the lights are in the view).");
    w.block("fn received_light(n: vec3<f32>, p: vec3<f32>) -> vec3<f32>", |w| {
        w.line("var light = lights.ambient.rgb;");
        w.block(
            format!("for (var i = 0u; i < min(lights.count.x, {LIGHTS_MOST}u); i++)"),
            |w| {
                emit_incoming(w, shadows);
                w.line("light += color * max((dot(n, toward) + LIGHT_WRAP) / (1.0 + LIGHT_WRAP), 0.0);");
            },
        );
        w.line("return light;");
    });
}

/// Emits, inside a loop over the sources (`i`) at view-space point `p`, `toward` (the unit
/// vector toward source i) and `color` (its light there, the shadowed source's through its
/// map when the draw reads `shadows`, looked up where it says): the twin of
/// [`Lights::incoming`].
pub(crate) fn emit_incoming(w: &mut Writer, shadows: Option<ShadowAt>) {
    w.line("let source = lights.sources[i];");
    w.comment("A unit direction (zero where a host gave none: no light).");
    w.line("var toward = -source.place.xyz;");
    w.line("var color = source.color.rgb;");
    if let Some(at) = shadows {
        w.block("if (i == lights.shadow.x)", |w| {
            w.line(format!("color = color * {};", at.visibility_wgsl()));
        });
    }
    w.block("if (source.place.w > 0.5)", |w| {
        w.line("let d = source.place.xyz - p;");
        w.line("let d2 = max(dot(d, d), POINT_NEAREST2);");
        w.line("toward = d * inverseSqrt(d2);");
        w.line("let q = d2 / (source.color.w * source.color.w);");
        w.line("let window = clamp(1.0 - q * q, 0.0, 1.0);");
        w.line("color = color * (window * window / d2);");
    });
}
