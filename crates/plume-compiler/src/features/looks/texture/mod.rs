//! Sprite textures and flipbooks (`render.texture`). This module owns the option end to end:
//! loading the PNG (with errors located at `render.texture.file`), its lowered form, which
//! frame a particle shows (the WGSL of the draw module and its f64 twin for the reference
//! drawing), and how the fragment shader samples the frame.
//!
//! The texture is decoded to RGBA8 and used as stored: a texel multiplies the sprite's colour
//! component by component (no sRGB decoding, as the colour stops are written straight to the
//! image). The sprite's corner coordinates (cx, cy) in [-1, 1]² (see [`crate::features::looks::orient`]) map to
//! the frame's (u, v) = ((cx + 1) / 2, (1 − cy) / 2): the image's top row at the quad's +y
//! side, its left column at −x. Texels are filtered trilinearly over mip levels that keep every
//! frame whole, clamped half a texel inside the frame so that no neighbouring frame of the atlas
//! bleeds in. A second image laid out as the first may multiply the colour too (`second`).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::base::files::ReadError;
use crate::base::rng::{rand_u32, stream};
use crate::base::writer::{f32_lit, u32_lit, Writer};
use serde::Deserialize;

mod check;
mod second;
pub use second::{SecondTexture, SECOND_TEXTURE_BINDING};

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
    pub(crate) play: Play,
    /// With `Rate`: each particle starts the loop at a frame drawn from its id, so particles
    /// born together do not play in step (a flock's wing beats).
    #[serde(default)]
    pub random_start: bool,
    /// What a texel does to the sprite's colour.
    #[serde(default)]
    pub sample: Sample,
    /// A second image laid out as this one, sampled at the same place; its texel multiplies
    /// the colour too, as its own `sample` maps it.
    #[serde(default)]
    pub second: Option<SecondTexture>,
}

/// What a texel does to the sprite's colour (`render.texture.sample`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Sample {
    /// The colour times the texel, RGBA.
    #[default]
    Modulate,
    /// The colour's RGB times the texel's; its opacity as it is (the texel's alpha unused).
    ModulateRgb,
    /// The texel's red channel is the sprite's shape: the opacity times it, the colour as it
    /// is (a greyscale mask).
    OpacityFromRed,
}

impl Sample {
    /// The texel `t` (WGSL) as this mapping makes it, to multiply the colour by; None for
    /// `Modulate` (the texel itself).
    fn mapped_wgsl(self) -> Option<&'static str> {
        match self {
            Sample::Modulate => None,
            Sample::ModulateRgb => Some("vec4<f32>(t.rgb, 1.0)"),
            Sample::OpacityFromRed => Some("vec4<f32>(1.0, 1.0, 1.0, t.r)"),
        }
    }

    /// The f64 twin of `mapped_wgsl`: what multiplies the colour for texel `t`.
    pub fn mapped(self, t: [f64; 4]) -> [f64; 4] {
        match self {
            Sample::Modulate => t,
            Sample::ModulateRgb => [t[0], t[1], t[2], 1.0],
            Sample::OpacityFromRed => [1.0, 1.0, 1.0, t[0]],
        }
    }
}

fn one_frame() -> (u32, u32) {
    (1, 1)
}

/// How a flipbook's frames play (`render.texture.play`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub(crate) enum Play {
    /// Once over each particle's life: frame k of n from life fraction k/n (frame 0 for a
    /// particle that never dies).
    #[default]
    OverLife,
    /// At this many frames per second of the particle's age, looping.
    Rate(f64),
}

/// Largest texture side accepted (texels): ample for a sprite atlas, and within wgpu's default
/// limits (8192) with room to spare.
pub(crate) const MAX_SIDE: u32 = 4096;

/// Binding of the texture in the draw module.
pub const TEXTURE_BINDING: u32 = 30;

/// Binding of its sampler.
pub const SAMPLER_BINDING: u32 = 31;

/// Added to the frame clock before taking its floor (in frames), so that a frame starting
/// exactly on a step starts on that step in f32 (GPU) and f64 (reference) alike.
pub(crate) const FRAME_EPSILON: f64 = 1.0 / 1024.0;

