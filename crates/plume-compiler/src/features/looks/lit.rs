//! Lit sprites (`render.lit`): each sprite is shaded by the effect's lights
//! ([`crate::features::lights`]) as a surface with a normal at every pixel: the quad's own
//! facing (`Flat`), or a half sphere bent over the quad (`Sphere`, for soft volumes: lit on
//! the side the light comes from, dark on the other). The normal is built from the quad's half
//! axes, in the sprite's own frame as it turns, and faces the viewer. A part of the colour can
//! stay unlit (`emissive`), and `wrap` lets light reach round the terminator of thin volumes.
//!
//! Both renderers shade each pixel the same way ([`emit_lit_color`]: the fragment shader,
//! and the compute splat's composite from the quad's half axes and centre it keeps); the
//! reference drawing shades in world space, and [`Lit::shade`] is the f64 twin the tests
//! check single pixels against.

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};

/// The normal a lit sprite has at each pixel.
#[derive(Clone, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Normals {
    /// The quad's own facing, the same at every pixel (a card, a leaf).
    Flat,
    /// A half sphere bent over the quad: the normal leans toward the rim as the corner
    /// coordinates do (smoke, clouds, dust).
    #[default]
    Sphere,
    /// A normal map: a PNG laid out as the sprite's texture (`render.texture`: the same size
    /// and frames), each texel a normal in the sprite's own frame, (r, g, b) = (n + 1) / 2
    /// with x right, y up and z toward the viewer (OpenGL's convention).
    Map {
        /// The PNG file, relative to the effect file's directory.
        file: String,
    },
}

/// Binding of a normal map (`Normals::Map`) in the draw module; it shares the texture's
/// sampler.
pub const NORMAL_MAP_BINDING: u32 = 37;

/// `render.lit`: the sprites are shaded by the lights.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lit {
    /// The normal at each pixel.
    #[serde(default)]
    pub normals: Normals,
    /// How far light reaches round the terminator, in [0, 1]: 0 is Lambert's law, 1 lights
    /// the side facing away at half the strength of the side edge-on.
    #[serde(default)]
    pub wrap: f64,
    /// The part of the colour that glows by itself and is not lit, in [0, 1].
    #[serde(default)]
    pub emissive: f64,
}

impl Lit {
    /// Checks `wrap` and `emissive` (each in [0, 1]), and that a normal map names a file and
    /// has a texture to follow (`textured`).
    pub fn check(&self, path: &ValuePath, textured: bool, c: &mut Checker) {
        c.within(&path.field("wrap"), self.wrap, 0.0, 1.0);
        c.within(&path.field("emissive"), self.emissive, 0.0, 1.0);
        if let Normals::Map { file } = &self.normals {
            let at = path.field("normals").variant("Map").field("file");
            if file.trim().is_empty() {
                c.error(
                    &at,
                    "names no file; give a PNG's path relative to the effect file",
                );
            } else if !textured {
                c.error(&at, "a normal map is laid out as the sprite's texture, its frames played with it: give render.texture too");
            }
        }
    }

    /// The normal map's file, when the normals come from one.
    pub fn normal_map(&self) -> Option<&str> {
        match &self.normals {
            Normals::Map { file } => Some(file),
            _ => None,
        }
    }

    /// The unit normal at corner coordinates `uv` of a quad with half axes `half_x`, `half_y`
    /// (at right angles), facing the side `toward_eye` (from its centre) points to; for a
    /// normal map, `tangent` is the map's normal there in the quad's frame ((r, g, b) · 2 − 1).
    /// The f64 twin of the WGSL `sprite_basis` and `surface_normal`.
    pub fn normal(
        &self,
        uv: (f64, f64),
        (half_x, half_y): (DVec3, DVec3),
        toward_eye: DVec3,
        tangent: DVec3,
    ) -> DVec3 {
        let (ux, uy) = (half_x.normalize_or_zero(), half_y.normalize_or_zero());
        let mut facing = ux.cross(uy);
        if facing.dot(toward_eye) < 0.0 {
            facing = -facing;
        }
        match self.normals {
            Normals::Flat => facing,
            Normals::Sphere => {
                let bulge = (1.0 - uv.0 * uv.0 - uv.1 * uv.1).max(0.0).sqrt();
                let n = uv.0 * ux + uv.1 * uy + bulge * facing;
                // Unit inside the disc; past its rim (a texture's corners) normalised.
                n / n.length_squared().max(1.0).sqrt()
            }
            Normals::Map { .. } => {
                let n = tangent.x * ux + tangent.y * uy + tangent.z * facing;
                n / n.length_squared().max(1e-12).sqrt()
            }
        }
    }

