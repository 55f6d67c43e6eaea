// GPU sorts of (key, value) pairs by key, ascending; no subgroup operations, so they run on
// llvmpipe. Not generated: the sorts are the same for every effect (the depth keys are).
//
// Radix sort: stable LSD, 8-bit digits, one tile of 256 pairs per workgroup.
//   histogram: per tile, count digits; counts[digit * tiles + tile] (digit-major, so one
//              exclusive scan gives every tile's first output slot for each digit, stably).
//   scan_blocks / add_sums: the exclusive scan, 256 per workgroup, applied level by level.
//   scatter: ranks each pair within its tile by sorting (digit, thread) in workgroup memory,
//            so equal digits keep their input order; writes at counts[...] + rank.
// Bitonic sort: the baseline, on a power-of-two padded array, by (key, value).

struct Params {
    n: u32,
    shift: u32,
    tiles: u32,
    j: u32,
    k: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read_write> keys_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> vals_in: array<u32>;
@group(0) @binding(2) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(3) var<storage, read_write> vals_out: array<u32>;
@group(0) @binding(4) var<storage, read_write> counts: array<u32>;
@group(0) @binding(5) var<uniform> params: Params;

var<workgroup> hist: array<atomic<u32>, 256>;
var<workgroup> start: array<u32, 256>;
var<workgroup> order: array<u32, 256>;

fn tile_of(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

@compute @workgroup_size(256)
fn histogram(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
             @builtin(local_invocation_index) t: u32) {
    let tile = tile_of(wid, groups);
    atomicStore(&hist[t], 0u);
    workgroupBarrier();
    let i = tile * 256u + t;
    if (tile < params.tiles && i < params.n) {
        atomicAdd(&hist[(keys_in[i] >> params.shift) & 255u], 1u);
    }
    workgroupBarrier();
    if (tile < params.tiles) {
        counts[t * params.tiles + tile] = atomicLoad(&hist[t]);
    }
}

@compute @workgroup_size(256)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
           @builtin(local_invocation_index) t: u32) {
    let tile = tile_of(wid, groups);
    let i = tile * 256u + t;
    let valid = tile < params.tiles && i < params.n;
    var digit = 255u;
    if (valid) {
        digit = (keys_in[i] >> params.shift) & 255u;
    }
    atomicStore(&hist[t], 0u);
    workgroupBarrier();
    if (valid) {
        atomicAdd(&hist[digit], 1u);
    }
    workgroupBarrier();
    // Where each digit starts within the tile (exclusive scan of 256 bins by one thread).
    if (t == 0u) {
        var sum = 0u;
        for (var d = 0u; d < 256u; d++) {
            start[d] = sum;
            sum += atomicLoad(&hist[d]);
        }
    }
    // Sort (digit, thread) in workgroup memory: equal digits stay in thread order. Invalid
    // lanes sort last.
    order[t] = select(0xffffffffu, (digit << 8u) | t, valid);
    workgroupBarrier();
    for (var k = 2u; k <= 256u; k <<= 1u) {
        for (var j = k >> 1u; j > 0u; j >>= 1u) {
            let other = t ^ j;
            if (other > t) {
                let a = order[t];
                let b = order[other];
                let up = (t & k) == 0u;
                if ((a > b) == up) {
                    order[t] = b;
                    order[other] = a;
                }
            }
            workgroupBarrier();
        }
    }
    let entry = order[t];
    if (entry != 0xffffffffu) {
        let d = entry >> 8u;
        let src = tile * 256u + (entry & 255u);
        let dst = counts[d * params.tiles + tile] + (t - start[d]);
        keys_out[dst] = keys_in[src];
        vals_out[dst] = vals_in[src];
    }
}

// Exclusive scan of `counts` in blocks of 256: each block scanned in place, its total written to
// keys_out[block] (used as the next level's input).
@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    let i = block * 256u + t;
    var v = 0u;
    if (i < params.n) {
        v = counts[i];
    }
    start[t] = v;
    workgroupBarrier();
    // Hillis-Steele inclusive scan.
    for (var off = 1u; off < 256u; off <<= 1u) {
        var add = 0u;
        if (t >= off) {
            add = start[t - off];
        }
        workgroupBarrier();
        start[t] += add;
        workgroupBarrier();
    }
    if (i < params.n) {
        counts[i] = start[t] - v;
    }
    if (t == 255u && block < params.tiles) {
        keys_out[block] = start[255];
    }
}

// Adds the scanned block totals (in keys_out) back to every element of their block.
@compute @workgroup_size(256)
fn add_sums(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
            @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    let i = block * 256u + t;
    if (i < params.n) {
        counts[i] += keys_out[block];
    }
}

// One compare-exchange step of a bitonic sort over keys_in/vals_in (power-of-two length n),
// ordered by (key, value).
@compute @workgroup_size(256)
fn bitonic_step(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    let other = i ^ params.j;
    if (i >= params.n || other <= i) {
        return;
    }
    let ka = keys_in[i];
    let kb = keys_in[other];
    let va = vals_in[i];
    let vb = vals_in[other];
    let greater = ka > kb || (ka == kb && va > vb);
    let up = (i & params.k) == 0u;
    if (greater == up) {
        keys_in[i] = kb;
        keys_in[other] = ka;
        vals_in[i] = vb;
        vals_in[other] = va;
    }
}
