//! Quads, every sprite the compute renderer does not draw as a disc: `project` writes each one's record
//! (the projective map from pixels back to its corner coordinates, its colour, its box), and
//! `composite` maps each pixel centre back onto the quad and shades it as the fragment shader
//! does. A quad that faces the camera is composited by an affine map where the view allows
//! ([`splat_affine_quads`]).

use super::composite::{self, emit_composite};
use super::masks;
use super::{
    emit_project_kernel, host_depth, lit_record_row, lit_record_vec4s, splat_quad_words,
    splat_slices,
};
use crate::base::writer::{f32_lit, Writer};
use crate::features::looks::orient::OrientIr;
use crate::features::looks::COLOR_MOST;
use crate::ir::EffectIr;
use crate::stages::wgsl::draw::DrawShape;

/// Whether `composite` maps a quad's pixels back to its corner coordinates affinely, without
/// a division at each pixel: a quad that faces the camera (`Camera`, `Velocity`, turned or not)
/// lies parallel to the image plane, so one w holds over all of it wherever the projection's w
/// ignores view x and y (every perspective and orthographic projection). The composite then
/// has an override constant, [`SPLAT_FLAT_VIEW`] (true unless set), and the runtime makes a
/// second pipeline with it false for projections whose w leans on view x or y, which divide
/// at each pixel. Not against a host's depth, whose test needs w at each pixel.
pub fn splat_affine_quads(ir: &EffectIr, shape: &DrawShape) -> bool {
    !matches!(ir.render.orient, OrientIr::Fixed { .. }) && !host_depth(shape)
}

/// The override constant of an affine quad composite ([`splat_affine_quads`]): true where the
/// projection's w ignores view x and y (`proj`'s first two columns have w = 0).
pub const SPLAT_FLAT_VIEW: &str = "FLAT_VIEW";

