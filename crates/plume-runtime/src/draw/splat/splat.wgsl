// The compute splat's tile kernels (not generated: they are the same for every effect; the
// effect-specific part, `project`, is in the effect's draw module). After `project` has written
// each sprite's pixel extent and colour and its tile count, and the counts have been scanned:
//   clear:  the keys of entries past those emit writes to the largest key (unused entries
//           sort last), tile ranges to empty;
//   emit:   one (tile, sprite) entry per tile a sprite touches, at the sprite's scanned offset
//           (a thread per entry),
//           so entries are in draw order; a stable radix sort by tile then keeps that order
//           within each tile (additive quads and ribbons, summed in any order, build their
//           lists with additive_lists.wgsl instead);
//   ranges: each tile's run of entries;
//   raster: a workgroup per 16x16 tile, a thread per pixel, composites the tile's sprites
//           front to back (coverage at the pixel centre, alpha a (1 - r²)², the effect's
//           blend) and stops where nothing behind can change the 8-bit result. Batches of 256
//           sprites are binned to the pixels they touch first (bit masks), so a pixel in a
//           dense tile visits its own sprites, not the whole tile's. Quads use the draw
//           module's generated `composite` and `merge` instead.

// Per sprite (16 bytes): centre x, y in pixels (f32), then (half extent in pixels, alpha) as
// two f16, then RGB as three 10-bit unorms.
@group(0) @binding(1) var<storage, read> splats: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(7) var<storage, read_write> image: array<u32>;

const TILE: u32 = 16u;
const UNUSED: u32 = 0xffffffffu;

// Entries every sprite's tiles take: the last sprite's scanned offset plus its count.
fn entries_needed() -> u32 {
    if (params.count == 0u) {
        return 0u;
    }
    return offsets[params.count - 1u] + tile_counts[params.count - 1u];
}

// Only the entries `emit` leaves unwritten: emit writes every one below entries_needed().
@compute @workgroup_size(256)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index2d(gid, groups);
    if (i < params.entries && i >= entries_needed()) {
        keys[i] = UNUSED;
        vals[i] = UNUSED;
    }
    if (i < params.tiles) {
        ranges[i] = vec2<u32>(0u);
    }
}

struct Splat {
    centre: vec2<f32>,
    extent: f32,
    color: vec4<f32>,
}

fn unpack_splat(w: vec4<u32>) -> Splat {
    var s: Splat;
    s.centre = bitcast<vec2<f32>>(w.xy);
    let ea = unpack2x16float(w.z);
    s.extent = ea.x;
    s.color = vec4<f32>(
        vec3<f32>(vec3<u32>(w.w, w.w >> 10u, w.w >> 20u) & vec3<u32>(1023u)) / 1023.0,
        ea.y,
    );
    return s;
}

// The workgroup's 256 sprites' scanned offsets (and where the last one's entries end), and
// their tile boxes.
var<workgroup> group_offsets: array<u32, 257>;
var<workgroup> group_boxes: array<vec2<u32>, 256>;

// A workgroup per 256 consecutive sprites writes their entries, which are consecutive too,
// a thread per entry: entry p is sprite r's (the last whose offset is at most p), its tile
// the box's (p - offset)th in row order. Neighbouring threads write neighbouring words; a
// thread per sprite, writing its own run, scattered each warp's stores over 32 runs (H100,
// sparks 10M: 0.84 ms for 53.7M entries, about a fifth of the copy kernel's bandwidth).
@compute @workgroup_size(256)
fn emit(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    // Uniform (as the barrier needs): the workgroup's first sprite, index2d's numbering.
    let first = (wid.x + wid.y * groups.x) * 256u;
    let k = first + t;
    if (first >= params.count) {
        return;
    }
    let sprites = min(params.count - first, 256u);
    if (t < sprites) {
        group_offsets[t] = offsets[k];
        group_boxes[t] = tile_boxes[k];
        if (t + 1u == sprites) {
            group_offsets[sprites] = offsets[k] + tile_counts[k];
            if (k + 1u == params.count) {
                status[0] = offsets[k] + tile_counts[k];
            }
        }
    }
    workgroupBarrier();
    let begin = group_offsets[0];
    let end = min(group_offsets[sprites], params.entries);
    for (var p = begin + t; p < end; p += 256u) {
        // The last sprite r whose offset is at most p (sprites with no entries share the next
        // one's offset, and the search passes them).
        var lo = 0u;
        var hi = sprites - 1u;
        while (lo < hi) {
            let mid = (lo + hi + 1u) / 2u;
            if (group_offsets[mid] <= p) {
                lo = mid;
            } else {
                hi = mid - 1u;
            }
        }
        let packed = group_boxes[lo];
        let b = vec4<u32>(packed & vec2<u32>(0xffffu), packed >> vec2<u32>(16u)).xzyw;
        let i = p - group_offsets[lo];
        let columns = b.z - b.x + 1u;
        keys[p] = (b.y + i / columns) * params.tiles_x + b.x + i % columns;
        vals[p] = first + lo;
    }
}

@compute @workgroup_size(256)
fn find_ranges(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index2d(gid, groups);
    let n = min(status[0], params.entries);
    if (i >= n) {
        return;
    }
    let key = keys[i];
    if (key >= params.tiles) {
        return;
    }
    if (i == 0u || keys[i - 1u] != key) {
        ranges[key].x = i;
    }
    if (i + 1u == n || keys[i + 1u] != key) {
        ranges[key].y = i + 1u;
    }
}

