//! Lit sprites (`render.lit`): each sprite is shaded by the effect's lights
//! ([`crate::features::lights`]) as a surface with a normal at every pixel: the quad's own
//! facing (`Flat`), or a half sphere bent over the quad (`Sphere`, for soft volumes: lit on
//! the side the light comes from, dark on the other). The normal is built from the quad's half
//! axes, in the sprite's own frame as it turns, and faces the viewer. A part of the colour can
//! stay unlit (`emissive`), and `wrap` lets light reach round the terminator of thin volumes.
//!
//! Both renderers shade each pixel the same way (`emit_lit_color`: the fragment shader,
//! and the compute renderer's composite from the quad's half axes and centre it keeps); the
//! reference drawing shades in world space, and [`Lit::shade`] is the f64 twin the tests
//! check single pixels against.

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};
use crate::features::shadow::ShadowAt;

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
    /// Six-way lightmaps (Unity's smoke format): no normal, but how much of a light from each
    /// of six directions of the sprite's frame the pixel lets through, baked into two PNGs
    /// laid out as the sprite's texture: light from the right (+x), top (+y) and back (−z, from
    /// behind the sprite) in the first one's red, green and blue, from the left, bottom and
    /// front (+z, the viewer's side) in the second one's. A light arriving along unit t (in the
    /// sprite's frame) is weighted t² per axis (weights that sum to 1), each axis's map chosen
    /// by the sign; ambient light takes the six maps' mean.
    SixWay {
        /// Light from +x, +y and −z in red, green and blue.
        right_top_back: String,
        /// Light from −x, −y and +z in red, green and blue.
        left_bottom_front: String,
    },
}

/// Bindings of a lit look's maps in the draw module (a normal map; or the six-way lightmaps,
/// right-top-back then left-bottom-front): they share the texture's sampler.
pub const LIT_MAP_BINDINGS: [u32; 2] = [37, 38];

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
    /// Where a shadowed light's map is looked up: at each pixel (the default) or once a
    /// particle, at its centre.
    #[serde(default)]
    pub(crate) shadow_at: ShadowAt,
    /// Whether the draw reads a shadow map (`features::shadow`): set by the compiler where a
    /// light of the file casts a shadow or `CompileOptions::receive_shadows` asks for it, never
    /// by the file. Without it the draw module holds no lookup.
    #[serde(skip)]
    pub shadows: bool,
}

impl Lit {
    /// Checks `wrap` and `emissive` (each in [0, 1]), and that each map names a file and has a
    /// texture to follow (`textured`).
    pub(crate) fn check(&self, path: &ValuePath, textured: bool, c: &mut Checker) {
        c.within(&path.field("wrap"), self.wrap, 0.0, 1.0);
        c.within(&path.field("emissive"), self.emissive, 0.0, 1.0);
        for (field, file) in self.map_files() {
            let at = path
                .field("normals")
                .variant(self.normals_name())
                .field(field);
            if file.trim().is_empty() {
                c.error(
                    &at,
                    "names no file; give a PNG's path relative to the effect file",
                );
            } else if !textured {
                c.error(&at, "a lit look's map is laid out as the sprite's texture, its frames played with it: give render.texture too");
            }
        }
    }

    /// Where the draw looks a shadow up; `None` where it reads no shadow map.
    pub(crate) fn shadow_lookup(&self) -> Option<ShadowAt> {
        self.shadows.then_some(self.shadow_at)
    }

    /// Whether the draw looks its shadow up once a particle: its vertex shader (or the compute
    /// renderer's load of its record) sets `particle_shadow` from the particle's centre.
    pub(crate) fn shadow_per_particle(&self) -> bool {
        self.shadow_lookup() == Some(ShadowAt::Particle)
    }

