//! The compute renderer's kernels for ribbons: a record per segment of a ribbon's strip (the two
//! triangles between ribbon points s and s + 1), `project` (its tile box and count) and
//! `composite` (each pixel's perspective-correct barycentric weights in the segment's
//! triangles, shaded as `fs_trail` does).
//!
//! A segment, not a triangle, is the record: its two triangles cover nearly the same tiles, so
//! a record for each triangle put each tile entry in the list twice, and made the ribbon's
//! particle, its samples and its points again for each, a far slower frame
//! (docs/performance.md, "What bounds sparks and orbit").

use crate::base::writer::{u32_lit, Writer};
use crate::features::looks::trail::TrailIr;
use crate::ir::EffectIr;
use crate::stages::wgsl::draw::splat::{
    batch_stride, emit_composite, emit_project_kernel, host_depth, Prefetch, RecordBatch,
    SPLAT_BATCH,
};
use crate::stages::wgsl::draw::DrawShape;

/// Vec4s of a ribbon segment's record in the compute renderer's composite:
/// - three: the rows of the map from pixels to its first triangle's barycentric weights (xyz;
///   w, the triangle's vertices' clip z);
/// - one: the fourth vertex in the first triangle's weights, from which a pixel's weights in the
///   second triangle follow (1 / its first weight, or 0 when the segment draws one triangle;
///   its second and third; w, its clip z);
/// - one: the colours of the segment's two ribbon points as f16 pairs;
/// - one: whether the first triangle is the strip's second (v1, v2, v3: the segment's first
///   one draws nothing), and the pixel box's two corners (z, w).
///
/// Records are not stored: `project` and `composite` both make them from the particle state
/// (`segment_record`), as a million ribbons of 23 segments would need 2.2 GB of them.
pub(crate) const SPLAT_SEGMENT_VEC4S: u32 = 6;

/// Segments of one ribbon's strip: two triangles between each pair of neighbouring points.
pub fn segments(trail: &TrailIr) -> u32 {
    trail.points - 1
}

/// Emits `segment_record(k)`, `project` and `composite` for the ribbons of `ir` (the trail
/// module's `ribbon_of`, `ribbon_point` and the compute renderer's declarations are in scope).
pub(super) fn emit(w: &mut Writer, ir: &EffectIr, trail: &TrailIr, shape: &DrawShape) {
    w.line(format!(
        "const SEGMENTS: u32 = {};",
        u32_lit(segments(trail))
    ));
    w.blank();
    w.block("struct SegmentRecord", |w| {
        w.line("valid: bool,");
        w.line("first: vec2<f32>,");
        w.line("last: vec2<f32>,");
        w.line(format!("words: array<vec4<u32>, {SPLAT_SEGMENT_VEC4S}>,"));
    });
    w.blank();
    emit_segment_loads(w);
    w.blank();
    emit_segment_record(w, false);
    if ir.render.lit.is_some() {
        w.blank();
        emit_segment_record(w, true);
    }
    w.blank();
    // Additive segments get lists without a sort ([`crate::stages::wgsl::draw::splat_additive_lists`]).
    let sorted = !crate::stages::wgsl::draw::splat_additive_lists(ir);
    emit_project_kernel(w, sorted, &|w: &mut Writer| {
        w.line("let rec = segment_record(k);");
        w.block("if (rec.valid)", |w| {
            w.line("tiles = box_tiles(k, rec.first, rec.last);");
        });
    });
    w.blank();
    emit_segment_composite(w, ir, shape);
}

/// `segment_record(k)`: segment k (instance k / SEGMENTS, ribbon points s and s + 1) as a
/// record. Its vertices are the vertex shader's: v0 and v1 at point s (sides -1 and +1), v2
/// and v3 at point s + 1, drawn as the strip's triangles (v0, v1, v2) and (v1, v2, v3). A
/// triangle with a vertex outside the depth range, or without area, draws nothing, as the
/// triangle-by-triangle splat had it.
fn emit_segment_loads(w: &mut Writer) {
    w.comment("Every load segment k's record needs: the particle and the ring entries, whose places follow from the slot and the step alone (a slot past the capacity, the order's padding, loads slot CAPACITY - 1's, which the record does not use).");
    w.block("struct SegmentLoads", |w| {
        w.line("p: Particle,");
        w.line("oldest: vec4<u32>,");
        w.comment("Points s - 1 (or s at the particle), s, s + 1 and s + 2 (or s + 1 at the oldest sample): s < lo, so s + 1 needs no clamp.");
        w.line("before: vec4<u32>,");
        w.line("near: vec4<u32>,");
        w.line("far: vec4<u32>,");
        w.line("after: vec4<u32>,");
    });
    w.blank();
    w.block("fn segment_loads(k: u32) -> SegmentLoads", |w| {
        w.line("let instance = k / SEGMENTS;");
        w.line("let s = k - instance * SEGMENTS;");
        w.line("let slot = min(ribbon_slot(instance), CAPACITY - 1u);");
        w.line("let newest = newest_sample();");
        w.line("return SegmentLoads(load_particle(slot), oldest_entry(slot), sample_entry(slot, newest, max(s, 1u) - 1u), sample_entry(slot, newest, s), sample_entry(slot, newest, s + 1u), sample_entry(slot, newest, s + 2u));");
    });
    w.blank();
    w.comment("Segment k as a record; not valid when neither of its triangles draws or its box holds no pixel centre.");
    w.block("fn segment_record(k: u32) -> SegmentRecord", |w| {
        w.comment("Every load issued before any is tested. Loaded after the particle's tests, they would take three round trips to memory, not one.");
        w.line("return segment_record_from(k, segment_loads(k));");
    });
}