/// `project` for quads: instance k's quad as the vertex shader places it (the same half axes,
/// the same projection), as a 64-byte record: the inverse of the map from corner coordinates
/// (u, v, 1) to homogeneous pixels counted from the quad's pixel box (small numbers: f32 keeps
/// about a ten-thousandth of a pixel), its colour and frame, the box itself; and its tile
/// count. A quad with a corner behind the camera or outside the depth range is not drawn (the
/// rasteriser would clip it to the part inside). For a host's image (`host`) the record also
/// holds the clip-space depth terms a pixel's depth is found from (a vec4 before the last).
pub(crate) fn emit_project_quads(w: &mut Writer, ir: &EffectIr, host: bool) {
    let lit = lit_record_vec4s(ir);
    let vec4s = splat_quad_words(ir, host) / 4;
    let (half_x, half_y) = if ir.render.turns_quad() {
        ("s.half_x", "s.half_y")
    } else {
        (
            "vec3<f32>(0.5 * s.size, 0.0, 0.0)",
            "vec3<f32>(0.0, 0.5 * s.size, 0.0)",
        )
    };
    let frame = if ir.render.texture.is_some() {
        "s.frame"
    } else {
        "0u"
    };
    // Quads: additive light gets lists without a sort ([`splat_additive_lists`]).
    let sorted = !super::splat_additive_lists(ir);
    emit_project_kernel(w, sorted, &|w: &mut Writer| {
        w.line("let s = sprite_at(k);");
        w.block("if (s.visible)", |w| {
                w.line("let size = vec2<f32>(f32(splat_view.width), f32(splat_view.height));");
                w.line("let c0 = draw.proj * s.center;");
                w.line(format!("let ax = draw.proj * vec4<f32>({half_x}, 0.0);"));
                w.line(format!("let ay = draw.proj * vec4<f32>({half_y}, 0.0);"));
                w.line("var inside = true;");
                w.line("var lo = vec2<f32>(3.0e38);");
                w.line("var hi = vec2<f32>(-3.0e38);");
                w.block("for (var i = 0u; i < 4u; i++)", |w| {
                    w.line("let corner = vec2<f32>(f32(i & 1u), f32(i >> 1u)) * 2.0 - 1.0;");
                    w.line("let q = c0 + corner.x * ax + corner.y * ay;");
                    w.line("inside = inside && unclipped(q);");
                    w.line("let p = clip_pixel(q, size);");
                    w.line("lo = min(lo, p);");
                    w.line("hi = max(hi, p);");
                });
                w.comment("Pixels whose centres (i + 0.5) the quad's bounding box holds.");
                w.line("let first = first_pixel(lo);");
                w.line("let last = last_pixel(hi, size);");
                w.block("if (inside && all(first <= last))", |w| {
                    w.comment("Columns of the map (u, v, 1) -> (x w, y w, w), pixels counted from the box's first one.");
                    w.line("let cx = to_pixels(ax, first, size);");
                    w.line("let cy = to_pixels(ay, first, size);");
                    w.line("let cc = to_pixels(c0, first, size);");
                    w.comment("Its inverse maps pixels back to corner coordinates.");
                    w.line("let det = dot(cx, cross(cy, cc));");
                    w.comment("Edge-on (no area in the image): nothing to draw.");
                    w.block("if (abs(det) > 1e-30)", |w| {
                        w.line("let rows = inverse_rows(cx, cy, cc, det);");
                        w.line("tiles = box_tiles(k, first, last);");
                        w.comment("Colour up to COLOR_MOST (HDR light; an 8-bit composite clamps to 1), alpha to 1.");
                        let most = f32_lit(COLOR_MOST);
                        w.line(format!("let color = clamp(s.color, vec4<f32>(0.0), vec4<f32>({most}, {most}, {most}, 1.0));"));
                        w.line("let box = pack_box(first, last);");
                        w.line(format!("splats[{vec4s}u * k] = bitcast<vec4<u32>>(vec4<f32>(rows[0], color.r));"));
                        w.line(format!("splats[{vec4s}u * k + 1u] = bitcast<vec4<u32>>(vec4<f32>(rows[1], color.g));"));
                        w.line(format!("splats[{vec4s}u * k + 2u] = bitcast<vec4<u32>>(vec4<f32>(rows[2], color.b));"));
                        if host {
                            w.comment("Clip z at corner coordinates (u, v) is c0.z + u ax.z + v ay.z.");
                            w.line(format!("splats[{vec4s}u * k + 3u] = bitcast<vec4<u32>>(vec4<f32>(c0.z, ax.z, ay.z, 0.0));"));
                        }
                        let row = lit_record_row(host);
                        match lit {
                            0 => {}
                            1 => {
                                w.comment("The centre and half size in view space (the basis is the view's): the lit look's normal and light at each pixel.");
                                w.line(format!("splats[{vec4s}u * k + {row}u] = bitcast<vec4<u32>>(vec4<f32>(s.center.xyz, 0.5 * s.size));"));
                            }
                            _ => {
                                w.comment("The basis, centre and half sizes in view space: the lit look's normal and light at each pixel.");
                                w.line(format!("let basis = sprite_basis({half_x}, {half_y}, s.center.xyz);"));
                                w.line(format!("splats[{vec4s}u * k + {row}u] = bitcast<vec4<u32>>(vec4<f32>(basis[0], s.center.x));"));
                                w.line(format!("splats[{vec4s}u * k + {}u] = bitcast<vec4<u32>>(vec4<f32>(basis[1], s.center.y));", row + 1));
                                w.line(format!("splats[{vec4s}u * k + {}u] = bitcast<vec4<u32>>(vec4<f32>(basis[2], s.center.z));", row + 2));
                                w.line(format!("splats[{vec4s}u * k + {}u] = bitcast<vec4<u32>>(vec4<f32>(length({half_x}), length({half_y}), 0.0, 0.0));", row + 3));
                            }
                        }
                        w.line(format!("splats[{vec4s}u * k + {}u] = vec4<u32>(bitcast<u32>(color.a), {frame}, box);", vec4s - 1));
                    });
                });
            });
    });
}

