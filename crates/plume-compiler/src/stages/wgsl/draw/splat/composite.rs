//! The compute renderer's composite kernels, the same for every record kind (quads, ribbon segments):
//! `composite`, a workgroup per tile blending its list front to back, and `merge`, which
//! composes the slices of a tile's list. The record kind supplies the code that loads a record
//! and evaluates it at a pixel.

use super::masks::{
    emit_box_lines, emit_line_masks, emit_line_masks_transposed, emit_transpose, line_words,
    TILE_DIAGONALS,
};
use super::{DrawShape, SPLAT_TILE};
use crate::base::writer::Writer;

/// Records a composite workgroup bins at once: 128 records (8 KiB of alpha quads, 14 KiB of
/// additive ribbon segments, [`batch_stride`]) and a 4-word mask per column and row of the
/// tile (512 bytes) stay within WebGPU's 16 KiB of workgroup memory.
pub(crate) const SPLAT_BATCH: u32 = 128;

/// Records a composite workgroup bins at once for additive quads: half a batch. A pixel then
/// walks a batch's masks in two words, not four, and a workgroup spends less of its time with
/// most of its threads waiting at a barrier for a slow mask or load. Alpha records and ribbon
/// segments keep 128: half a batch slowed them (docs/performance.md, "What bounds sparks and
/// orbit"; benchmarks/h100-splat/line-masks/8-batch-64-96/).
pub(crate) const SPLAT_ADDITIVE_QUAD_BATCH: u32 = 64;

/// Workgroups a tile's list of additive light is split over ([`splat_slices`]).
pub const SPLAT_SLICES: u32 = 8;

/// Workgroups each tile's list is split over: each composites a contiguous slice of it front
/// to back into partial sums (light gathered, light let through), and `merge` composes the
/// slices front to back per pixel. Additive light gets [`SPLAT_SLICES`]: it seldom stops early,
/// and a busy tile then keeps eight workgroups busy instead of one. Alpha gets one: a slice
/// behind cannot know that the slices in front already hide it, so slicing did the work early
/// stopping saves (docs/performance.md, "What bounds sparks and orbit";
/// benchmarks/h100-splat/slices-8-everywhere.jsonl).
pub fn splat_slices(ir: &crate::ir::EffectIr) -> u32 {
    match ir.render.blend {
        crate::stages::schema::Blend::Additive => SPLAT_SLICES,
        // The compute renderer composites alpha and additive light only (`ComputeOffscreen::draws`).
        _ => 1,
    }
}

/// The pixels a subgroup of 32 composites, where subgroups are used (`shape.subgroups`): a
/// block 4 wide and 8 tall rather than two rows of 16. A subgroup walks its pixels' records
/// until its busiest lane is done, and a squarer block's pixels share more of their records,
/// so its lanes wait less on each other (docs/performance.md, "What bounds sparks and orbit",
/// also measures 8 x 4 and 2 x 16; benchmarks/h100-splat/scatter/).
const SUBGROUP_BLOCK: (u32, u32) = (4, 8);

/// Binding of the slices' partial sums: `SPLAT_SLICES` vec4s a pixel (slice-major).
pub const SPLAT_PARTIAL_BINDING: u32 = 33;

/// How a composite workgroup holds its records: vec4s from one to the next (`vec4s`), and
/// records a batch (`size`: [`SPLAT_BATCH`] or [`SPLAT_ADDITIVE_QUAD_BATCH`], a multiple of 32).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RecordBatch {
    /// Vec4s from one record to the next in workgroup memory ([`batch_stride`]), the record's
    /// box in the last of them.
    pub vec4s: u32,
    /// Records binned at once.
    pub size: u32,
    /// Whether `load` also writes the record's diagonals and anti-diagonals into
    /// `record_lines` ([`super::masks::emit_diagonal_spans`]), so that the masks hold them too.
    pub diagonals: bool,
    /// What of the next batch is loaded while this one is composited ([`Prefetch`]).
    pub(crate) prefetch: Prefetch,
}

/// What of the next batch a composite loads while it composites this one.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Prefetch {
    /// Nothing: each batch loads its entries, then makes its records. Quads' records, made
    /// from one load each, were slower with their entries loaded ahead: the loads held more
    /// registers (docs/performance.md, "What bounds sparks and orbit").
    None,
    /// Its entries and what making its records loads: `declare` (WGSL) declares the loads
    /// before the loop, `issue` (WGSL, reading the next entry `next_k`) issues them, once for
    /// the first batch and then after each batch's records are made, so that they arrive
    /// while the masks and the walk run and `load` reads them. Ribbon segments, each made from
    /// several scattered loads, gained from their entries loaded ahead and more from the
    /// segments' loads too (docs/performance.md, "The compute renderer"; benchmarks/h100-splat/runs/).
    Loads {
        declare: &'static str,
        issue: &'static str,
    },
}