    /// The variant of `normals`, as the file writes it.
    pub(crate) fn normals_name(&self) -> &'static str {
        match self.normals {
            Normals::Flat => "Flat",
            Normals::Sphere => "Sphere",
            Normals::Map { .. } => "Map",
            Normals::SixWay { .. } => "SixWay",
        }
    }

    /// The maps the look reads, in binding order ([`LIT_MAP_BINDINGS`]), each with the field
    /// that names it: a normal map, or the two six-way lightmaps; none for computed normals.
    pub(crate) fn map_files(&self) -> Vec<(&'static str, &str)> {
        match &self.normals {
            Normals::Map { file } => vec![("file", file)],
            Normals::SixWay {
                right_top_back,
                left_bottom_front,
            } => vec![
                ("right_top_back", right_top_back),
                ("left_bottom_front", left_bottom_front),
            ],
            Normals::Flat | Normals::Sphere => Vec::new(),
        }
    }

    /// The unit normal at corner coordinates `uv` of a quad with half axes `half_x`, `half_y`
    /// (at right angles), facing the side `toward_eye` (from its centre) points to; for a
    /// normal map, `tangent` is the map's normal there in the quad's frame ((r, g, b) · 2 − 1).
    /// The f64 twin of the WGSL `sprite_basis` and `lit_light`'s normal.
    pub fn normal(
        &self,
        uv: (f64, f64),
        (half_x, half_y): (DVec3, DVec3),
        toward_eye: DVec3,
        tangent: DVec3,
    ) -> DVec3 {
        let (ux, uy, facing) = basis((half_x, half_y), toward_eye);
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
            // Six-way lightmaps have no normal: the card's facing.
            Normals::SixWay { .. } => facing,
        }
    }

    /// The light (per channel) that the pixel at corner coordinates `uv`, point `p`, of a
    /// quad with half axes `axes` facing the side `toward_eye` points to receives from
    /// `lights` (all in one space): by its normal for `Flat`, `Sphere` and `Map` (as
    /// [`crate::features::lights::Lights::received`]), or through its six-way lightmaps.
    /// `maps` are the look's map texels there (RGBA in [0, 1], in `map_files` order;
    /// unread without maps). The f64 twin of the WGSL `lit_light`.
    pub fn light(
        &self,
        lights: &crate::features::lights::Lights,
        (uv, axes, toward_eye, p): ((f64, f64), (DVec3, DVec3), DVec3, DVec3),
        maps: [glam::DVec4; 2],
    ) -> DVec3 {
        let decoded = maps[0].truncate() * 2.0 - DVec3::ONE;
        if !matches!(self.normals, Normals::SixWay { .. }) {
            let n = self.normal(uv, axes, toward_eye, decoded);
            return lights.received(n, p, self.wrap);
        }
        let (ux, uy, facing) = basis(axes, toward_eye);
        let (rtb, lbf) = (maps[0].truncate(), maps[1].truncate());
        let mut light = lights.ambient * ((rtb.element_sum() + lbf.element_sum()) / 6.0);
        for (toward, color) in lights.incoming(p) {
            let t = DVec3::new(toward.dot(ux), toward.dot(uy), toward.dot(facing));
            let response = DVec3::new(
                if t.x > 0.0 { rtb.x } else { lbf.x },
                if t.y > 0.0 { rtb.y } else { lbf.y },
                // Front (+z, the viewer's side) is the second map's, back the first's.
                if t.z > 0.0 { lbf.z } else { rtb.z },
            );
            light += color * (t * t).dot(response);
        }
        light
    }

    /// Emits, for a look with maps (a normal map, six-way lightmaps), `lit_map_texel_k` for
    /// each (its texel, as `frame_texel` samples the texture) and the maps' texels at a
    /// pixel, as the columns of a `mat2x4`: `lit_maps(in)` for the fragment shader (their
    /// derivatives taken before any discard) and, for the compute renderer,
    /// `splat_lit_maps(uv, du, dv, frame)`; nothing for computed normals.
    pub(crate) fn emit_map_fns(&self, w: &mut Writer, splat: bool) {
        let maps = self.map_files().len();
        if maps == 0 {
            return;
        }
        use crate::features::looks::texture::TextureIr;
        for k in 0..maps {
            TextureIr::emit_texel_fn_of(w, &format!("lit_map_texel_{k}"), &format!("lit_map_{k}"));
            w.blank();
        }
        let columns = |w: &mut Writer| {
            let texels: Vec<String> = (0..2)
                .map(|k| match k < maps {
                    true => format!("lit_map_texel_{k}(cell, quad, gx, gy)"),
                    false => "vec4<f32>(0.0)".to_string(),
                })
                .collect();
            w.line(format!("return mat2x4<f32>({});", texels.join(", ")));
        };
        w.comment("The lit look's map texels at this fragment (columns: the maps in order).");
        w.block("fn lit_maps(in: Sprite) -> mat2x4<f32>", |w| {
            TextureIr::emit_fragment_coordinates(w);
            columns(w);
        });
        if splat {
            w.blank();
            w.comment("The lit look's map texels at corner coordinates uv (their derivatives du, dv), for the compute renderer.");
            w.block(
                "fn splat_lit_maps(uv: vec2<f32>, du: vec2<f32>, dv: vec2<f32>, frame: u32) -> mat2x4<f32>",
                |w| {
                    TextureIr::emit_splat_coordinates(w);
                    columns(w);
                },
            );
        }
    }

    /// The WGSL of the look's map texels at a fragment (`in`): `lit_maps(in)`, or zeros that
    /// `lit_light` does not read.
    pub(crate) fn maps_wgsl(&self) -> &'static str {
        match self.map_files().is_empty() {
            false => "lit_maps(in)",
            true => "mat2x4<f32>()",
        }
    }

    /// The WGSL of the look's map texels at corner coordinates `uv` in the compute renderer's
    /// composite (`du`, `dv`, the frame in `r3.y`), as [`Self::maps_wgsl`].
    pub(crate) fn splat_maps_wgsl(&self) -> &'static str {
        match self.map_files().is_empty() {
            false => "splat_lit_maps(uv, du, dv, r3.y)",
            true => "mat2x4<f32>()",
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
    /// `lit_light(uv, basis, maps, p)`, the light at corner coordinates `uv`, view-space point
    /// `p`, and `lit_color(c, light)`: the WGSL twins of [`Self::light`] and [`Self::shade`].
    /// The look's maps are declared here too.
    pub(crate) fn emit_lit_color(&self, w: &mut Writer, turned: bool) {
        crate::features::lights::emit_received_light(w, self.wrap, self.shadow_lookup());
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
        for (k, binding) in LIT_MAP_BINDINGS
            .iter()
            .enumerate()
            .take(self.map_files().len())
        {
            w.line(format!(
                "@group(0) @binding({binding}) var lit_map_{k}: texture_2d<f32>;"
            ));
        }
        w.comment("The light the pixel at corner coordinates uv, view-space point p, of a sprite of that basis receives (maps: its map texels there).");
        w.block(
            "fn lit_light(uv: vec2<f32>, basis: mat3x3<f32>, maps: mat2x4<f32>, p: vec3<f32>) -> vec3<f32>",
            |w| match self.normals {
                Normals::Flat => w.line("return received_light(basis[2], p);"),
                Normals::Sphere => {
                    w.comment("A half sphere over the quad: unit inside the disc, normalised past its rim.");
                    w.line("let m = uv.x * basis[0] + uv.y * basis[1] + sqrt(max(1.0 - dot(uv, uv), 0.0)) * basis[2];");
                    w.line("return received_light(m * inverseSqrt(max(dot(m, m), 1.0)), p);");
                }
                Normals::Map { .. } => {
                    w.comment("The normal map's normal, in the sprite's frame (texels hold (n + 1) / 2).");
                    w.line("let m = basis * (maps[0].xyz * 2.0 - 1.0);");
                    w.line("return received_light(m * inverseSqrt(max(dot(m, m), 1e-12)), p);");
                }
                Normals::SixWay { .. } => {
                    w.comment("Six-way lightmaps: right, top, back in the first; left, bottom, front in the second.");
                    w.line("let rtb = maps[0].xyz;");
                    w.line("let lbf = maps[1].xyz;");
                    w.line("var light = lights.ambient.rgb * ((dot(rtb, vec3<f32>(1.0)) + dot(lbf, vec3<f32>(1.0))) / 6.0);");
                    w.block(
                        format!("for (var i = 0u; i < min(lights.count.x, {}u); i++)", crate::features::lights::LIGHTS_MOST),
                        |w| {
                            crate::features::lights::emit_incoming(w, self.shadow_lookup());
                            w.comment("Toward the light in the sprite's frame; each axis weighted t², its map by the sign.");
                            w.line("let t = toward * basis;");
                            w.line("let response = select(lbf, rtb, vec3<bool>(t.x > 0.0, t.y > 0.0, t.z <= 0.0));");
                            w.line("light += color * dot(t * t, response);");
                        },
                    );
                    w.line("return light;");
                }
            },
        );
        w.blank();
        emit_lit_color_fn(w);
    }

    /// Emits what a lit trail's strip needs (the trail draw module's): the lights'
    /// declarations, `received_light` and `lit_color`. A strip is a flat card: its normal comes
    /// from its geometry ([`crate::features::looks::trail::strip_normals`]), whatever
    /// `normals` says (maps are a sprite's texture).
    pub(crate) fn emit_strip_lighting(&self, w: &mut Writer) {
        crate::features::lights::emit_received_light(w, self.wrap, self.shadow_lookup());
        w.line(format!(
            "const LIT_EMISSIVE: f32 = {};",
            f32_lit(self.emissive)
        ));
        w.blank();
        emit_lit_color_fn(w);
        w.blank();
        emit_card_normal_fn(w);
    }
}