/// `composite` for quads: [`emit_composite`] with each pixel centre mapped back to the quad's
/// corner coordinates and shaded by `splat_shade` (the fragment shader's disc, or its texel
/// with derivatives from the quad's map); for a host's image, tested and faded against its
/// depth at the pixel.
pub(crate) fn emit_quad_raster(w: &mut Writer, ir: &EffectIr, shape: &DrawShape) {
    match &ir.render.texture {
        Some(t) => t.emit_splat_shade(w),
        None => {
            w.comment(
                "The soft round sprite at corner coordinates uv (the fragment shader's disc).",
            );
            w.block(
                "fn splat_shade(uv: vec2<f32>, du: vec2<f32>, dv: vec2<f32>, color: vec4<f32>, frame: u32) -> vec4<f32>",
                |w| {
                    w.line("let r2 = dot(uv, uv);");
                    w.block("if (r2 >= 1.0)", |w| w.line("return vec4<f32>(0.0);"));
                    w.line("let falloff = (1.0 - r2) * (1.0 - r2);");
                    w.line("return vec4<f32>(color.rgb, color.a * falloff);");
                },
            );
        }
    }
    w.blank();
    let lit = lit_record_vec4s(ir);
    let maps = ir.render.lit.as_ref().map_or("", |l| l.splat_maps_wgsl());
    let per_particle_shadow = ir
        .render
        .lit
        .as_ref()
        .is_some_and(|l| l.shadow_per_particle());
    if lit > 0 {
        emit_lit_record(w, lit, per_particle_shadow);
        w.blank();
    }
    let additive = ir.render.blend == crate::stages::schema::Blend::Additive;
    let vec4s = (splat_quad_words(ir, shape.host.is_some()) / 4) as u32;
    let depth = host_depth(shape);
    let stride = composite::batch_stride(vec4s, additive);
    let affine = splat_affine_quads(ir, shape);
    if affine {
        w.comment(
            "Whether the projection's w ignores view x and y: set per pipeline by the runtime.",
        );
        w.line(format!("override {SPLAT_FLAT_VIEW}: bool = true;"));
        w.blank();
    }
    let load = |w: &mut Writer| {
        w.comment("The map's rows moved from the record's box corner to the tile's origin (their constant terms absorb the shift) and packed ahead of the colour: (a.xyz, b.x), (b.yz, c.xy), (c.z, rgb), so that a pixel tests the record on nine words, without the corner.");
        w.line(format!("let last = splats[{vec4s}u * k + {}u];", vec4s - 1));
        w.line("let shift = vec2<f32>(vec2<i32>(unpack_corner(last.z)) - vec2<i32>(origin));");
        w.line(format!("let a = bitcast<vec4<f32>>(splats[{vec4s}u * k]);"));
        w.line(format!(
            "let b = bitcast<vec4<f32>>(splats[{vec4s}u * k + 1u]);"
        ));
        w.line(format!(
            "let c = bitcast<vec4<f32>>(splats[{vec4s}u * k + 2u]);"
        ));
        w.line("let az = a.z - dot(a.xy, shift);");
        w.line("let bz = b.z - dot(b.xy, shift);");
        w.line("let cz = c.z - dot(c.xy, shift);");
        if additive {
            masks::emit_diagonal_spans(
                w,
                [
                    "vec3<f32>(a.xy, az)",
                    "vec3<f32>(b.xy, bz)",
                    "vec3<f32>(c.xy, cz)",
                ],
                &[
                    "vec3<f32>(-1.0, -1.0, 1.0)",
                    "vec3<f32>(1.0, -1.0, 1.0)",
                    "vec3<f32>(1.0, 1.0, 1.0)",
                    "vec3<f32>(-1.0, 1.0, 1.0)",
                ],
            );
        }
        let projective = |w: &mut Writer| {
            w.line(format!(
                "batch[{stride}u * t] = bitcast<vec4<u32>>(vec4<f32>(a.xy, az, b.x));"
            ));
            w.line(format!(
                "batch[{stride}u * t + 1u] = bitcast<vec4<u32>>(vec4<f32>(b.y, bz, c.xy));"
            ));
            w.line(format!(
                "batch[{stride}u * t + 2u] = bitcast<vec4<u32>>(vec4<f32>(cz, a.w, b.w, c.w));"
            ));
        };
        if affine {
            w.comment("Where the projection's w ignores view x and y (FLAT_VIEW), one w holds over this quad, which lies parallel to the image plane: the rows of u and v are divided by s = 1 / w once here (at the tile's centre), not at each pixel, and packed (u, v.x), (v.yz, r, g), (b, alpha), so that a pixel tests the record on six words and shades it on four more.");
            w.block("if (FLAT_VIEW)", |w| {
                w.line("let sc = dot(vec3<f32>(c.xy, cz), vec3<f32>(8.0, 8.0, 1.0));");
                w.comment("A drawn quad lies in front of the camera (s > 0); were it not, u = 2 at every pixel would cover none.");
                w.line("let inv = select(0.0, 1.0 / sc, sc > 0.0);");
                w.line("let u_row = select(vec3<f32>(0.0, 0.0, 2.0), vec3<f32>(a.xy, az) * inv, sc > 0.0);");
                w.line("let v_row = vec3<f32>(b.xy, bz) * inv;");
                w.line(format!(
                    "batch[{stride}u * t] = bitcast<vec4<u32>>(vec4<f32>(u_row, v_row.x));"
                ));
                w.line(format!(
                    "batch[{stride}u * t + 1u] = bitcast<vec4<u32>>(vec4<f32>(v_row.yz, a.w, b.w));"
                ));
                w.line(format!(
                    "batch[{stride}u * t + 2u] = vec4<u32>(bitcast<u32>(c.w), last.x, 0u, 0u);"
                ));
            });
            w.block("else", projective);
        } else {
            projective(w);
        }
        for r in 3..vec4s {
            // The box's vec4 last in the batch's record, past the padding.
            let at = if r + 1 == vec4s { stride - 1 } else { r };
            w.line(format!(
                "batch[{stride}u * t + {at}u] = splats[{vec4s}u * k + {r}u];"
            ));
        }
        if per_particle_shadow {
            let row = lit_record_row(shape.host.is_some());
            let place = |r: u32| format!("bitcast<vec4<f32>>(batch[{stride}u * t + {}u])", row + r);
            let centre = match lit {
                1 => format!("{}.xyz", place(0)),
                _ => format!("vec3<f32>({}.w, {}.w, {}.w)", place(0), place(1), place(2)),
            };
            w.comment("shadow_at: Particle: the shadowed light's verdict at the quad's centre, looked up once as its record is loaded.");
            w.line(format!("batch_shadow[t] = shadow_visibility({centre});"));
        }
    };
    let evaluate = |w: &mut Writer| {
        if affine {
            evaluate_affine(
                w,
                stride,
                &lit_shade(lit, maps, shape.host.is_some(), stride, per_particle_shadow),
            );
            return;
        }
        w.line(format!(
            "let q0 = bitcast<vec4<f32>>(batch[{stride}u * j]);"
        ));
        w.line(format!(
            "let q1 = bitcast<vec4<f32>>(batch[{stride}u * j + 1u]);"
        ));
        w.line(format!(
            "let q2x = bitcast<f32>(batch[{stride}u * j + 2u].x);"
        ));
        w.comment("The map's rows, unpacked.");
        w.line("let r0 = q0.xyz;");
        w.line("let r1 = vec3<f32>(q0.w, q1.xy);");
        w.line("let r2 = vec3<f32>(q1.zw, q2x);");
        w.comment("The pixel centre from the tile's origin (the rows' frame, as loaded).");
        w.line("let p = vec3<f32>(centre - vec2<f32>(origin), 1.0);");
        w.comment("s = 1 / w: positive in front of the camera.");
        w.line("let s = dot(r2, p);");
        w.block("if (s <= 0.0)", |w| w.line("continue;"));
        w.line("let uv = vec2<f32>(dot(r0, p), dot(r1, p)) / s;");
        w.block("if (any(abs(uv) >= vec2<f32>(1.0)))", |w| {
            w.line("continue;")
        });
        if depth {
            w.comment("NDC depth at the pixel: clip z at uv over w (times s = 1 / w).");
            w.line(format!(
                "let rz = bitcast<vec4<f32>>(batch[{stride}u * j + 3u]);"
            ));
            w.line("let fade = host_fade(centre, dot(rz.xyz, vec3<f32>(1.0, uv)) * s);");
            w.block("if (fade <= 0.0)", |w| w.line("continue;"));
        }
        w.comment("The rest of the record, for the pixels it covers.");
        w.line(format!(
            "let rgb = bitcast<vec4<f32>>(batch[{stride}u * j + 2u]).yzw;"
        ));
        w.line(format!("let r3 = batch[{stride}u * j + {}u];", stride - 1));
        w.comment("uv's derivatives along the image's x and y (the quotient rule).");
        w.line("let du = (vec2<f32>(r0.x, r1.x) - uv * r2.x) / s;");
        w.line("let dv = (vec2<f32>(r0.y, r1.y) - uv * r2.y) / s;");
        w.line("let color = vec4<f32>(rgb, bitcast<f32>(r3.x));");
        let shade = lit_shade(lit, maps, shape.host.is_some(), stride, per_particle_shadow);
        if depth {
            w.line(format!("let unfaded = {shade};"));
            w.line("let shaded = vec4<f32>(unfaded.rgb, unfaded.a * fade);");
        } else {
            w.line(format!("let shaded = {shade};"));
        }
    };
    // A turned lit quad's four more vec4s fit WebGPU's 16 KiB of workgroup memory in
    // batches of 64.
    let batch = if additive || lit > 1 {
        composite::SPLAT_ADDITIVE_QUAD_BATCH
    } else {
        composite::SPLAT_BATCH
    };
    if per_particle_shadow {
        w.comment("Each record's shadow verdict at its centre, beside its record in the batch (shadow_at: Particle).");
        w.line(format!("var<workgroup> batch_shadow: array<f32, {batch}>;"));
        w.blank();
    }
    emit_composite(
        w,
        shape,
        additive,
        splat_slices(ir),
        composite::RecordBatch {
            vec4s: stride,
            size: batch,
            diagonals: additive,
            prefetch: composite::Prefetch::None,
        },
        &load,
        &evaluate,
    );
}