    /// Emits, for a normal map, `normal_texel` (the map's texel, as `frame_texel` samples the
    /// texture) and the tangent-space normal at a pixel: `tangent_normal(in)` for the fragment
    /// shader (its derivatives taken before any discard) and, for the compute splat,
    /// `splat_tangent(uv, du, dv, frame)`; nothing for other normals.
    pub fn emit_tangent_fns(&self, w: &mut Writer, splat: bool) {
        if self.normal_map().is_none() {
            return;
        }
        use crate::features::looks::texture::TextureIr;
        TextureIr::emit_texel_fn_of(w, "normal_texel", "normal_texture");
        w.blank();
        w.comment("The normal map's normal at this fragment, in the sprite's frame (texels hold (n + 1) / 2).");
        w.block("fn tangent_normal(in: Sprite) -> vec3<f32>", |w| {
            TextureIr::emit_fragment_coordinates(w);
            w.line("return normal_texel(cell, quad, gx, gy).xyz * 2.0 - 1.0;");
        });
        if splat {
            w.blank();
            w.comment("The normal map's normal at corner coordinates uv (their derivatives du, dv), for the compute splat.");
            w.block(
                "fn splat_tangent(uv: vec2<f32>, du: vec2<f32>, dv: vec2<f32>, frame: u32) -> vec3<f32>",
                |w| {
                    TextureIr::emit_splat_coordinates(w);
                    w.line("return normal_texel(cell, quad, gx, gy).xyz * 2.0 - 1.0;");
                },
            );
        }
    }

    /// The WGSL of the tangent-space normal at a fragment (`in`): `tangent_normal(in)` for a
    /// normal map, else a zero vector that `surface_normal` does not read.
    pub fn tangent_wgsl(&self) -> &'static str {
        match self.normal_map() {
            Some(_) => "tangent_normal(in)",
            None => "vec3<f32>(0.0)",
        }
    }

    /// The shaded colour of `rgb` under `light` (what [`crate::features::lights::Lights::received`]
    /// gives): rgb · (emissive + (1 − emissive) · light).
    pub fn shade(&self, rgb: DVec3, light: DVec3) -> DVec3 {
        rgb * (DVec3::splat(self.emissive) + (1.0 - self.emissive) * light)
    }

    /// Emits the lights' declarations and `received_light`, then (for a `turned` quad)
    /// `sprite_basis(ax, ay, c)` (its unit axes and facing toward the viewer, as the columns of
    /// a matrix, from its half axes and centre in view space: made once a sprite),
    /// `surface_normal(uv, basis, tangent)` and `lit_color(c, n, p)`, the colour `c` shaded at
    /// view-space point `p` whose normal is `n`: the WGSL twins of [`Self::normal`] and
    /// [`Self::shade`]. A normal map's texture is declared here too.
    pub fn emit_lit_color(&self, w: &mut Writer, turned: bool) {
        crate::features::lights::emit_received_light(w, self.wrap);
        w.line(format!(
            "const LIT_EMISSIVE: f32 = {};",
            f32_lit(self.emissive)
        ));
        w.blank();
        if !turned {
            w.comment("The basis of an upright sprite facing the camera: the view's own.");
            w.line("const VIEW_BASIS: mat3x3<f32> = mat3x3<f32>(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);");
            w.blank();
        }
        if turned {
            w.comment("A quad's basis in view space: its unit axes (at right angles) and its facing toward the viewer (the eye at the view's origin, or along +z for an orthographic projection), from its half axes and centre.");
            w.block(
                "fn sprite_basis(ax: vec3<f32>, ay: vec3<f32>, c: vec3<f32>) -> mat3x3<f32>",
                |w| {
                    w.line("let ux = ax * inverseSqrt(max(dot(ax, ax), 1e-30));");
                    w.line("let uy = ay * inverseSqrt(max(dot(ay, ay), 1e-30));");
                    w.line("var facing = cross(ux, uy);");
                    w.line(
                        "let eye = select(-c, vec3<f32>(0.0, 0.0, 1.0), draw.proj[3][3] == 1.0);",
                    );
                    w.block("if (dot(facing, eye) < 0.0)", |w| {
                        w.line("facing = -facing;")
                    });
                    w.line("return mat3x3<f32>(ux, uy, facing);");
                },
            );
            w.blank();
        }
        if self.normal_map().is_some() {
            w.comment("The normal map, laid out as the sprite texture (its sampler shared).");
            w.line(format!(
                "@group(0) @binding({NORMAL_MAP_BINDING}) var normal_texture: texture_2d<f32>;"
            ));
            w.blank();
        }
        w.comment("The unit normal at corner coordinates uv of a sprite of that basis (tangent: a normal map's normal there, in the sprite's frame).");
        w.block(
            "fn surface_normal(uv: vec2<f32>, basis: mat3x3<f32>, tangent: vec3<f32>) -> vec3<f32>",
            |w| match self.normals {
                Normals::Flat => w.line("return basis[2];"),
                Normals::Sphere => {
                    w.comment("A half sphere over the quad: unit inside the disc, normalised past its rim.");
                    w.line("let m = uv.x * basis[0] + uv.y * basis[1] + sqrt(max(1.0 - dot(uv, uv), 0.0)) * basis[2];");
                    w.line("return m * inverseSqrt(max(dot(m, m), 1.0));");
                }
                Normals::Map { .. } => {
                    w.line("let m = basis * tangent;");
                    w.line("return m * inverseSqrt(max(dot(m, m), 1e-12));");
                }
            },
        );
        w.blank();
        w.comment("Colour c at view-space point p of a lit sprite whose normal there is n: its unlit (emissive) part plus the rest times the light received.");
        w.block(
            "fn lit_color(c: vec4<f32>, n: vec3<f32>, p: vec3<f32>) -> vec4<f32>",
            |w| {
                w.line("let light = received_light(n, p);");
                w.line(
                    "return vec4<f32>(c.rgb * (LIT_EMISSIVE + (1.0 - LIT_EMISSIVE) * light), c.a);",
                );
            },
        );
    }
}
