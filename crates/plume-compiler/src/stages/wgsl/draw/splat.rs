//! The compute splat's part of the draw module: its bindings and the `project` kernel, which
//! writes each sprite's pixel centre, extent, colour and tile box for the splat's tile
//! kernels (the runtime's `splat.wgsl`).

use super::{SPLAT_BINDINGS, SPLAT_TILE};
use crate::base::writer::Writer;

/// The splat's declarations: its view and output buffers (bindings [`SPLAT_BINDINGS`]).
pub(crate) fn emit_splat_declarations(w: &mut Writer) {
    w.comment("The compute splat's image: size in pixels, tiles, and the instances to project.");
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
}

/// `project`: the splat's first kernel. Instance k's sprite as the rasteriser would place it,
/// in 16 bytes: its centre in pixels (two f32), its half extent in pixels and its alpha (two
/// f16), its RGB (three 10-bit unorms); and how many screen tiles its pixels touch (0 when
/// hidden, clipped, or covering no pixel centre). Pixels are square (the projection's aspect is
/// the image's), so one extent serves both axes.
pub(crate) fn emit_project(w: &mut Writer) {
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let k = gid.x + gid.y * groups.x * 256u;");
            w.block("if (k >= splat_view.count)", |w| w.line("return;"));
            w.line("var tiles = 0u;");
            w.line("let s = sprite_at(k);");
            w.block("if (s.visible)", |w| {
                w.line("let clip = draw.proj * s.center;");
                w.comment("All corners share z and w: the rasteriser clips the whole sprite or none of it.");
                w.block("if (clip.w > 0.0 && clip.z >= 0.0 && clip.z <= clip.w)", |w| {
                    w.line("let h = 0.5 * s.size;");
                    w.line("let size = vec2<f32>(f32(splat_view.width), f32(splat_view.height));");
                    w.line("let extent = abs((draw.proj * vec4<f32>(h, 0.0, 0.0, 0.0)).x / clip.w) * 0.5 * size.x;");
                    w.comment("The extent as stored (f16), as the tile kernels see it.");
                    w.line("let packed = pack2x16float(vec2<f32>(extent, s.color.a));");
                    w.line("let e = unpack2x16float(packed).x;");
                    w.line("let c = vec2<f32>(clip.x / clip.w * 0.5 + 0.5, 0.5 - clip.y / clip.w * 0.5) * size;");
                    w.comment("Pixels whose centres (i + 0.5) lie strictly inside the sprite.");
                    w.line("let lo = max(ceil(c - e - 0.5), vec2<f32>(0.0));");
                    w.line("let hi = min(floor(c + e - 0.5), size - 1.0);");
                    w.block("if (all(lo <= hi))", |w| {
                        w.line(format!(
                            "let t0 = vec2<u32>(lo) / {SPLAT_TILE}u;"
                        ));
                        w.line(format!(
                            "let t1 = vec2<u32>(hi) / {SPLAT_TILE}u;"
                        ));
                        w.line("tiles = (t1.x - t0.x + 1u) * (t1.y - t0.y + 1u);");
                        w.line("tile_boxes[k] = vec2<u32>(t0.x | (t0.y << 16u), t1.x | (t1.y << 16u));");
                        w.line("let rgb = vec3<u32>(round(clamp(s.color.rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * 1023.0));");
                        w.line("splats[k] = vec4<u32>(bitcast<vec2<u32>>(c), packed, rgb.x | (rgb.y << 10u) | (rgb.z << 20u));");
                    });
                });
            });
            w.line("tile_counts[k] = tiles;");
            w.line("tile_offsets[k] = tiles;");
        },
    );
}
