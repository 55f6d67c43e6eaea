//! The compute renderer's part of the draw module: its bindings and the `project` kernel, which
//! writes each sprite's record and tile box for the compute renderer's tile kernels (the runtime's
//! `splat.wgsl`).
//!
//! Two kinds of record. Round camera-facing sprites ([`splat_discs`]) are discs: 16 bytes (a
//! centre, an extent, a colour), composited by the runtime's fixed `raster` kernel. Every other
//! sprite (a texture, an orientation, a rotation, its own height) is a quad: 64 bytes holding
//! the projective map from the image's pixels back to the quad's corner coordinates, so that a
//! pixel finds where it lies on the sprite (and the derivatives a texture's mip level needs)
//! as the rasteriser's perspective-correct interpolation would; the kernel that composites
//! them, `composite`, is generated here with the effect's own shading.

mod composite;
mod light;
mod masks;
mod quads;

pub(crate) use composite::{batch_stride, emit_composite, Prefetch, RecordBatch, SPLAT_BATCH};
pub use composite::{splat_slices, SPLAT_PARTIAL_BINDING, SPLAT_SLICES};
pub use light::{splat_light_ceiling, splat_light_constants};
pub(crate) use quads::{emit_project_quads, emit_quad_raster};
pub use quads::{splat_affine_quads, SPLAT_FLAT_VIEW};

use super::{DrawShape, SPLAT_BINDINGS, SPLAT_TILE};
use crate::base::writer::{f32_lit, Writer};
use crate::features::looks::orient::OrientIr;
use crate::ir::EffectIr;

/// Whether the compute renderer draws `ir`'s sprites as discs (round, camera-facing, square, untextured:
/// the runtime's fixed raster kernel) rather than as quads (`composite`, generated). Into
/// an HDR image (`hdr`: the effect or its graph glows) sprites are drawn as quads: their
/// colours may pass what a disc's 10-bit record holds.
pub fn splat_discs(ir: &EffectIr, hdr: bool) -> bool {
    ir.render.orient == OrientIr::Camera
        && ir.render.texture.is_none()
        && ir.render.size_y.is_none()
        && ir.render.lit.is_none()
        && !hdr
}

/// Why the compute renderer cannot draw `ir`'s mesh look: only solid meshes
/// ([`crate::features::looks::mesh_splat`]); `None` when it can, or when `ir` draws no meshes.
pub fn splat_mesh_refusal(ir: &EffectIr) -> Option<&'static str> {
    ir.render.mesh.as_ref()?;
    crate::features::looks::mesh_splat::refusal(ir.render.blend)
}

/// Whether the compute renderer builds `ir`'s tile lists without a sort: additive light, which the
/// composites (the generated one of quads and ribbon segments, and the runtime's disc kernel)
/// sum in fixed point, the same in any order. Its `project` keeps the counts once, for no
/// scan reads a second copy.
pub fn splat_additive_lists(ir: &EffectIr) -> bool {
    ir.render.blend == crate::stages::schema::Blend::Additive
}

/// Pixels per row of the compute renderer's HDR image (a glowing effect's): the width rounded up to 32,
/// so that a row of 8-byte pixels is a whole number of 256-byte copy rows and the image can be
/// copied into the glow's HDR texture as it is.
pub fn splat_hdr_pitch(width: u32) -> u32 {
    width.next_multiple_of(32)
}

/// 32-bit words of a quad's record: rows of the pixel-to-corner map (xyz) with the colour's
/// red, green and blue (w); for a host's image (`host`) the quad's clip-space depth terms
/// (centre, x and y half axes), from which a pixel's depth follows; for a lit look of `ir`
/// the quad's place in view space, which its normal and the light at a pixel follow from
/// (`lit_record_vec4s`); last, alpha, the flipbook frame and the pixel box's two corners.
pub fn splat_quad_words(ir: &EffectIr, host: bool) -> u64 {
    16 + if host { 4 } else { 0 } + 4 * u64::from(lit_record_vec4s(ir))
}

/// Vec4s of a lit quad's record that place it in view space (after the host's depth terms
/// when there are, [`lit_record_row`]): for a turned quad (`RenderIr::turns_quad`) four,
/// (unit x axis, centre x), (unit y axis, centre y), (facing, centre z), (half width, half
/// height, 0, 0); for an upright camera-facing one, whose basis is the view's own, one,
/// (centre, half size); none for an unlit look.
pub(crate) fn lit_record_vec4s(ir: &EffectIr) -> u32 {
    match (ir.render.lit.is_some(), ir.render.turns_quad()) {
        (false, _) => 0,
        (true, true) => 4,
        (true, false) => 1,
    }
}