/// The composite's step for record j of a batch of camera-facing quads ([`splat_affine_quads`],
/// never against a host's depth), as the load packed it: in a flat view (FLAT_VIEW) u and v
/// are affine in the pixel and the colour follows the map; else the projective map of the
/// other quads, divided at each pixel.
fn evaluate_affine(w: &mut Writer, stride: u32, shade: &str) {
    w.line(format!(
        "let q0 = bitcast<vec4<f32>>(batch[{stride}u * j]);"
    ));
    w.line(format!(
        "let q1 = bitcast<vec4<f32>>(batch[{stride}u * j + 1u]);"
    ));
    w.comment("The pixel centre from the tile's origin (the rows' frame, as loaded).");
    w.line("let p = vec3<f32>(centre - vec2<f32>(origin), 1.0);");
    w.comment("The rows of u and v: (q0.xyz) and (q0.w, q1.xy), both layouts alike.");
    w.line("var uv = vec2<f32>(dot(q0.xyz, p), dot(vec3<f32>(q0.w, q1.xy), p));");
    w.comment("s = 1 / w: positive in front of the camera; in a flat view the rows were divided by it as the batch was loaded.");
    w.line("var s = 1.0;");
    w.line("var r2 = vec3<f32>(0.0);");
    w.block("if (!FLAT_VIEW)", |w| {
        w.line(format!(
            "r2 = vec3<f32>(q1.zw, bitcast<f32>(batch[{stride}u * j + 2u].x));"
        ));
        w.line("s = dot(r2, p);");
        w.block("if (s <= 0.0)", |w| w.line("continue;"));
        w.line("uv /= s;");
    });
    w.block("if (any(abs(uv) >= vec2<f32>(1.0)))", |w| {
        w.line("continue;")
    });
    w.comment("The rest of the record, for the pixels it covers.");
    w.line(format!("let q2 = batch[{stride}u * j + 2u];"));
    w.line(format!("let r3 = batch[{stride}u * j + {}u];", stride - 1));
    w.line("var color = vec4<f32>(q1.zw, bitcast<vec2<f32>>(q2.xy));");
    w.line("var du = vec2<f32>(q0.x, q0.w);");
    w.line("var dv = vec2<f32>(q0.y, q1.x);");
    w.block("if (!FLAT_VIEW)", |w| {
        w.line("color = vec4<f32>(bitcast<vec3<f32>>(q2.yzw), bitcast<f32>(r3.x));");
        w.comment("uv's derivatives along the image's x and y: the quotient rule (in a flat view, the map's columns).");
        w.line("du = (du - uv * r2.x) / s;");
        w.line("dv = (dv - uv * r2.y) / s;");
    });
    w.line(format!("let shaded = {shade};"));
}