/// The texture, loaded and lowered.
#[derive(Clone, PartialEq)]
pub struct TextureIr {
    /// The file as the effect names it.
    pub file: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGBA8 texels, rows top to bottom.
    pub rgba: Arc<[u8]>,
    /// Atlas columns.
    pub columns: u32,
    /// Atlas rows.
    pub rows: u32,
    /// How the frames play.
    pub(crate) play: Play,
    /// Whether each particle's loop starts at a frame drawn from its id (with `Rate`).
    pub random_start: bool,
    /// What a texel does to the colour.
    pub sample: Sample,
    /// A second image laid out as this one (`render.texture.second`), its `sample` its own.
    pub second: Option<Box<TextureIr>>,
    /// Why the file could not be read, for an effect compiled to be stepped, not drawn
    /// (`CompileOptions::step_only`): the image is then a white stand-in, and a draw refuses
    /// with this message (the field's path, then what went wrong with the file).
    pub missing: Option<String>,
}

impl std::fmt::Debug for TextureIr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:?} {}x{} frames {}x{} {:?}{}",
            self.file,
            self.width,
            self.height,
            self.columns,
            self.rows,
            self.play,
            if self.random_start {
                " random start"
            } else {
                ""
            }
        )?;
        if self.missing.is_some() {
            write!(f, " (missing: a white stand-in)")?;
        }
        match &self.second {
            Some(second) => write!(f, ", times {:?} {second:?}", second.sample),
            None => Ok(()),
        }
    }
}

/// The most bytes a texture file may have (an 8192 x 8192 RGBA image stored raw).
pub(crate) const MAX_FILE_BYTES: u64 = 1 << 28;

/// Where `file` lies: relative to `base_dir` (the effect file's directory) when given.
pub fn resolve(file: &str, base_dir: Option<&Path>) -> PathBuf {
    match base_dir {
        Some(dir) => dir.join(file),
        None => PathBuf::from(file),
    }
}