/// The first vec4 of a lit quad's record that places it ([`lit_record_vec4s`]).
pub(crate) fn lit_record_row(host: bool) -> u32 {
    3 + u32::from(host)
}

/// How the compute renderer meets a host's image (the embedding API's compute draw): the image keeps each
/// pixel's coverage, so that a full-screen pass can put it over the host's colour, and every
/// pixel of a sprite or ribbon is tested against the host's depth (a copy of it, one f32 a
/// pixel at [`SPLAT_HOST_DEPTH_BINDING`]) as the rasteriser's depth test would test its
/// fragment, and faded by `render.soft` as the fragment shader would fade it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplatHost {
    /// The host's depth test; None when the host draws without depth (nothing hides
    /// particles).
    pub depth: Option<HostDepthTest>,
    /// Whether `render.soft` sprites fade against the host's depth.
    pub soft: bool,
}

/// Which particle depths pass a host's depth test: its compare function, particle against
/// scene, on NDC depth (`Greater` for reversed Z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HostDepthTest {
    /// Nearer with a standard depth buffer.
    Less,
    /// Nearer or level, standard depth.
    LessEqual,
    /// Nearer with reversed Z.
    Greater,
    /// Nearer or level, reversed Z.
    GreaterEqual,
    /// Every particle passes (only the soft fade reads the depth).
    Always,
}

impl HostDepthTest {
    /// The WGSL comparison that passes `z` against `scene`.
    pub(crate) fn passes(self) -> &'static str {
        match self {
            HostDepthTest::Less => "z < scene",
            HostDepthTest::LessEqual => "z <= scene",
            HostDepthTest::Greater => "z > scene",
            HostDepthTest::GreaterEqual => "z >= scene",
            HostDepthTest::Always => "true",
        }
    }
}

/// How the compute mesh draw meets `host`: by its depth test's convention (reversed Z for
/// `Greater` and `GreaterEqual`) and against its depth.
pub(crate) fn mesh_host(host: SplatHost) -> crate::features::looks::mesh_splat::MeshHost {
    crate::features::looks::mesh_splat::MeshHost {
        reversed: matches!(
            host.depth,
            Some(HostDepthTest::Greater | HostDepthTest::GreaterEqual)
        ),
        passes: host.depth.map(HostDepthTest::passes),
        depth_binding: SPLAT_HOST_DEPTH_BINDING,
    }
}

/// Binding of the host's depth in a host splat: one f32 a pixel, rows of the image's width.
pub const SPLAT_HOST_DEPTH_BINDING: u32 = 34;

/// Whether a host splat's records are tested against the host's depth (`host_fade`).
pub(crate) fn host_depth(shape: &DrawShape) -> bool {
    shape.host.is_some_and(|h| h.depth.is_some())
}

/// `host_fade(pixel, z)`: the share of a record's alpha that the host's depth lets through at
/// the pixel centre `pixel` for NDC depth `z`: 0 where the depth test fails, else 1, or for a
/// soft effect how far the scene lies behind over the fade distance (the fragment shader's
/// `soft_fade`).
fn emit_host_fade(w: &mut Writer, ir: &EffectIr, host: SplatHost, raster_soft: bool) {
    let Some(test) = host.depth else {
        return;
    };
    w.comment("The host's depth, one f32 a pixel (a copy of its depth image).");
    w.line(format!(
        "@group(0) @binding({SPLAT_HOST_DEPTH_BINDING}) var<storage, read> host_depth: array<f32>;"
    ));
    let soft = ir.render.soft.filter(|_| host.soft);
    if let Some(distance) = soft {
        w.line(format!(
            "const HOST_SOFT_DISTANCE: f32 = {};",
            f32_lit(distance)
        ));
        // A module soft for the raster draw too has it already (`emit_soft`).
        if !raster_soft {
            super::common::emit_view_distance(w);
        }
    }
    w.comment("The share of a record's alpha the host's depth lets through at pixel centre `pixel`, for NDC depth z.");
    w.block("fn host_fade(pixel: vec2<f32>, z: f32) -> f32", |w| {
        w.line("let scene = host_depth[u32(pixel.y) * splat_tiles.width + u32(pixel.x)];");
        w.block(format!("if (!({}))", test.passes()), |w| {
            w.line("return 0.0;")
        });
        match soft {
            Some(_) => w.line(
                "return clamp((view_distance(scene) - view_distance(z)) / HOST_SOFT_DISTANCE, 0.0, 1.0);",
            ),
            None => w.line("return 1.0;"),
        }
    });
}

/// Bindings `composite` reads besides the records: the tile parameters (the runtime's
/// `Params`, 8 words), the sorted entries' sprites, each tile's run of entries, the image.
pub const SPLAT_RASTER_BINDINGS: [u32; 4] = [25, 26, 27, 28];