/// `card_normal(c, along)`: the unit normal of a lit strip (a trail's or a ribbon's) at
/// view-space point `c`, running `along` there: a flat card facing the eye, the way to the eye
/// made square to the strip. The WGSL twin of
/// [`strip_normals`](crate::features::looks::trail::strip_normals).
pub(crate) fn emit_card_normal_fn(w: &mut Writer) {
    w.comment("A lit strip's normal at view-space c, running along `along`: the way to the eye (the view's origin), square to the strip.");
    w.block(
        "fn card_normal(c: vec3<f32>, along: vec3<f32>) -> vec3<f32>",
        |w| {
            w.line("let e = -c;");
            w.line("let facing = e - along * (dot(e, along) / max(dot(along, along), 1e-30));");
            w.line("return facing * inverseSqrt(max(dot(facing, facing), 1e-30));");
        },
    );
}

/// `lit_color(c, light)`: the WGSL twin of [`Lit::shade`] (`LIT_EMISSIVE` in scope).
fn emit_lit_color_fn(w: &mut Writer) {
    w.comment("Colour c lit by light: its unlit (emissive) part plus the rest times the light.");
    w.block(
        "fn lit_color(c: vec4<f32>, light: vec3<f32>) -> vec4<f32>",
        |w| {
            w.line("return vec4<f32>(c.rgb * (LIT_EMISSIVE + (1.0 - LIT_EMISSIVE) * light), c.a);");
        },
    );
}

/// A quad's basis: its unit axes (`axes` at right angles) and its facing, toward the side
/// `toward_eye` points to. The f64 twin of the WGSL `sprite_basis`.
fn basis((half_x, half_y): (DVec3, DVec3), toward_eye: DVec3) -> (DVec3, DVec3, DVec3) {
    let (ux, uy) = (half_x.normalize_or_zero(), half_y.normalize_or_zero());
    let facing = ux.cross(uy);
    match facing.dot(toward_eye) < 0.0 {
        true => (ux, uy, -facing),
        false => (ux, uy, facing),
    }
}