/// The composite's shading of record j at corner coordinates uv: `splat_shade`'s colour, and
/// for a lit look (`lit` vec4s of place, [`lit_record_vec4s`]) that colour lit as the fragment
/// shader lights it, from the place the record keeps ([`lit_record_row`]) and the look's map
/// texels there (`maps`, WGSL); `shadow`: the record's own shadow verdict, which its load
/// kept in `batch_shadow` (`shadow_at: Particle`).
fn lit_shade(lit: u32, maps: &str, host: bool, stride: u32, shadow: bool) -> String {
    let unlit = "splat_shade(uv, du, dv, color, r3.y)";
    if lit == 0 {
        return unlit.to_string();
    }
    let row = lit_record_row(host);
    let at = |r: u32| format!("bitcast<vec4<f32>>(batch[{stride}u * j + {r}u])");
    let mut place: Vec<String> = (row..row + lit).map(at).collect();
    if shadow {
        place.insert(0, "batch_shadow[j]".into());
    }
    format!("lit_record({unlit}, uv, {maps}, {})", place.join(", "))
}

/// `lit_record(c, uv, maps, ...)`: colour `c` at corner coordinates uv of a lit quad, lit
/// there as the fragment shader lights it (`maps`: the look's map texels there), from the
/// place its record keeps: for `lit` = 1 its centre and half size `q` (upright, facing the
/// camera: the view's basis), else (unit x axis, centre x) in `a`, (unit y axis, centre y) in
/// `b`, (facing, centre z) in `f` and its half sizes in `h.xy`. With `shadow` (`shadow_at:
/// Particle`) the quad's shadow verdict comes first, as `shadow`.
pub(crate) fn emit_lit_record(w: &mut Writer, lit: u32, shadow: bool) {
    let (shadow_arg, take_shadow) = match shadow {
        true => ("shadow: f32, ", "particle_shadow = shadow;"),
        false => ("", ""),
    };
    if lit == 1 {
        w.comment("An upright lit quad's colour at corner coordinates uv, from its record's centre and half size (view space).");
        w.block(
            format!("fn lit_record(c: vec4<f32>, uv: vec2<f32>, maps: mat2x4<f32>, {shadow_arg}q: vec4<f32>) -> vec4<f32>"),
            |w| {
                if shadow {
                    w.line(take_shadow);
                }
                w.line("let p = q.xyz + vec3<f32>(uv * q.w, 0.0);");
                w.line("return lit_color(c, lit_light(uv, VIEW_BASIS, maps, p));");
            },
        );
        return;
    }
    w.comment("A lit quad's colour at corner coordinates uv, from its record's basis, centre and half sizes (view space).");
    w.block(
        format!("fn lit_record(c: vec4<f32>, uv: vec2<f32>, maps: mat2x4<f32>, {shadow_arg}a: vec4<f32>, b: vec4<f32>, f: vec4<f32>, h: vec4<f32>) -> vec4<f32>"),
        |w| {
            if shadow {
                w.line(take_shadow);
            }
            w.line("let p = vec3<f32>(a.w, b.w, f.w) + (uv.x * h.x) * a.xyz + (uv.y * h.y) * b.xyz;");
            w.line("let basis = mat3x3<f32>(a.xyz, b.xyz, f.xyz);");
            w.line("return lit_color(c, lit_light(uv, basis, maps, p));");
        },
    );
}