/// The compute renderer's declarations: its view and output buffers (bindings [`SPLAT_BINDINGS`]), for
/// quads the tile buffers `composite` reads ([`SPLAT_RASTER_BINDINGS`]), and for a host's
/// image its depth (`host_fade`).
pub(crate) fn emit_splat_declarations(
    w: &mut Writer,
    ir: &EffectIr,
    discs: bool,
    shape: &DrawShape,
) {
    let hdr = shape.hdr;
    w.comment("The compute renderer's image: size in pixels, tiles, and the instances to project.");
    w.block("struct SplatView", |w| {
        w.line("width: u32,");
        w.line("height: u32,");
        w.line("tiles_x: u32,");
        w.line("count: u32,");
    });
    let [view, splats, counts, offsets, boxes] = SPLAT_BINDINGS;
    w.line(format!(
        "@group(0) @binding({view}) var<uniform> splat_view: SplatView;"
    ));
    w.comment("Records as words (a quad's floats bitcast), so packed integers never pass through float registers.");
    w.line(format!(
        "@group(0) @binding({splats}) var<storage, read_write> splats: array<vec4<u32>>;"
    ));
    w.line(format!(
        "@group(0) @binding({counts}) var<storage, read_write> tile_counts: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({offsets}) var<storage, read_write> tile_offsets: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({boxes}) var<storage, read_write> tile_boxes: array<vec2<u32>>;"
    ));
    w.blank();
    emit_place_helpers(w);
    if let Some(host) = shape.host {
        w.blank();
        emit_host_fade(w, ir, host, shape.soft);
    }
    if discs {
        return;
    }
    w.blank();
    w.comment("The tile kernels' parameters (the runtime's splat.wgsl `Params`).");
    w.block("struct SplatTiles", |w| {
        for field in [
            "width",
            "height",
            "tiles_x",
            "tiles",
            "count",
            "entries",
            "additive",
            "background",
            "light_ceiling",
        ] {
            w.line(format!("{field}: u32,"));
        }
    });
    let [params, sprites, ranges, image] = SPLAT_RASTER_BINDINGS;
    w.line(format!(
        "@group(0) @binding({params}) var<uniform> splat_tiles: SplatTiles;"
    ));
    w.line(format!(
        "@group(0) @binding({sprites}) var<storage, read> tile_sprites: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({ranges}) var<storage, read> tile_ranges: array<vec2<u32>>;"
    ));
    w.comment(if hdr {
        "The image: HDR (the effect glows), (r, g) and (b, 1) as f16 pairs, rows of splat_hdr_pitch(width) pixels."
    } else {
        "The image: RGBA8 pixels."
    });
    w.line(format!(
        "@group(0) @binding({image}) var<storage, read_write> splat_image: array<{}>;",
        if hdr { "vec2<u32>" } else { "u32" }
    ));
}

/// `project`: the compute renderer's first kernel. Instance k's sprite as the rasteriser would place it,
/// in 16 bytes: its centre in pixels (two f32), its half extent in pixels and its alpha (two
/// f16), its RGB (three 10-bit unorms); and how many screen tiles its pixels touch (0 when
/// hidden, clipped, or covering no pixel centre). Pixels are square (the projection's aspect is
/// the image's), so one extent serves both axes.
pub(crate) fn emit_project(w: &mut Writer, ir: &EffectIr) {
    // Alpha discs blend in their sorted lists' order; additive ones in any.
    emit_project_kernel(w, !splat_additive_lists(ir), &|w: &mut Writer| {
        w.line("let s = sprite_at(k);");
        w.block("if (s.visible)", |w| {
                w.line("let clip = draw.proj * s.center;");
                w.comment("All corners share z and w: the rasteriser clips the whole sprite or none of it.");
                w.block("if (unclipped(clip))", |w| {
                    w.line("let h = 0.5 * s.size;");
                    w.line("let size = vec2<f32>(f32(splat_view.width), f32(splat_view.height));");
                    w.line("let extent = abs((draw.proj * vec4<f32>(h, 0.0, 0.0, 0.0)).x / clip.w) * 0.5 * size.x;");
                    w.comment("The extent as stored (f16), as the tile kernels see it.");
                    w.line("let packed = pack2x16float(vec2<f32>(extent, s.color.a));");
                    w.line("let e = unpack2x16float(packed).x;");
                    w.line("let c = clip_pixel(clip, size);");
                    w.comment("Pixels whose centres (i + 0.5) lie strictly inside the sprite.");
                    w.line("let lo = first_pixel(c - e);");
                    w.line("let hi = last_pixel(c + e, size);");
                    w.block("if (all(lo <= hi))", |w| {
                        w.line("tiles = box_tiles(k, lo, hi);");
                        w.line("let rgb = vec3<u32>(round(clamp(s.color.rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * 1023.0));");
                        w.line("splats[k] = vec4<u32>(bitcast<vec2<u32>>(c), packed, rgb.x | (rgb.y << 10u) | (rgb.z << 20u));");
                    });
                });
            });
    });
}