/// Vec4s between the records of a composite's batch in workgroup memory, for records of
/// `vec4s`. For additive light an odd number, so that the eight threads of a quarter warp that
/// read a vec4 each from different records land on different banks (records 64 bytes apart all
/// begin on one of two banks' groups of four); the record's last vec4 (the box) goes last in
/// its stride: sparks' quads 80 bytes apart and orbit's ribbons 112 bytes apart composite
/// faster so (benchmarks/h100-splat/segments/). Alpha records keep theirs: few of them shade a
/// pixel before it is opaque, and the larger batch slowed snow's and boids' composites
/// (docs/performance.md, "What bounds sparks and orbit").
pub(crate) fn batch_stride(vec4s: u32, additive: bool) -> u32 {
    if additive {
        vec4s | 1
    } else {
        vec4s
    }
}

/// `composite`: a workgroup per 16x16 tile and slice (`slices`: [`splat_slices`]), a thread per pixel,
/// composites its slice of the tile's records
/// (`records.vec4s` vec4s each, the last one's z and w the pixel box's corners; the code `load` emits
/// puts entry `k`'s record at `batch[records.vec4s * t]`) front to back (the
/// draw order reversed), each pixel's colour `shaded` from the code `evaluate` emits (which
/// reads record j of the batch, the pixel centre `centre`, and may `continue` past a record
/// that does not cover it), into the slice's partial sums; `merge` composes the slices and
/// rounds to 8 bits once (or stores f16 pairs into an HDR image; for a host's image with each
/// pixel's coverage, see [`emit_background`]). Alpha: the light that still comes through, T, falls by (1 - a) at each record,
/// and a pixel stops once T is under half an 8-bit step (what lies behind can no longer change
/// it); additive light is summed in fixed point ([`super::light`]: exact, so the same in any
/// order, which lets the runtime build additive lists without a sort), and into an 8-bit
/// image a pixel stops once every channel is full. The tile stops
/// when all its pixels have. The raster pipeline blends back to front, into an 8-bit target
/// rounding after every blend; this is the same sum without those roundings (tests/render.rs
/// measures how far apart they land).
///
/// Batches of `records.size` records are binned first, so that a pixel visits only the records
/// whose boxes hold it: a box is the product of a column range and a row range, so a bit mask
/// per column of the tile and one per row (built from each record's lines with no atomics:
/// [`super::masks`]) give each pixel its records as the AND of its column's and its row's. The
/// masks cost the same whatever the boxes' sizes; binning each record into a mask per pixel
/// cost its box's area in workgroup atomics (docs/performance.md, "What bounds sparks and
/// orbit"). With `records.diagonals` (additive quads) the masks hold the tile's diagonals and
/// anti-diagonals too, so that a slanted streak is visited within an octagon rather than its
/// box, and fewer of a streak's pixels test it.
pub(crate) fn emit_composite(
    w: &mut Writer,
    shape: &DrawShape,
    additive: bool,
    slices: u32,
    records: RecordBatch,
    load: &dyn Fn(&mut Writer),
    evaluate: &dyn Fn(&mut Writer),
) {
    let RecordBatch {
        vec4s: record,
        size: batch,
        diagonals,
        prefetch,
    } = records;
    let hdr = shape.hdr;
    let words = batch / 32;
    // A mask of `batch` bits for each of the tile's columns and rows (and diagonals).
    let lines = 2 * SPLAT_TILE + if diagonals { 2 * TILE_DIAGONALS } else { 0 };
    let line_masks = lines * words;
    w.line(format!(
        "var<workgroup> batch: array<vec4<u32>, {}>;",
        record * batch
    ));
    w.line("var<workgroup> batch_range: vec2<u32>;");
    if diagonals {
        w.comment(format!(
            "Per record of the batch, the tile's lines it crosses, a bit each: columns | rows << {SPLAT_TILE}, then diagonals (x + y, 0 to {}), then anti-diagonals (x - y + {}).",
            TILE_DIAGONALS - 1,
            SPLAT_TILE - 1
        ));
    } else {
        w.comment(format!(
            "Per record of the batch, the tile's columns | rows << {SPLAT_TILE} its box crosses, a bit each."
        ));
    }
    w.line(format!(
        "var<workgroup> record_lines: array<u32, {}>;",
        batch * line_words(diagonals)
    ));
    w.comment(format!(
        "Per column of the tile, then per row, which of the batch's {batch} records' boxes hold it ({words} words of bits): a pixel's records are those of its column and its row."
    ));
    w.line(format!(
        "var<workgroup> line_masks: array<u32, {line_masks}>;"
    ));
    w.comment("Pixels of the tile that are finished (or outside the image).");
    w.line("var<workgroup> finished: atomic<u32>;");
    w.line(format!("const SLICES: u32 = {slices}u;"));
    w.line(format!(
        "@group(0) @binding({SPLAT_PARTIAL_BINDING}) var<storage, read_write> partials: array<vec4<f32>>;"
    ));
    w.blank();
    w.comment("A box's corner, packed as x | y << 16.");
    w.block("fn unpack_corner(b: u32) -> vec2<u32>", |w| {
        w.line("return vec2<u32>(b & 0xffffu, b >> 16u);");
    });
    w.blank();
    w.comment("Bits first to last of a word (none when first > last; both at most 31).");
    w.block("fn span_bits(first: u32, last: u32) -> u32", |w| {
        w.line("return (0xffffffffu >> (31u - last)) & (0xffffffffu << first);");
    });
    w.blank();
    if shape.subgroups {
        emit_transpose(w);
        w.blank();
        // naga allows the subgroup builtins in one-dimensional workgroups only.
        w.line(format!(
            "@compute @workgroup_size({})",
            SPLAT_TILE * SPLAT_TILE
        ));
    } else {
        w.line(format!(
            "@compute @workgroup_size({SPLAT_TILE}, {SPLAT_TILE})"
        ));
    }
    let signature = if shape.subgroups {
        "fn composite(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) t: u32, @builtin(subgroup_id) sg: u32, @builtin(subgroup_invocation_id) lane: u32)"
    } else {
        "fn composite(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) t: u32)"
    };
    w.block(
        signature,
        |w| {
            if shape.subgroups {
                let (wide, tall) = SUBGROUP_BLOCK;
                let across = SPLAT_TILE / wide;
                w.comment(format!("The pixel's place in the tile: subgroup t / 32 takes a block {wide} pixels wide and {tall} tall."));
                w.line(format!(
                    "let lid = vec2<u32>((t / 32u) % {across}u * {wide}u + t % {wide}u, (t / 32u) / {across}u * {tall}u + (t % 32u) / {wide}u);"
                ));
            }
            w.line("let tile = wid.x + wid.y * splat_tiles.tiles_x;");
            w.line(format!("let origin = wid.xy * {SPLAT_TILE}u;"));
            w.line("let px = origin.x + lid.x;");
            w.line("let py = origin.y + lid.y;");
            w.line("let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);");
            if additive {
                super::light::emit_declare(w);
            } else {
                w.comment("Light gathered so far, front to back, and the share of what lies behind that still comes through.");
                w.line("var gathered = vec3<f32>(0.0);");
                w.line("var through = 1.0;");
            }
            w.line("var done = px >= splat_tiles.width || py >= splat_tiles.height;");
            w.block("if (t == 0u)", |w| {
                w.line("batch_range = tile_ranges[tile];");
                w.line("atomicStore(&finished, 0u);");
            });
            w.comment("Uniform for the whole workgroup, as the barriers in the loop need.");
            w.line("let whole = workgroupUniformLoad(&batch_range);");
            w.comment("This workgroup's slice of the tile's list (slice SLICES - 1 is the front-most).");
            w.line("let chunk = (whole.y - whole.x + SLICES - 1u) / SLICES;");
            w.line("let first = min(whole.x + wid.z * chunk, whole.y);");
            w.line("let range = vec2<u32>(first, min(first + chunk, whole.y));");
            w.block("if (done)", |w| w.line("atomicAdd(&finished, 1u);"));
            w.line("var end = range.y;");
            if let Prefetch::Loads { declare, issue } = prefetch {
                w.comment("The first batch's entry and loads, then each next one's while this one is composited.");
                w.line("var next_k = 0u;");
                w.line(format!(
                    "let start0 = select(range.x, end - {batch}u, end - range.x > {batch}u);"
                ));
                w.block("if (start0 + t < end)", |w| {
                    w.line("next_k = tile_sprites[start0 + t];");
                });
                w.line(declare);
                w.block(format!("if (t < {batch}u)"), |w| w.line(issue));
            }
            w.block("while (end > range.x)", |w| {
                w.line(format!(
                    "let start = select(range.x, end - {batch}u, end - range.x > {batch}u);"
                ));
                w.line("let i = start + t;");
                if let Prefetch::Loads { .. } = prefetch {
                    w.line("let k = next_k;");
                    w.line(format!(
                        "let next_start = select(range.x, start - {batch}u, start - range.x > {batch}u);"
                    ));
                    w.block("if (start > range.x && next_start + t < start)", |w| {
                        w.line("next_k = tile_sprites[next_start + t];");
                    });
                }
                w.block("if (i < end)", |w| {
                    if let Prefetch::None = prefetch {
                        w.line("let k = tile_sprites[i];");
                    }
                    load(w);
                    emit_box_lines(w, record, diagonals);
                });
                w.comment("A record slot past the list's end crosses no line.");
                w.block(format!("else if (t < {batch}u)"), |w| {
                    let stride = line_words(diagonals);
                    w.line(format!("record_lines[{stride}u * t] = 0u;"));
                    for part in 1..stride {
                        w.line(format!("record_lines[{stride}u * t + {part}u] = 0u;"));
                    }
                });
                w.line("workgroupBarrier();");
                if let Prefetch::Loads { issue, .. } = prefetch {
                    w.comment("The next batch's loads, in flight while this batch's masks are built and walked (a stale next_k, past the slice's front, loads what this batch did).");
                    w.block(format!("if (t < {batch}u)"), |w| w.line(issue));
                }
                if shape.subgroups {
                    emit_line_masks_transposed(w, words, diagonals);
                } else {
                    emit_line_masks(w, words, line_masks, diagonals);
                }
                w.line("workgroupBarrier();");
                w.comment("Front to back: the batch's last entry first.");
                w.line(format!("var m = {words}u;"));
                w.block("while (!done && m > 0u)", |w| {
                    w.line("m -= 1u;");
                    w.line(format!(
                        "var bits = line_masks[lid.x * {words}u + m] & line_masks[({SPLAT_TILE}u + lid.y) * {words}u + m];"
                    ));
                    if diagonals {
                        w.line(format!(
                            "bits &= line_masks[({}u + lid.x + lid.y) * {words}u + m] & line_masks[({}u + lid.x - lid.y) * {words}u + m];",
                            2 * SPLAT_TILE,
                            2 * SPLAT_TILE + TILE_DIAGONALS + SPLAT_TILE - 1
                        ));
                    }
                    w.block("while (bits != 0u)", |w| {
                        w.line("let top = firstLeadingBit(bits);");
                        w.line("bits &= ~(1u << top);");
                        w.line("let j = m * 32u + top;");
                        evaluate(w);
                        if hdr {
                            w.comment("A float target takes what the fragment shader returns as it is.");
                            w.line("let f = shaded;");
                        } else {
                            w.comment("A unorm target clamps what the fragment shader returns before blending.");
                            w.line("let f = clamp(shaded, vec4<f32>(0.0), vec4<f32>(1.0));");
                        }
                        if additive && hdr {
                            w.comment("Light adds up past 1 in an HDR image: only the glow's clamp finishes a pixel (tested once a mask word, where there is one).");
                            super::light::emit_add(w);
                        } else if additive {
                            super::light::emit_add(w);
                            w.comment("Full on its own: full with whatever else adds to it.");
                            w.line(format!("done = {};", super::light::full()));
                        } else {
                            w.line("gathered += through * f.a * f.rgb;");
                            w.line("through *= 1.0 - f.a;");
                            w.comment("What lies behind can move no channel by half an 8-bit step.");
                            w.line("done = through < 0.5 / 255.0;");
                        }
                        w.block("if (done)", |w| {
                            w.line("atomicAdd(&finished, 1u);");
                            w.line("break;");
                        });
                    });
                    if additive && hdr && shape.clamped {
                        super::light::emit_ceiling_test(w);
                        w.block("if (done)", |w| w.line("atomicAdd(&finished, 1u);"));
                    }
                });
                if additive {
                    super::light::emit_batch_clamp(w, batch);
                }
                w.line("end = start;");
                w.comment("Also the barrier before the next batch overwrites the masks.");
                w.block(
                    format!(
                        "if (workgroupUniformLoad(&finished) == {}u)",
                        SPLAT_TILE * SPLAT_TILE
                    ),
                    |w| w.line("break;"),
                );
            });
            w.block("if (px < splat_tiles.width && py < splat_tiles.height)", |w| {
                w.line("let pixels = splat_tiles.width * splat_tiles.height;");
                let partial = match additive {
                    true => format!("vec4<f32>({}, 1.0)", super::light::as_f32()),
                    false => "vec4<f32>(gathered, through)".to_string(),
                };
                w.line(format!("partials[wid.z * pixels + py * splat_tiles.width + px] = {partial};"));
            });
        },
    );
    w.blank();
    emit_merge(w, shape, additive);
}

