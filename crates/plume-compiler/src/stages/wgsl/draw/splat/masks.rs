//! The composite's line masks: which of a batch's records cross each of the tile's lines
//! (columns, rows, and for additive quads diagonals and anti-diagonals). Each record's lines are
//! found once, as bits, when it is loaded (`record_lines`); a mask word gathers one bit from each
//! of 32 records, by a thread per word or by a subgroup's bit-matrix transpose.

use super::SPLAT_TILE;
use crate::base::writer::Writer;

/// Diagonals of a tile (x + y constant), and as many anti-diagonals (x - y).
pub(super) const TILE_DIAGONALS: u32 = 2 * SPLAT_TILE - 1;

/// Words of `record_lines` a record has: its columns and rows, and with `diagonals` its
/// diagonals and anti-diagonals.
pub(super) fn line_words(diagonals: bool) -> u32 {
    if diagonals {
        3
    } else {
        1
    }
}

/// Writes `record_lines` for the record thread `t` just put in the batch (`vec4s` apart, the box
/// last): the tile's columns and rows its box crosses, as bits (columns | rows << 16).
pub(super) fn emit_box_lines(w: &mut Writer, vec4s: u32, diagonals: bool) {
    let last = SPLAT_TILE - 1;
    w.comment("The tile's columns and rows the box crosses, counted from the tile's origin.");
    w.line(format!("let box = batch[{vec4s}u * t + {}u];", vec4s - 1));
    w.line(
        "let box_first = max(vec2<i32>(unpack_corner(box.z)) - vec2<i32>(origin), vec2<i32>(0));",
    );
    w.line(format!(
        "let box_last = min(vec2<i32>(unpack_corner(box.w)) - vec2<i32>(origin), vec2<i32>({last}));"
    ));
    w.line("let crossed = select(vec2<u32>(0u), vec2<u32>(span_bits(u32(box_first.x), u32(box_last.x)), span_bits(u32(box_first.y), u32(box_last.y))), box_first <= box_last);");
    w.line(format!(
        "record_lines[{}u * t] = crossed.x | crossed.y << {SPLAT_TILE}u;",
        line_words(diagonals)
    ));
}

/// The line masks: word q % `words` of line q / `words` (columns, rows, then with `diagonals`
/// diagonals and anti-diagonals), built by thread q % 256 from each record's `record_lines`, a
/// bit taken from each of the word's 32 records. No atomics, and a record's lines were found
/// once, when it was loaded: comparing every record's box with every line instead took a
/// large share of sparks' composite (benchmarks/h100-splat/masks/).
pub(super) fn emit_line_masks(w: &mut Writer, words: u32, line_masks: u32, diagonals: bool) {
    let stride = line_words(diagonals);
    let lines = 2 * SPLAT_TILE;
    w.comment(format!(
        "Word q % {words} of line q / {words}: bit r for record word * 32 + r."
    ));
    w.block(format!("for (var q = t; q < {line_masks}u; q += 256u)"), |w| {
        w.line(format!("let word = q % {words}u;"));
        w.line(format!("let line = q / {words}u;"));
        if diagonals {
            w.comment("Columns and rows in the record's first word, diagonals in its second, anti-diagonals in its third: which word, and which bit.");
            w.line(format!(
                "let part = select(select(2u, 1u, line < {}u), 0u, line < {lines}u);",
                lines + TILE_DIAGONALS
            ));
            w.line(format!(
                "let bit = line - select(select({}u, {lines}u, line < {}u), 0u, line < {lines}u);",
                lines + TILE_DIAGONALS,
                lines + TILE_DIAGONALS
            ));
        } else {
            w.line("let part = 0u;");
            w.line("let bit = line;");
        }
        w.line("var bits = 0u;");
        w.block("for (var r = 0u; r < 32u; r++)", |w| {
            w.line(format!(
                "bits |= ((record_lines[{stride}u * (word * 32u + r) + part] >> bit) & 1u) << r;"
            ));
        });
        w.line("line_masks[q] = bits;");
    });
}

/// `transpose32(row, lane)`: lane i of a subgroup of 32 holds row i of a 32 x 32 bit matrix
/// (bit j: column j) and gets column `lane` back (bit i: row i). Five rounds; round s swaps,
/// in every 2s x 2s block, the s x s block above the diagonal with the one below it, which
/// the lane s away holds.
pub(super) fn emit_transpose(w: &mut Writer) {
    w.comment("Lane i holds row i of a 32 x 32 bit matrix (bit j: column j); returns column `lane` (bit i: row i). Round s swaps the off-diagonal s x s blocks of every 2s x 2s block with the lane s away.");
    w.block("fn transpose32(row: u32, lane: u32) -> u32", |w| {
        w.line("var v = row;");
        for (s, low) in [
            (16u32, 0x0000_ffffu32),
            (8, 0x00ff_00ff),
            (4, 0x0f0f_0f0f),
            (2, 0x3333_3333),
            (1, 0x5555_5555),
        ] {
            let high = !low;
            w.line(format!("let partner_{s} = subgroupShuffleXor(v, {s}u);"));
            w.line(format!(
                "v = select((v & 0x{high:08x}u) | ((partner_{s} & 0x{high:08x}u) >> {s}u), (v & 0x{low:08x}u) | ((partner_{s} & 0x{low:08x}u) << {s}u), (lane & {s}u) == 0u);"
            ));
        }
        w.line("return v;");
    });
}

