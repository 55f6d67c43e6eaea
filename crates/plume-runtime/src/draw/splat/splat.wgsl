// The compute renderer's tile kernels (not generated: they are the same for every effect; the
// effect-specific part, `project`, is in the effect's draw module). After `project` has written
// each sprite's pixel extent and colour and its tile count, and the counts have been scanned:
//   clear:  the keys of entries past those emit writes to the largest key (unused entries
//           sort last), tile ranges to empty;
//   emit:   one (tile, sprite) entry per tile a sprite touches, at the sprite's scanned offset
//           (a thread per entry),
//           so entries are in draw order; a stable radix sort by tile then keeps that order
//           within each tile (additive light, summed in any order, builds its lists with
//           additive_lists.wgsl instead);
//   ranges: each tile's run of entries;
//   raster: a workgroup per 16x16 tile, a thread per pixel, composites the tile's sprites
//           front to back (coverage at the pixel centre, alpha a (1 - r²)², the effect's
//           blend) and stops where nothing behind can change the 8-bit result. Batches of 256
//           sprites are binned to the pixels they touch first (bit masks), so a pixel in a
//           dense tile visits its own sprites, not the whole tile's. Additive discs split
//           each tile's list over slices (workgroups);
//   merge_discs: (additive discs) a thread per pixel sums the slices' light over what lies
//           under it.
// Quads use the draw module's generated `composite` and `merge` instead.

// Per sprite (16 bytes): centre x, y in pixels (f32), then (half extent in pixels, alpha) as
// two f16, then RGB as three 10-bit unorms.
@group(0) @binding(1) var<storage, read> splats: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(7) var<storage, read_write> image: array<u32>;
// Additive discs: each slice's light, in fixed point (LIGHT_UNITS a 1.0), red, green, blue
// and an unused word a pixel, summed over the slices; `merge_discs` takes and clears it.
@group(0) @binding(11) var<storage, read_write> disc_light: array<atomic<u32>>;
// Additive light is summed in fixed point as the generated composites sum it: LIGHT_UNITS,
// ROUNDING and ROUNDING_BITS come before this file from the compiler (`splat_light_constants`).
// Exact, so the same in any order: additive discs' lists are placed without a sort
// (additive_lists.wgsl).
// An additive pixel's units after a batch: at most 2.0 (the image shows at most 1, and light
// is never negative), so a batch of 256 fragments of at most 1.0 each cannot wrap the sums.
const LIGHT_MOST: u32 = 65536u;

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
// thread per sprite, writing its own run, scattered each warp's stores over 32 runs, far below
// the copy kernel's bandwidth (docs/performance.md, "What bounds sparks and orbit").
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
// and per row instead, 32 box tests a thread; discs are small, a few atomics each, and the
// masks' tests cost them more than they saved: docs/performance.md, "What bounds sparks and
// orbit".)
var<workgroup> masks: array<atomic<u32>, 2048>;
var<workgroup> tile_masks: array<atomic<u32>, 8>;
// Pixels of the tile that are finished (or outside the image).
var<workgroup> finished: atomic<u32>;

// A workgroup per tile, a thread per pixel, compositing the tile's sprites front to back (the
// draw order reversed) and rounding to 8 bits once at the end. Alpha: the light that still
// comes through, T, falls by (1 - a) at each sprite, and a pixel stops once T is under half an
// 8-bit step. Additive: light summed in fixed point, in any order, until every channel is full;
// each tile's list is split over groups.z workgroups (slices), whose light `merge_discs` sums
// (orbit's discs pile into the tiles along its rings, and one workgroup a tile worked through
// each pile alone; docs/performance.md, "What bounds sparks and orbit"). The tile stops when
// all its pixels have.
// Each batch of 256 sprites is first binned to the pixels their boxes touch (a bit per sprite
// in each pixel's mask; one tile-wide bit for a box that covers the tile), so a pixel visits
// only the sprites that may cover it, in descending bit order: front to back.
@compute @workgroup_size(16, 16)
fn raster(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>,
          @builtin(local_invocation_index) t: u32, @builtin(num_workgroups) groups: vec3<u32>) {
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
    // Additive: the bits of each fragment's rounded light summed (wrapping), the fragments
    // summed since the last batch (whose ROUNDING_BITS come off once a batch), and the units
    // at which a channel over the background is full.
    var light = vec3<u32>(0u);
    var layers = 0u;
    let wanted = vec3<u32>(ceil(max(vec3<f32>(1.0) - background, vec3<f32>(0.0)) * LIGHT_UNITS));
    if (t == 0u) {
        tile_range = ranges[tile];
        atomicStore(&finished, 0u);
    }
    // Uniform for the whole workgroup, as the barriers in the loop need.
    let whole = workgroupUniformLoad(&tile_range);
    // This workgroup's slice of the tile's list (additive discs are split over groups.z
    // workgroups; slice groups.z - 1 is the front-most).
    let slices = groups.z;
    let chunk = (whole.y - whole.x + slices - 1u) / slices;
    let first = min(whole.x + wid.z * chunk, whole.y);
    let range = vec2<u32>(first, min(first + chunk, whole.y));
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
                    light += bitcast<vec3<u32>>(fma(s.color.rgb, vec3<f32>(a * LIGHT_UNITS), vec3<f32>(ROUNDING)));
                    layers += 1u;
                    done = all(light - vec3<u32>(layers * ROUNDING_BITS) >= wanted);
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
        light = min(light - vec3<u32>(layers * ROUNDING_BITS), vec3<u32>(LIGHT_MOST));
        layers = 0u;
        end = start;
        // Also the barrier before the next batch overwrites the masks.
        if (workgroupUniformLoad(&finished) == TILE * TILE) {
            break;
        }
    }
    if (px < params.width && py < params.height && params.additive != 0u) {
        // The slice's light in units (each batch took its ROUNDING_BITS off and clamped it to
        // LIGHT_MOST), summed with the other slices'.
        let units = light;
        let at = 4u * (py * params.width + px);
        // Most slices of a sparse tile hold nothing for most pixels.
        if (units.x != 0u) {
            atomicAdd(&disc_light[at], units.x);
        }
        if (units.y != 0u) {
            atomicAdd(&disc_light[at + 1u], units.y);
        }
        if (units.z != 0u) {
            atomicAdd(&disc_light[at + 2u], units.z);
        }
    } else if (px < params.width && py < params.height) {
        let c = gathered + through * background;
        image[py * params.width + px] = pack4x8unorm(vec4<f32>(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
    }
}

// Additive discs: a thread per pixel puts the slices' light over the background (or the image
// the groups before drew), rounds once, and clears the light for the next frame.
@compute @workgroup_size(16, 16)
fn merge_discs(@builtin(global_invocation_id) gid: vec3<u32>) {
    let px = gid.x;
    let py = gid.y;
    if (px >= params.width || py >= params.height) {
        return;
    }
    let pixel = py * params.width + px;
    let at = 4u * pixel;
    let units = vec3<u32>(atomicLoad(&disc_light[at]), atomicLoad(&disc_light[at + 1u]), atomicLoad(&disc_light[at + 2u]));
    atomicStore(&disc_light[at], 0u);
    atomicStore(&disc_light[at + 1u], 0u);
    atomicStore(&disc_light[at + 2u], 0u);
    var background = unpack4x8unorm(params.background).rgb;
    if ((params.background >> 24u) == 0u) {
        background = unpack4x8unorm(image[pixel]).rgb;
    }
    let c = vec3<f32>(units) / LIGHT_UNITS + background;
    image[pixel] = pack4x8unorm(vec4<f32>(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
}