impl TextureIr {
    /// Loads the texture `spec` names (already checked: frames at least 1x1, a positive rate).
    /// The error says what is wrong with the file, for `render.texture.file`.
    pub fn load(spec: &Texture, base_dir: Option<&Path>) -> Result<Self, String> {
        let path = resolve(&spec.file, base_dir);
        let bytes = crate::base::files::read(&path, MAX_FILE_BYTES).map_err(|e| {
            let shown = path.display();
            match e {
                ReadError::Open(e) => format!("cannot open texture {shown}: {e}"),
                ReadError::Read(e) => format!("cannot read texture {shown}: {e}"),
                ReadError::TooLarge(size) => format!(
                    "texture {shown} is {size} bytes, more than the {MAX_FILE_BYTES} a texture file may have"
                ),
            }
        })?;
        let image = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("cannot read texture {}: {e}", path.display()))?
            .decode()
            .map_err(|e| format!("cannot decode texture {}: {e}", path.display()))?
            .to_rgba8();
        let (width, height) = image.dimensions();
        let (columns, rows) = spec.frames;
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(format!(
                "texture {} is {width}x{height} texels; at most {MAX_SIDE} on a side is supported",
                path.display()
            ));
        }
        if width % columns != 0 || height % rows != 0 {
            return Err(format!(
                "texture {} is {width}x{height} texels, which a grid of {columns} x {rows} frames does not divide evenly",
                path.display()
            ));
        }
        Ok(Self {
            file: spec.file.clone(),
            width,
            height,
            rgba: image.into_raw().into(),
            columns,
            rows,
            play: spec.play,
            random_start: spec.random_start,
            sample: spec.sample,
            second: None,
            missing: None,
        })
    }

    /// A lit look's map in `file` (`render.lit.normals`: a normal map, a six-way lightmap),
    /// laid out as `texture`: its frames, how they play, and its size, which must be the
    /// texture's.
    pub(crate) fn load_lit_map(
        file: &str,
        texture: &TextureIr,
        base_dir: Option<&Path>,
    ) -> Result<Self, String> {
        Self::load_laid_out_as(file, texture, base_dir, "a lit look's map")
    }

    /// The image in `file` (`what` it is, for the error), laid out as `texture`: its frames,
    /// how they play, and its size, which must be the texture's.
    fn load_laid_out_as(
        file: &str,
        texture: &TextureIr,
        base_dir: Option<&Path>,
        what: &str,
    ) -> Result<Self, String> {
        let spec = texture.spec_of(file);
        let map = Self::load(&spec, base_dir)?;
        if (map.width, map.height) != (texture.width, texture.height) {
            return Err(format!(
                "{} is {}x{} texels; {what} is laid out as the texture {:?}, which is {}x{}",
                resolve(file, base_dir).display(),
                map.width,
                map.height,
                texture.file,
                texture.width,
                texture.height
            ));
        }
        Ok(map)
    }

    /// A lit look's map standing in for `file`, which could not be read (`missing` says why),
    /// laid out as `texture`: every texel (0.5, 0.5, 1), a flat normal.
    pub(crate) fn stand_in_lit_map(file: &str, texture: &TextureIr, missing: String) -> Self {
        let mut map = Self::stand_in(&texture.spec_of(file), missing);
        map.rgba = [128, 128, 255, 255].repeat(map.rgba.len() / 4).into();
        map
    }

    /// A `Texture` of `file` with this texture's frames and play.
    fn spec_of(&self, file: &str) -> Texture {
        Texture {
            file: file.to_string(),
            frames: (self.columns, self.rows),
            play: self.play,
            random_start: self.random_start,
            sample: self.sample,
            second: None,
        }
    }

    /// The texture `spec` names, standing in for a file that could not be read (`missing`
    /// says why): its frames and how they play, each frame one white texel.
    pub(crate) fn stand_in(spec: &Texture, missing: String) -> Self {
        let (columns, rows) = spec.frames;
        Self {
            file: spec.file.clone(),
            width: columns,
            height: rows,
            rgba: vec![255; (columns * rows * 4) as usize].into(),
            columns,
            rows,
            play: spec.play,
            random_start: spec.random_start,
            sample: spec.sample,
            second: None,
            missing: Some(missing),
        }
    }

    /// Frames in the atlas.
    pub fn frames(&self) -> u32 {
        self.columns * self.rows
    }

    /// Whether the frame shown depends on a particle's age (a flipbook of several frames).
    pub fn animated(&self) -> bool {
        self.frames() > 1
    }

    /// Whether choosing the frame needs the age of particles that never die (a rate).
    pub(crate) fn needs_age_of_immortals(&self) -> bool {
        self.animated() && matches!(self.play, Play::Rate(_))
    }

    /// Whether choosing the frame draws a random number (a random first frame).
    pub(crate) fn draws_random(&self) -> bool {
        self.animated() && self.random_start
    }

    /// The frame shown by particle `id` (of an effect whose seed mixes to `seed_mix`) that has
    /// lived `lived` whole steps of `life` (0: it never dies) with steps of `dt` seconds: the
    /// f64 twin of `sprite_frame` in the draw module.
    pub fn frame(&self, id: u32, seed_mix: u32, lived: u64, life: u64, dt: f64) -> u32 {
        let n = u64::from(self.frames());
        if n <= 1 {
            return 0;
        }
        match self.play {
            Play::OverLife if life == 0 => 0,
            // Integer arithmetic, so that the GPU and the CPU agree at every boundary.
            Play::OverLife => ((lived.min(life) * n / life).min(n - 1)) as u32,
            Play::Rate(fps) => {
                let clock = (lived as f64 * (dt * fps) + FRAME_EPSILON).floor() as u64;
                let start = match self.random_start {
                    true => u64::from(rand_u32(seed_mix, id, stream::FLIPBOOK)) % n,
                    false => 0,
                };
                ((clock % n + start) % n) as u32
            }
        }
    }

    /// Frame `k`'s texel rectangle `(x0, y0, width, height)` in the image.
    pub fn frame_texels(&self, k: u32) -> [u32; 4] {
        let (w, h) = (self.width / self.columns, self.height / self.rows);
        [(k % self.columns) * w, (k / self.columns) * h, w, h]
    }

    /// Emits the texture's bindings and constants.
    pub(crate) fn emit_declarations(&self, w: &mut Writer) {
        w.comment(format!(
            "render.texture {:?}: {}x{} texels, {} x {} frames.",
            self.file, self.width, self.height, self.columns, self.rows
        ));
        w.line(format!(
            "@group(0) @binding({TEXTURE_BINDING}) var sprite_texture: texture_2d<f32>;"
        ));
        w.line(format!(
            "@group(0) @binding({SAMPLER_BINDING}) var sprite_sampler: sampler;"
        ));
        if let Some(second) = &self.second {
            second.emit_second_declaration(w);
        }
        w.line(format!(
            "const FRAME_COLUMNS: u32 = {};",
            u32_lit(self.columns)
        ));
        w.comment("A frame's extent in texture coordinates, the atlas's and a frame's in texels.");
        w.line(format!(
            "const FRAME_SIZE: vec2<f32> = vec2<f32>({}, {});",
            f32_lit(1.0 / f64::from(self.columns)),
            f32_lit(1.0 / f64::from(self.rows))
        ));
        w.line(format!(
            "const ATLAS_TEXELS: vec2<f32> = vec2<f32>({}, {});",
            f32_lit(f64::from(self.width)),
            f32_lit(f64::from(self.height))
        ));
        w.line(format!(
            "const FRAME_TEXELS: vec2<f32> = vec2<f32>({}, {});",
            f32_lit(f64::from(self.width / self.columns)),
            f32_lit(f64::from(self.height / self.rows))
        ));
    }

    /// Emits `sprite_frame(id, lived, life)` for an animated texture: the frame of particle
    /// `id` that has lived `lived` whole steps of `life` (0: it never dies), as [`Self::frame`].
    pub(crate) fn emit_frame_fn(&self, w: &mut Writer, dt: f64) {
        let n = self.frames();
        w.block(
            "fn sprite_frame(id: u32, lived: u32, life: u32) -> u32",
            |w| match self.play {
                Play::OverLife => {
                    w.comment(
                        "Frame k of n from life fraction k / n, in integers (as the reference).",
                    );
                    w.block("if (life == 0u)", |w| w.line("return 0u;"));
                    w.line(format!(
                        "return min(min(lived, life) * {} / life, {});",
                        u32_lit(n),
                        u32_lit(n - 1)
                    ));
                }
                Play::Rate(fps) => {
                    w.comment("Frames played by this age (whole steps), looping.");
                    w.line(format!(
                        "let clock = floor(f32(lived) * {} + {});",
                        f32_lit(dt * fps),
                        f32_lit(FRAME_EPSILON)
                    ));
                    if self.random_start {
                        w.comment("Each particle's loop starts at a frame drawn from its id.");
                        w.line(format!(
                            "let start = rand_u32(id, {}u) % {};",
                            stream::FLIPBOOK,
                            u32_lit(n)
                        ));
                        w.line(format!(
                            "return (u32(clock) % {n} + start) % {n};",
                            n = u32_lit(n)
                        ));
                    } else {
                        w.line(format!("return u32(clock) % {};", u32_lit(n)));
                    }
                }
            },
        );
    }

    /// Emits `frame_texel(cell, quad, gx, gy)`: the texel of the frame at atlas cell `cell`
    /// (column, row) at `quad` (the sprite's corner coordinates mapped to [0, 1]², v down),
    /// filtered for the screen-space derivatives `gx`, `gy` of its unclamped atlas coordinate.
    /// The fragment shader takes those derivatives from the rasteriser (`dpdxFine`), the
    /// compute renderer from its quad's projective map, so both sample the same mip levels.
    pub(crate) fn emit_texel_fn(&self, w: &mut Writer) {
        if let Some(second) = &self.second {
            return self.emit_texel_product_fn(second, w);
        }
        match self.sample.mapped_wgsl() {
            None => Self::emit_texel_fn_of(w, "frame_texel", "sprite_texture"),
            Some(mapped) => {
                Self::emit_texel_fn_of(w, "frame_texel_raw", "sprite_texture");
                w.comment(format!(
                    "The texel as render.texture.sample ({:?}) maps it.",
                    self.sample
                ));
                w.block(
                    "fn frame_texel(cell: vec2<f32>, quad: vec2<f32>, gx: vec2<f32>, gy: vec2<f32>) -> vec4<f32>",
                    |w| {
                        w.line("let t = frame_texel_raw(cell, quad, gx, gy);");
                        w.line(format!("return {mapped};"));
                    },
                );
            }
        }
    }

    /// Emits `name(cell, quad, gx, gy)`, [`Self::emit_texel_fn`]'s function for another atlas
    /// of the same layout bound as `texture` (a lit look's normal map).
    pub(crate) fn emit_texel_fn_of(w: &mut Writer, name: &str, texture: &str) {
        w.block(
            format!("fn {name}(cell: vec2<f32>, quad: vec2<f32>, gx: vec2<f32>, gy: vec2<f32>) -> vec4<f32>"),
            |w| {
                w.comment("Sample no nearer the frame's edge than half a texel of the coarser mip level in use, so no neighbouring frame blends in.");
                w.line("let rho = max(length(gx * ATLAS_TEXELS), length(gy * ATLAS_TEXELS));");
                w.line("let level = ceil(log2(max(rho, 1.0)));");
                w.line("let half_texel = min(vec2<f32>(0.5), 0.5 * exp2(level) / FRAME_TEXELS);");
                w.line("let local = clamp(quad, half_texel, vec2<f32>(1.0) - half_texel);");
                w.line(format!("return textureSampleGrad({texture}, sprite_sampler, (cell + local) * FRAME_SIZE, gx, gy);"));
            },
        );
    }

    /// Emits the fragment shader's body for a textured sprite: the frame's texel at the
    /// fragment's corner coordinates `in.uv`, times the colour (`frame_texel` in scope).
    pub(crate) fn emit_fragment_body(&self, w: &mut Writer) {
        Self::emit_fragment_coordinates(w);
        w.comment(
            "Only the triangle primitive reaches outside the quad: nothing of the frame there.",
        );
        w.block("if (any(abs(in.uv) > vec2<f32>(1.0)))", |w| {
            w.line("discard;")
        });
        w.line("return in.color * frame_texel(cell, quad, gx, gy);");
    }

    /// Emits, in a fragment shader's function of `in: Sprite`, the frame's atlas cell `cell`,
    /// the fragment's place in it `quad`, and the derivatives `gx`, `gy` of its atlas
    /// coordinate (taken here, before any discard).
    pub(crate) fn emit_fragment_coordinates(w: &mut Writer) {
        w.line(
            "let cell = vec2<f32>(f32(in.frame % FRAME_COLUMNS), f32(in.frame / FRAME_COLUMNS));",
        );
        w.line("let quad = vec2<f32>(in.uv.x + 1.0, 1.0 - in.uv.y) * 0.5;");
        w.comment("The mip level's derivatives, taken before any discard (uniform control flow) and before the half-texel clamp (which would flatten them at the frame's edge).");
        w.line("let unclamped = (cell + quad) * FRAME_SIZE;");
        w.line("let gx = dpdxFine(unclamped);");
        w.line("let gy = dpdyFine(unclamped);");
    }

    /// Emits, in the compute renderer's function of `uv`, `du`, `dv` and `frame`, the frame's
    /// atlas cell `cell`, the pixel's place in it `quad`, and the derivatives `gx`, `gy` of its
    /// atlas coordinate from those of `uv`.
    pub(crate) fn emit_splat_coordinates(w: &mut Writer) {
        w.line("let cell = vec2<f32>(f32(frame % FRAME_COLUMNS), f32(frame / FRAME_COLUMNS));");
        w.line("let quad = vec2<f32>(uv.x + 1.0, 1.0 - uv.y) * 0.5;");
        w.comment("quad's derivatives are half of uv's, v flipped; the atlas coordinate's are FRAME_SIZE times those.");
        w.line("let gx = vec2<f32>(du.x, -du.y) * 0.5 * FRAME_SIZE;");
        w.line("let gy = vec2<f32>(dv.x, -dv.y) * 0.5 * FRAME_SIZE;");
    }

    /// Emits the compute renderer's shading of a textured sprite: `splat_shade(uv, du, dv, color,
    /// frame)` is the frame's texel at corner coordinates `uv`, whose derivatives along the
    /// image's x and y are `du` and `dv`, times the colour (as [`Self::emit_fragment_body`]).
    pub(crate) fn emit_splat_shade(&self, w: &mut Writer) {
        w.block(
            "fn splat_shade(uv: vec2<f32>, du: vec2<f32>, dv: vec2<f32>, color: vec4<f32>, frame: u32) -> vec4<f32>",
            |w| {
                Self::emit_splat_coordinates(w);
                w.line("return color * frame_texel(cell, quad, gx, gy);");
            },
        );
    }

    /// Mip levels the atlas keeps: it halves while every frame's width and height stay whole
    /// texels, so that no texel of any level spans two frames (a 64x64 frame: 7 levels, down
    /// to 1x1; a 60x60 one: 3, down to 15x15).
    pub fn mip_levels(&self) -> u32 {
        let (frame_w, frame_h) = (self.width / self.columns, self.height / self.rows);
        1 + frame_w.trailing_zeros().min(frame_h.trailing_zeros())
    }
}

#[cfg(test)]
mod tests;