var<workgroup> shared_splats: array<vec4<u32>, 256>;
var<workgroup> tile_range: vec2<u32>;
// Per pixel of the tile, which of the batch's 256 sprites may cover it: 8 words of bits; and
// the sprites whose boxes cover the whole tile. (The quads' composite builds a mask per column
// and per row instead, 32 box tests a thread; discs are small, a few atomics each, and that
// took fountain 10M's raster stage from 0.34 to 0.74 ms on an H100.)
var<workgroup> masks: array<atomic<u32>, 2048>;
var<workgroup> tile_masks: array<atomic<u32>, 8>;
// Pixels of the tile that are finished (or outside the image).
var<workgroup> finished: atomic<u32>;

// A workgroup per tile, a thread per pixel, compositing the tile's sprites front to back (the
// draw order reversed) and rounding to 8 bits once at the end. Alpha: the light that still
// comes through, T, falls by (1 - a) at each sprite, and a pixel stops once T is under half an
// 8-bit step; additive: once every channel is full. The tile stops when all its pixels have.
// Each batch of 256 sprites is first binned to the pixels their boxes touch (a bit per sprite
// in each pixel's mask; one tile-wide bit for a box that covers the tile), so a pixel visits
// only the sprites that may cover it, in descending bit order: front to back.
@compute @workgroup_size(16, 16)
fn raster(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>,
          @builtin(local_invocation_index) t: u32) {
    let tile = wid.x + wid.y * params.tiles_x;
    let origin = wid.xy * TILE;
    let px = origin.x + lid.x;
    let py = origin.y + lid.y;
    let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
    var gathered = vec3<f32>(0.0);
    var through = 1.0;
    var done = px >= params.width || py >= params.height;
    var background = unpack4x8unorm(params.background).rgb;
    // Alpha 0: this group draws over the image the groups before it drew.
    if ((params.background >> 24u) == 0u && !done) {
        background = unpack4x8unorm(image[py * params.width + px]).rgb;
    }
    if (t == 0u) {
        tile_range = ranges[tile];
        atomicStore(&finished, 0u);
    }
    // Uniform for the whole workgroup, as the barriers in the loop need.
    let range = workgroupUniformLoad(&tile_range);
    if (done) {
        atomicAdd(&finished, 1u);
    }
    var end = range.y;
    while (end > range.x) {
        let start = select(range.x, end - 256u, end - range.x > 256u);
        for (var w = 0u; w < 8u; w++) {
            atomicStore(&masks[t * 8u + w], 0u);
        }
        if (t < 8u) {
            atomicStore(&tile_masks[t], 0u);
        }
        workgroupBarrier();
        let i = start + t;
        if (i < end) {
            let raw = splats[vals[i]];
            shared_splats[t] = raw;
            let s = unpack_splat(raw);
            let o = vec2<f32>(origin);
            // A thousandth of a pixel of margin: a pixel this box misses is at the rim, where
            // the exact test below finds no cover anyway.
            let lo = max(ceil(s.centre - s.extent - 0.501) - o, vec2<f32>(0.0));
            let hi = min(floor(s.centre + s.extent - 0.499) - o, vec2<f32>(f32(TILE - 1u)));
            let bit = 1u << (t & 31u);
            if (all(lo == vec2<f32>(0.0)) && all(hi == vec2<f32>(f32(TILE - 1u)))) {
                atomicOr(&tile_masks[t >> 5u], bit);
            } else if (all(lo <= hi)) {
                for (var y = u32(lo.y); y <= u32(hi.y); y++) {
                    for (var x = u32(lo.x); x <= u32(hi.x); x++) {
                        atomicOr(&masks[(y * TILE + x) * 8u + (t >> 5u)], bit);
                    }
                }
            }
        }
        workgroupBarrier();
        var w = 8u;
        while (!done && w > 0u) {
            w -= 1u;
            var m = atomicLoad(&masks[t * 8u + w]) | atomicLoad(&tile_masks[w]);
            while (m != 0u) {
                let b = firstLeadingBit(m);
                m &= ~(1u << b);
                let s = unpack_splat(shared_splats[w * 32u + b]);
                let uv = (centre - s.centre) / s.extent;
                let r2 = dot(uv, uv);
                if (r2 >= 1.0) {
                    continue;
                }
                let a = s.color.a * (1.0 - r2) * (1.0 - r2);
                if (params.additive != 0u) {
                    gathered += s.color.rgb * a;
                    done = all(gathered + background >= vec3<f32>(1.0));
                } else {
                    gathered += through * a * s.color.rgb;
                    through *= 1.0 - a;
                    // What lies behind can move no channel by half an 8-bit step.
                    done = through < 0.5 / 255.0;
                }
                if (done) {
                    atomicAdd(&finished, 1u);
                    break;
                }
            }
        }
        end = start;
        // Also the barrier before the next batch overwrites the masks.
        if (workgroupUniformLoad(&finished) == TILE * TILE) {
            break;
        }
    }
    if (px < params.width && py < params.height) {
        var c = gathered + through * background;
        if (params.additive != 0u) {
            c = gathered + background;
        }
        image[py * params.width + px] = pack4x8unorm(vec4<f32>(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
    }
}