/// `merge`: a thread per pixel composes the slices' partial sums front to back (light gathered
/// adds as much of itself as the slices in front let through), puts them over the background
/// (or the image the parts before drew), and rounds once (or stores f16 pairs into an HDR
/// image).
fn emit_merge(w: &mut Writer, shape: &DrawShape, additive: bool) {
    w.line(format!(
        "@compute @workgroup_size({SPLAT_TILE}, {SPLAT_TILE})"
    ));
    w.block(
        "fn merge(@builtin(global_invocation_id) gid: vec3<u32>)",
        |w| {
            w.line("let px = gid.x;");
            w.line("let py = gid.y;");
            w.block(
                "if (px >= splat_tiles.width || py >= splat_tiles.height)",
                |w| w.line("return;"),
            );
            w.line("let pixels = splat_tiles.width * splat_tiles.height;");
            w.line("let pixel = py * splat_tiles.width + px;");
            w.line("var gathered = vec3<f32>(0.0);");
            w.line("var through = 1.0;");
            w.block("for (var s = SLICES; s > 0u; s--)", |w| {
                w.line("let part = partials[(s - 1u) * pixels + pixel];");
                w.line("gathered += through * part.rgb;");
                w.line("through *= part.a;");
            });
            emit_background(w, shape);
            let (colour, cover) = if additive {
                ("gathered + background", "cover")
            } else {
                (
                    "gathered + through * background",
                    "1.0 - through * (1.0 - cover)",
                )
            };
            emit_store(w, shape, colour, cover);
        },
    );
}

