// The tile lists of additive light, built without a sort (not generated: the same for every
// effect). Additive light is summed in fixed point by the composite, exactly, so the order of a
// tile's list does not change its pixels; each entry can go wherever its tile's run has room.
// After `project` has written each sprite's tile box and count:
//   clear_cursors: every tile's cursor to 0;
//   count_entries: a workgroup per CHUNK sprites counts their entries per tile in workgroup
//                  memory, then adds each tile's count to its cursor;
//   place_runs:    one workgroup turns the counts into each tile's run of entries (in tile
//                  order: the ranges the composite reads) and each cursor into its run's start;
//   place:         a workgroup per CHUNK sprites counts again, takes a block of each tile's run
//                  for them (one atomic add on the cursor a tile), and hands its slots out in
//                  workgroup memory.
// Global atomics a tile per workgroup, not per entry: with an atomic a (sprite, tile) pair on
// the cursors, most tiles' entries fell on a few hundred hot cursors and queued there
// (docs/performance.md, "What bounds sparks and orbit"). Workgroup memory holds BAND tiles;
// an image with more runs the two kernels once per band of tiles (the grid's z).
// This replaces the sorted lists' scan, emit, radix sort by tile and ranges for additive
// light (docs/performance.md measures both).

// Per tile: its entries counted, then where its next entry goes.
@group(0) @binding(10) var<storage, read_write> cursors: array<atomic<u32>>;

// Sprite k's tiles, x0, y0, x1, y1 (inclusive); only meaningful where its count is not 0.
fn tile_box(k: u32) -> vec4<u32> {
    let packed = tile_boxes[k];
    return vec4<u32>(packed & vec2<u32>(0xffffu), packed >> vec2<u32>(16u)).xzyw;
}

@compute @workgroup_size(256)
fn clear_cursors(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index2d(gid, groups);
    if (i < params.tiles) {
        atomicStore(&cursors[i], 0u);
    }
}

// Tiles counted in workgroup memory at once, and sprites a thread (a workgroup's chunk is
// 256 * PER sprites).
const BAND: u32 = 4096u;
const PER: u32 = 4u;

var<workgroup> bins: array<atomic<u32>, 4096>;

// The entries of a run of `n` consecutive sprites whose tile boxes are the same (`b`), counted
// into `bins` for the tiles among the band_len from band0 on: one workgroup atomic a tile for
// the run, not a sprite.
fn count_run(n: u32, b: vec4<u32>, band0: u32, band_len: u32) {
    for (var y = b.y; y <= b.w; y++) {
        for (var x = b.x; x <= b.z; x++) {
            let bin = y * params.tiles_x + x - band0;
            if (bin < band_len) {
                atomicAdd(&bins[bin], n);
            }
        }
    }
}

// The entries of the workgroup's chunk of sprites counted into `bins` by tile: thread t takes
// PER consecutive sprites, in runs whose tile boxes are the same. A ribbon's neighbouring
// segments mostly share their tiles, and an atomic each on the same bin queued them. Placing
// them in runs too wrote each run's slots in a loop, which was slower, so `place_sweep` places
// sprite by sprite (docs/performance.md, "What bounds sparks and orbit").
fn count_sweep(chunk: u32, t: u32, band0: u32, band_len: u32) {
    var run_n = 0u;
    var run_box = vec4<u32>(0u);
    for (var j = 0u; j < PER; j++) {
        let k = (chunk * 256u + t) * PER + j;
        if (k < params.count && tile_counts[k] != 0u) {
            let b = tile_box(k);
            // Hidden sprites between two others touch no tile: the run goes on past them.
            if (all(b == run_box) && run_n != 0u) {
                run_n += 1u;
                continue;
            }
            if (run_n != 0u) {
                count_run(run_n, run_box, band0, band_len);
            }
            run_n = 1u;
            run_box = b;
        }
    }
    if (run_n != 0u) {
        count_run(run_n, run_box, band0, band_len);
    }
}

// Each entry of the workgroup's chunk of sprites whose tile is among the band_len tiles from
// band0 on, in turn, given the slot its tile's bin points at, the bin moving on.
fn place_sweep(chunk: u32, t: u32, band0: u32, band_len: u32) {
    for (var j = 0u; j < PER; j++) {
        let k = (chunk * PER + j) * 256u + t;
        if (k < params.count && tile_counts[k] != 0u) {
            let b = tile_box(k);
            for (var y = b.y; y <= b.w; y++) {
                for (var x = b.x; x <= b.z; x++) {
                    let bin = y * params.tiles_x + x - band0;
                    if (bin >= band_len) {
                        continue;
                    }
                    let p = atomicAdd(&bins[bin], 1u);
                    // Entries past the list's end are dropped (the list grows for the next frame).
                    if (p < params.entries) {
                        vals[p] = k;
                    }
                }
            }
        }
    }
}

// The workgroup's chunk counted into `bins` by tile, after zeroing them.
fn count_chunk(chunk: u32, t: u32, band0: u32, band_len: u32) {
    for (var i = t; i < band_len; i += 256u) {
        atomicStore(&bins[i], 0u);
    }
    workgroupBarrier();
    count_sweep(chunk, t, band0, band_len);
    workgroupBarrier();
}

@compute @workgroup_size(256)
fn count_entries(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let band0 = wid.z * BAND;
    let band_len = min(BAND, params.tiles - band0);
    count_chunk(wid.x + wid.y * groups.x, t, band0, band_len);
    for (var i = t; i < band_len; i += 256u) {
        let n = atomicLoad(&bins[i]);
        if (n != 0u) {
            atomicAdd(&cursors[band0 + i], n);
        }
    }
}

// Thread t scans its own run of tiles (a 256th of them) and the workgroup scans the 256 sums
// (the shared workgroup scan, device/workgroup_scan.wgsl).
@compute @workgroup_size(256)
fn place_runs(@builtin(local_invocation_index) t: u32) {
    let per = (params.tiles + 255u) / 256u;
    let first = min(t * per, params.tiles);
    let last = min(first + per, params.tiles);
    var own = 0u;
    for (var i = first; i < last; i++) {
        own += atomicLoad(&cursors[i]);
    }
    let inclusive = inclusive_scan_256(t, own);
    var start = inclusive - own;
    for (var i = first; i < last; i++) {
        let n = atomicLoad(&cursors[i]);
        // Entries past the list's end are dropped (and the list grown for the next frame).
        ranges[i] = vec2<u32>(min(start, params.entries), min(start + n, params.entries));
        atomicStore(&cursors[i], start);
        start += n;
    }
    if (t == 255u) {
        status[0] = inclusive;
    }
}

@compute @workgroup_size(256)
fn place(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let band0 = wid.z * BAND;
    let band_len = min(BAND, params.tiles - band0);
    let chunk = wid.x + wid.y * groups.x;
    count_chunk(chunk, t, band0, band_len);
    // Each tile's block: where the chunk's entries of it start.
    for (var i = t; i < band_len; i += 256u) {
        let n = atomicLoad(&bins[i]);
        if (n != 0u) {
            atomicStore(&bins[i], atomicAdd(&cursors[band0 + i], n));
        }
    }
    workgroupBarrier();
    place_sweep(chunk, t, band0, band_len);
}