/// The line masks by subgroups of 32 (`shape.subgroups`): subgroup `sg` takes the word's 32
/// records' `record_lines` (one part: columns and rows, diagonals or anti-diagonals), a lane
/// each, and a transpose leaves lane L with line L's word. Five shuffles a part and word where
/// a thread per mask word took 32 loads, a slower composite (docs/performance.md, "What bounds
/// sparks and orbit"; benchmarks/h100-splat/masks/).
pub(super) fn emit_line_masks_transposed(w: &mut Writer, words: u32, diagonals: bool) {
    let stride = line_words(diagonals);
    let tasks = words * stride;
    let subgroups = SPLAT_TILE * SPLAT_TILE / 32;
    let lines = 2 * SPLAT_TILE;
    w.comment(format!(
        "Task word + {words} part: the part's lines of records word * 32 to word * 32 + 31."
    ));
    w.block(
        format!("for (var task = sg; task < {tasks}u; task += {subgroups}u)"),
        |w| {
            w.line(format!("let word = task % {words}u;"));
            w.line(format!("let part = task / {words}u;"));
            w.line(format!(
                "let masks = transpose32(record_lines[{stride}u * (word * 32u + lane) + part], lane);"
            ));
            if diagonals {
                w.comment(format!(
                    "Lines 0 to {} (columns, rows), {lines} to {} (diagonals), {} to {} (anti-diagonals).",
                    lines - 1,
                    lines + TILE_DIAGONALS - 1,
                    lines + TILE_DIAGONALS,
                    lines + 2 * TILE_DIAGONALS - 1
                ));
                w.line(format!(
                    "let first = select(select({}u, {lines}u, part == 1u), 0u, part == 0u);",
                    lines + TILE_DIAGONALS
                ));
                w.block(
                    format!("if (lane < select({TILE_DIAGONALS}u, {lines}u, part == 0u))"),
                    |w| {
                        w.line(format!(
                            "line_masks[(first + lane) * {words}u + word] = masks;"
                        ));
                    },
                );
            } else {
                w.line(format!("line_masks[lane * {words}u + word] = masks;"));
            }
        },
    );
}

/// Writes `record_lines[3 t + 1]` and `[3 t + 2]` for the record just loaded: the tile's
/// diagonals and anti-diagonals that its `corners` span, as bits (WGSL vec3s in the record's own coordinates, a
/// quad's (u, v, 1)). `rows` are the WGSL of the three rows of the map from a pixel (x, y, 1),
/// counted from the tile's origin, to those coordinates over 1 / w; a corner's pixel is that
/// map's inverse (its adjugate's columns, up to a factor) applied to the corner. A corner
/// behind the camera (1 / w not positive there) or too far out leaves every diagonal in the
/// span: the record's box still bounds it. Its footprint is convex, so the corners' extremes
/// bound it along each diagonal; the spans are widened a hundredth of a pixel, which float
/// rounding of the corners (about 1e-4 pixel) stays well inside, and every pixel is then tested
/// exactly anyway.
pub(crate) fn emit_diagonal_spans(w: &mut Writer, rows: [&str; 3], corners: &[&str]) {
    let last = TILE_DIAGONALS - 1;
    let [a, b, c] = rows;
    w.line(format!(
        "let adjugate = mat3x3<f32>(cross({b}, {c}), cross({c}, {a}), cross({a}, {b}));"
    ));
    w.line(format!("let det = dot({a}, adjugate[0]);"));
    w.line("var lows = vec2<f32>(1e9);");
    w.line("var highs = vec2<f32>(-1e9);");
    w.line("var bounded = true;");
    for (n, corner) in corners.iter().enumerate() {
        w.line(format!("let h{n} = adjugate * {corner};"));
        w.line(format!("let p{n} = h{n}.xy / h{n}.z;"));
        w.line(format!(
            "bounded = bounded && h{n}.z * det > 0.0 && all(abs(p{n}) < vec2<f32>(1e6));"
        ));
        w.line(format!(
            "lows = min(lows, vec2<f32>(p{n}.x + p{n}.y, p{n}.x - p{n}.y));"
        ));
        w.line(format!(
            "highs = max(highs, vec2<f32>(p{n}.x + p{n}.y, p{n}.x - p{n}.y));"
        ));
    }
    w.comment(format!(
        "Pixel (i, j)'s centre is on x + y = i + j + 1 (diagonal i + j) and x - y = i - j (anti-diagonal i - j + {}).",
        SPLAT_TILE - 1
    ));
    w.line(format!(
        "let first_line = clamp(ceil(lows + vec2<f32>(-1.01, {}.99)), vec2<f32>(0.0), vec2<f32>({last}.0));",
        SPLAT_TILE - 2
    ));
    w.line(format!(
        "let last_line = clamp(floor(highs + vec2<f32>(-0.99, {}.01)), vec2<f32>(0.0), vec2<f32>({last}.0));",
        SPLAT_TILE - 1
    ));
    w.line(format!(
        "let spans = select(vec4<u32>(0u, {last}u, 0u, {last}u), vec4<u32>(vec4<f32>(first_line.x, last_line.x, first_line.y, last_line.y)), bounded);"
    ));
    w.line("record_lines[3u * t + 1u] = span_bits(spans.x, spans.y);");
    w.line("record_lines[3u * t + 2u] = span_bits(spans.z, spans.w);");
}