/// `var background`: what pixel (`px`, `py`; `pixel` = py * width + px) is drawn over: the
/// effect's background, or, when the parameters' background has alpha 0, the image the parts
/// drawn before this one left there; and `cover`, how much of the pixel those parts cover (0
/// over the effect's background). A host's image starts each frame cleared to nothing (the
/// runtime clears it): its parts always draw over it and keep its coverage, which the
/// composite over the host's colour reads as alpha.
fn emit_background(w: &mut Writer, shape: &DrawShape) {
    w.line("var background = unpack4x8unorm(splat_tiles.background).rgb;");
    if shape.host.is_some() {
        w.line("var cover = 0.0;");
    }
    w.comment("Alpha 0: this part draws over the image the parts before it drew.");
    w.block("if ((splat_tiles.background >> 24u) == 0u)", |w| {
        if shape.hdr {
            w.line("let under = splat_image[py * ((splat_tiles.width + 31u) & ~31u) + px];");
            w.line("background = vec3<f32>(unpack2x16float(under.x), unpack2x16float(under.y).x);");
            if shape.host.is_some() {
                w.line("cover = unpack2x16float(under.y).y;");
            }
        } else {
            w.line("background = unpack4x8unorm(splat_image[pixel]).rgb;");
        }
    });
}

/// Stores `colour` (a WGSL expression) at the pixel: rounded to 8 bits, or as f16 pairs into
/// an HDR image (clamped to the light's ceiling, [`super::light::splat_light_ceiling`]), with
/// alpha 1, or for a host's image the pixel's coverage `cover` (a WGSL expression).
fn emit_store(w: &mut Writer, shape: &DrawShape, colour: &str, cover: &str) {
    if shape.hdr {
        w.comment("At most the glow's clamp (or f16's largest finite value: no infinity reaches the bloom): a slice that stopped there leaves the same pixel as one that went on.");
        w.line(format!(
            "let c = min({colour}, vec3<f32>({}));",
            super::light::ceiling_as_f32()
        ));
        let alpha = match shape.host {
            Some(_) => cover,
            None => "1.0",
        };
        w.line(format!("let alpha = {alpha};"));
        w.line("let pitch = (splat_tiles.width + 31u) & ~31u;");
        w.line("splat_image[py * pitch + px] = vec2<u32>(pack2x16float(c.rg), pack2x16float(vec2<f32>(c.b, alpha)));");
    } else {
        w.line(format!(
            "splat_image[pixel] = pack4x8unorm(vec4<f32>(clamp({colour}, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));"
        ));
    }
}