/// `segment_record_from(k, loads)`: segment k as a record, from its loads (`segment_loads(k)`),
/// its colours unlit; with `lit`, `lit_segment_record_from`, the same with its points lit
/// (`lit_point_color`), which only `composite` calls, so that `project`, which needs only the
/// record's box, reads no lights.
fn emit_segment_record(w: &mut Writer, lit: bool) {
    let name = match lit {
        true => "lit_segment_record_from",
        false => "segment_record_from",
    };
    w.comment("Segment k as a record, from its loads (`segment_loads(k)`).");
    w.block(format!("fn {name}(k: u32, loads: SegmentLoads) -> SegmentRecord"), |w| {
        w.line("var rec: SegmentRecord;");
        w.line("rec.valid = false;");
        w.line("let instance = k / SEGMENTS;");
        w.line("let s = k - instance * SEGMENTS;");
        w.line("let slot = ribbon_slot(instance);");
        w.block("if (slot >= CAPACITY)", |w| w.line("return rec;"));
        w.line("let p = loads.p;");
        w.line("let e_before = loads.before;");
        w.line("let e_near = loads.near;");
        w.line("let e_far = loads.far;");
        w.line("let e_after = loads.after;");
        w.line("let r = ribbon_from(slot, p, loads.oldest);");
        w.comment("Past the points the particle has lived every vertex sits on its oldest sample: no area.");
        w.block("if (!r.visible || s >= r.lo)", |w| w.line("return rec;"));
        w.line("let before = sampled_point(r.x, max(s, 1u) - 1u, e_before);");
        w.line("let at_near = sampled_point(r.x, s, e_near);");
        w.line("let at_far = sampled_point(r.x, s + 1u, e_far);");
        w.line("let after = select(at_far, sampled_point(r.x, s + 2u, e_after), s + 2u <= r.lo);");
        w.line("let near = ribbon_point_between(r, s, at_near, before, at_far);");
        w.line("let far = ribbon_point_between(r, s + 1u, at_far, at_near, after);");
        w.comment("As trail_vertex places them: centre + sign * offset.");
        w.line("let v0 = draw.proj * vec4<f32>(near.center.xyz + -1.0 * near.offset, 1.0);");
        w.line("let v1 = draw.proj * vec4<f32>(near.center.xyz + 1.0 * near.offset, 1.0);");
        w.line("let v2 = draw.proj * vec4<f32>(far.center.xyz + -1.0 * far.offset, 1.0);");
        w.line("let v3 = draw.proj * vec4<f32>(far.center.xyz + 1.0 * far.offset, 1.0);");
        w.comment("A hidden vertex lies outside the depth range: the triangles with it draw nothing.");
        w.line("let shared_in = unclipped(v1) && unclipped(v2);");
        w.line("let in0 = shared_in && unclipped(v0);");
        w.line("let in1 = shared_in && unclipped(v3);");
        w.block("if (!in0 && !in1)", |w| w.line("return rec;"));
        w.line("let size = vec2<f32>(f32(splat_view.width), f32(splat_view.height));");
        w.line("let p0 = clip_pixel(v0, size);");
        w.line("let p1 = clip_pixel(v1, size);");
        w.line("let p2 = clip_pixel(v2, size);");
        w.line("let p3 = clip_pixel(v3, size);");
        w.comment("The box of the triangles that may draw.");
        w.line("var lo = min(p1, p2);");
        w.line("var hi = max(p1, p2);");
        w.block("if (in0)", |w| {
            w.line("lo = min(lo, p0);");
            w.line("hi = max(hi, p0);");
        });
        w.block("if (in1)", |w| {
            w.line("lo = min(lo, p3);");
            w.line("hi = max(hi, p3);");
        });
        w.line("rec.first = first_pixel(lo);");
        w.line("rec.last = last_pixel(hi, size);");
        w.block("if (any(rec.first > rec.last))", |w| w.line("return rec;"));
        w.line("let a = to_pixels(v0, rec.first, size);");
        w.line("let b = to_pixels(v1, rec.first, size);");
        w.line("let c = to_pixels(v2, rec.first, size);");
        w.line("let d = to_pixels(v3, rec.first, size);");
        w.line("let det0 = dot(a, cross(b, c));");
        w.line("let det1 = dot(b, cross(c, d));");
        w.line("let t0 = in0 && abs(det0) > 1e-30;");
        w.line("let t1 = in1 && abs(det1) > 1e-30;");
        w.block("if (!t0 && !t1)", |w| w.line("return rec;"));
        w.line("rec.valid = true;");
        w.line("let box = pack_box(rec.first, rec.last);");
        w.comment("Clip z of the vertices (a pixel's NDC depth is the weights' dot product with them).");
        w.line("let z = vec4<f32>(v0.z, v1.z, v2.z, v3.z);");
        w.line("var fourth = vec4<f32>(0.0, 0.0, 0.0, z.w);");
        w.line("var second = 0u;");
        w.line("var rows: mat3x3<f32>;");
        w.line("var zs = z.xyz;");
        w.block("if (t0)", |w| {
            w.line("rows = inverse_rows(a, b, c, det0);");
            w.comment("v3 = alpha v0 + beta v1 + gamma v2 (homogeneous pixels): a pixel's weights l in (v0, v1, v2) are (l.x / alpha) on v3, l.y - beta l.x / alpha on v1, l.z - gamma l.x / alpha on v2.");
            w.line("let alpha = dot(rows[0], d);");
            w.block("if (t1 && alpha != 0.0)", |w| {
                w.line("fourth = vec4<f32>(1.0 / alpha, dot(rows[1], d), dot(rows[2], d), z.w);");
            });
        });
        w.block("else", |w| {
            w.line("rows = inverse_rows(b, c, d, det1);");
            w.line("zs = z.yzw;");
            w.line("second = 1u;");
        });
        w.line("rec.words[0] = vec4<u32>(bitcast<vec3<u32>>(rows[0]), bitcast<u32>(zs.x));");
        w.line("rec.words[1] = vec4<u32>(bitcast<vec3<u32>>(rows[1]), bitcast<u32>(zs.y));");
        w.line("rec.words[2] = vec4<u32>(bitcast<vec3<u32>>(rows[2]), bitcast<u32>(zs.z));");
        w.line("rec.words[3] = bitcast<vec4<u32>>(fourth);");
        match lit {
            true => {
                w.line("let c_near = min(lit_point_color(r, near), vec4<f32>(65504.0));");
                w.line("let c_far = min(lit_point_color(r, far), vec4<f32>(65504.0));");
            }
            false => {
                w.line("let c_near = min(near.color, vec4<f32>(65504.0));");
                w.line("let c_far = min(far.color, vec4<f32>(65504.0));");
            }
        }
        w.line("rec.words[4] = vec4<u32>(pack2x16float(c_near.rg), pack2x16float(c_near.ba), pack2x16float(c_far.rg), pack2x16float(c_far.ba));");
        w.line("rec.words[5] = vec4<u32>(second, 0u, box);");
        w.line("return rec;");
    });
}