/// A `project` kernel: a thread per record k (under `splat_view.count`), `tiles` = 0 until
/// `body` counts the tiles record k touches (and writes its record), then the count kept; for
/// sorted lists (`offsets`) kept twice: the runtime scans the second copy in place into the
/// entries' offsets (additive lists are placed from the counts alone, [`splat_additive_lists`]).
pub(crate) fn emit_project_kernel(w: &mut Writer, offsets: bool, body: &dyn Fn(&mut Writer)) {
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let k = gid.x + gid.y * groups.x * 256u;");
            w.block("if (k >= splat_view.count)", |w| w.line("return;"));
            w.line("var tiles = 0u;");
            body(w);
            w.line("tile_counts[k] = tiles;");
            if offsets {
                w.line("tile_offsets[k] = tiles;");
            }
        },
    );
}

/// The WGSL every `project` shares to place a record in the image: a clip-space point's pixel,
/// whether the rasteriser keeps a vertex, the pixel centres a span of the image covers, the
/// tiles of a pixel box (recorded in `tile_boxes`), the box packed for the composite, a
/// clip-space vector's homogeneous pixel coordinates, and the inverse of a 3x3 map.
fn emit_place_helpers(w: &mut Writer) {
    w.comment("A clip-space point's pixel (x right, y down).");
    w.block(
        "fn clip_pixel(q: vec4<f32>, size: vec2<f32>) -> vec2<f32>",
        |w| {
            w.line("return vec2<f32>(q.x / q.w * 0.5 + 0.5, 0.5 - q.y / q.w * 0.5) * size;");
        },
    );
    w.comment("Whether the rasteriser keeps a vertex unclipped: in front of the camera, inside the depth range.");
    w.block("fn unclipped(q: vec4<f32>) -> bool", |w| {
        w.line("return q.w > 0.0 && q.z >= 0.0 && q.z <= q.w;");
    });
    w.comment("The first and last pixels whose centres (i + 0.5) a span from lo to hi holds, in the image.");
    w.block("fn first_pixel(lo: vec2<f32>) -> vec2<f32>", |w| {
        w.line("return max(ceil(lo - 0.5), vec2<f32>(0.0));");
    });
    w.block(
        "fn last_pixel(hi: vec2<f32>, size: vec2<f32>) -> vec2<f32>",
        |w| {
            w.line("return min(floor(hi - 0.5), size - 1.0);");
        },
    );
    w.comment("Record k's tiles, from its pixel box: kept in tile_boxes (x0 | y0 << 16, x1 | y1 << 16), and counted.");
    w.block(
        "fn box_tiles(k: u32, first: vec2<f32>, last: vec2<f32>) -> u32",
        |w| {
            w.line(format!("let t0 = vec2<u32>(first) / {SPLAT_TILE}u;"));
            w.line(format!("let t1 = vec2<u32>(last) / {SPLAT_TILE}u;"));
            w.line("tile_boxes[k] = vec2<u32>(t0.x | (t0.y << 16u), t1.x | (t1.y << 16u));");
            w.line("return (t1.x - t0.x + 1u) * (t1.y - t0.y + 1u);");
        },
    );
    w.comment("A pixel box as the composite reads it: its corners as x | y << 16.");
    w.block("fn pack_box(first: vec2<f32>, last: vec2<f32>) -> vec2<u32>", |w| {
        w.line("return vec2<u32>(u32(first.x) | (u32(first.y) << 16u), u32(last.x) | (u32(last.y) << 16u));");
    });
    w.comment("A clip-space vector's homogeneous pixel coordinates (x right, y down, w), counted from pixel `origin`: a point's pixel is xy / w.");
    w.block(
        "fn to_pixels(q: vec4<f32>, origin: vec2<f32>, size: vec2<f32>) -> vec3<f32>",
        |w| {
            w.line("let h = vec2<f32>(0.5 * size.x * (q.x + q.w), 0.5 * size.y * (q.w - q.y));");
            w.line("return vec3<f32>(h - origin * q.w, q.w);");
        },
    );
    w.comment("The rows of the inverse of the map whose columns are a, b, c (det = a . (b x c), not 0): the adjugate over the determinant.");
    w.block(
        "fn inverse_rows(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, det: f32) -> mat3x3<f32>",
        |w| {
            w.line("return mat3x3<f32>(cross(b, c) / det, cross(c, a) / det, cross(a, b) / det);");
        },
    );
}