/// `composite` for ribbon segments: [`emit_composite`] with each record made again from the
/// particle state, and each pixel given its weights in the segment's first triangle, or if it
/// lies outside it, in its second (from the first's weights and the fourth vertex's).
fn emit_segment_composite(w: &mut Writer, ir: &EffectIr, shape: &DrawShape) {
    let n = SPLAT_SEGMENT_VEC4S;
    let additive = ir.render.blend == crate::stages::schema::Blend::Additive;
    let stride = batch_stride(n, additive);
    let load = |w: &mut Writer| {
        w.comment("Made again from the particle state (loaded while the batch before was composited): the same record `project` made, its weights' rows moved from the box corner to the tile's origin (their constant terms absorb the shift; the fourth vertex's weights do not change).");
        match ir.render.lit {
            Some(_) => w.line("let rec = lit_segment_record_from(k, loads);"),
            None => w.line("let rec = segment_record_from(k, loads);"),
        }
        w.line(format!(
            "let shift = vec2<f32>(vec2<i32>(unpack_corner(rec.words[{}u].z)) - vec2<i32>(origin));",
            n - 1
        ));
        // Unrolled here, not in WGSL: `rec.words` indexed by a loop counter went to local memory.
        for r in 0..3 {
            w.line(format!(
                "let row{r} = bitcast<vec3<f32>>(rec.words[{r}u].xyz);"
            ));
            w.line(format!(
                "batch[{stride}u * t + {r}u] = vec4<u32>(bitcast<vec3<u32>>(vec3<f32>(row{r}.xy, row{r}.z - dot(row{r}.xy, shift))), rec.words[{r}u].w);"
            ));
        }
        for r in 3..n {
            // The box's vec4 last in the batch's record, past the padding.
            let at = if r + 1 == n { stride - 1 } else { r };
            w.line(format!("batch[{stride}u * t + {at}u] = rec.words[{r}u];"));
        }
    };
    let depth = host_depth(shape);
    let evaluate = |w: &mut Writer| {
        w.line(format!(
            "let r0 = bitcast<vec4<f32>>(batch[{stride}u * j]);"
        ));
        w.line(format!(
            "let r1 = bitcast<vec4<f32>>(batch[{stride}u * j + 1u]);"
        ));
        w.line(format!(
            "let r2 = bitcast<vec4<f32>>(batch[{stride}u * j + 2u]);"
        ));
        w.comment("The pixel centre from the tile's origin (the rows' frame, as loaded).");
        w.line("let p = vec3<f32>(centre - vec2<f32>(origin), 1.0);");
        w.line("var weighed = vec3<f32>(dot(r0.xyz, p), dot(r1.xyz, p), dot(r2.xyz, p));");
        w.comment("The weights over 1 / w: their sum is positive in front of the camera.");
        w.line("var sum = weighed.x + weighed.y + weighed.z;");
        w.line("var b = vec3<f32>(0.0);");
        w.line("var inside = sum > 0.0;");
        w.block("if (inside)", |w| {
            w.line("b = weighed / sum;");
            w.comment("The edge shared with the strip's next triangle (opposite the first vertex) is that one's.");
            w.line("inside = b.x > 0.0 && b.y >= 0.0 && b.z >= 0.0;");
        });
        w.line(format!(
            "var second = batch[{stride}u * j + {}u].x == 1u;",
            stride - 1
        ));
        if depth {
            w.line("var zs = vec3<f32>(r0.w, r1.w, r2.w);");
        }
        w.block("if (!inside)", |w| {
            w.comment("The segment's second triangle (v1, v2, v3), if the first is (v0, v1, v2) and it has one.");
            w.line(format!("let r3 = bitcast<vec4<f32>>(batch[{stride}u * j + 3u]);"));
            w.block("if (second || r3.x == 0.0)", |w| w.line("continue;"));
            w.line("let on_fourth = weighed.x * r3.x;");
            w.line("weighed = vec3<f32>(weighed.y - r3.y * on_fourth, weighed.z - r3.z * on_fourth, on_fourth);");
            w.line("sum = weighed.x + weighed.y + weighed.z;");
            w.block("if (sum <= 0.0)", |w| w.line("continue;"));
            w.line("b = weighed / sum;");
            w.block("if (b.x <= 0.0 || b.y < 0.0 || b.z < 0.0)", |w| {
                w.line("continue;")
            });
            w.line("second = true;");
            if depth {
                w.line("zs = vec3<f32>(r1.w, r2.w, r3.w);");
            }
        });
        if depth {
            w.comment("NDC depth: the weights (screen-space barycentrics over w) times the vertices' clip z.");
            w.line("let fade = host_fade(centre, dot(weighed, zs));");
            w.block("if (fade <= 0.0)", |w| w.line("continue;"));
        }
        w.comment(
            "The rest of the record, for the pixels it covers: the near and far points' colours.",
        );
        w.line(format!("let cw = batch[{stride}u * j + 4u];"));
        w.line("let c_near = vec4<f32>(unpack2x16float(cw.x), unpack2x16float(cw.y));");
        w.line("let c_far = vec4<f32>(unpack2x16float(cw.z), unpack2x16float(cw.w));");
        w.comment("(v0, v1, v2) are near, near, far; (v1, v2, v3) near, far, far.");
        w.line("let color = select(b.x + b.y, b.x, second) * c_near + select(b.z, b.y + b.z, second) * c_far;");
        w.comment("The sides alternate (-, +, - or +, -, +): the same square either way.");
        w.line("let across = b.x - b.y + b.z;");
        w.comment("fs_trail: soft across the strip.");
        let fade = if depth { " * fade" } else { "" };
        w.line(format!(
            "let shaded = vec4<f32>(color.rgb, color.a * (1.0 - across * across){fade});"
        ));
    };
    emit_composite(
        w,
        shape,
        additive,
        crate::stages::wgsl::draw::splat_slices(ir),
        RecordBatch {
            vec4s: stride,
            size: SPLAT_BATCH,
            diagonals: false,
            prefetch: Prefetch::Loads {
                declare: "var loads: SegmentLoads;",
                issue: "loads = segment_loads(next_k);",
            },
        },
        &load,
        &evaluate,
    );
}
