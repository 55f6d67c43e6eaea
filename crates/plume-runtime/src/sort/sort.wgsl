// The exclusive scan (short ones 256 words a workgroup: scan_blocks, add_block_prefix; long ones
// reduce then scan, 2,048 words a workgroup: scan_reduce, scan_totals, scan_apply) and the
// bitonic sort (the radix sort's baseline, on a power-of-two padded array, by (key, value)); no
// subgroup operations, so they run on llvmpipe. The radix sort is in radix.wgsl.

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
// What the `_from` scans (`scan_blocks_from`, `scan_reduce_from`, `scan_apply_from`) scan out
// of place, zeroing it as they read it (the flock grid's bucket counts, ready for the next
// step's counting with no kernel to clear them).
@group(0) @binding(6) var<storage, read_write> source: array<u32>;

var<workgroup> start: array<u32, 256>;

fn tile_of(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

// A short scan (up to 256 blocks of 256 words): each block scanned in place, its total written to
// keys_out[block]; then `add_block_prefix`.
@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    let i = block * 256u + t;
    var v = 0u;
    if (i < params.n) {
        v = counts[i];
    }
    scan_block(block, i, t, v);
}

// `scan_blocks` of `source` into `counts`, leaving `source` zeroed (each word is read by one
// thread only, so it can clear what it read).
@compute @workgroup_size(256)
fn scan_blocks_from(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    let i = block * 256u + t;
    var v = 0u;
    if (i < params.n) {
        v = source[i];
        // Only where it is not zero already, as scan_apply_from.
        if (v != 0u) {
            source[i] = 0u;
        }
    }
    scan_block(block, i, t, v);
}

// Block `block`'s exclusive scan of the values `v` its threads hold into counts[i], and its
// total into keys_out[block]. Every thread must call it.
fn scan_block(block: u32, i: u32, t: u32, v: u32) {
    let inclusive = inclusive_scan_256(t, v);
    if (i < params.n) {
        counts[i] = inclusive - v;
    }
    if (t == 255u && block < params.tiles) {
        keys_out[block] = inclusive;
    }
}

// Each workgroup sums the totals of the blocks before its own (keys_out, as
// scan_blocks left them) and adds that to its block: one dispatch where scanning the totals
// first would take two.
@compute @workgroup_size(256)
fn add_block_prefix(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    var v = 0u;
    if (t < block) {
        v = keys_out[t];
    }
    start[t] = v;
    workgroupBarrier();
    for (var half = 128u; half > 0u; half >>= 1u) {
        if (t < half) {
            start[t] += start[t + half];
        }
        workgroupBarrier();
    }
    let i = block * 256u + t;
    if (i < params.n) {
        counts[i] += start[0];
    }
}

// A long scan of `counts` (or of `source` into `counts`, zeroing `source`), reduce then scan,
// SCAN_PER words a thread: `scan_reduce` writes each block's total to keys_out[block];
// past SCAN_PREFIX_MAX blocks `scan_totals` (one workgroup) scans the totals in place
// (params.shift 1); `scan_apply` scans each block from its prefix: the scanned total, or (fewer
// blocks, params.shift 0) the sum of the totals before its own, which it adds up itself (one
// dispatch fewer; one block needs neither of the others).
const SCAN_PER: u32 = 8u;
// Words a workgroup of a long scan takes (radix.rs's SCAN_BLOCK).
const SCAN_BLOCK: u32 = 256u * SCAN_PER;

// A block of 2,048 words staged in workgroup memory, word e at e + e / 32: the eight
// consecutive words a thread scans then lie in eight different banks.
var<workgroup> staged: array<u32, SCAN_BLOCK + SCAN_BLOCK / 32u>;

fn padded(e: u32) -> u32 {
    return e + (e >> 5u);
}

// `inclusive_scan_256` and `exclusive_scan_256` are the shared workgroup scan
// (device/workgroup_scan.wgsl).

// The sum of the threads' `v`, returned to every thread. Every thread must call it.
fn workgroup_sum(t: u32, v: u32) -> u32 {
    start[t] = v;
    workgroupBarrier();
    for (var half = 128u; half > 0u; half >>= 1u) {
        if (t < half) {
            start[t] += start[t + half];
        }
        workgroupBarrier();
    }
    let total = start[0];
    workgroupBarrier();
    return total;
}

@compute @workgroup_size(256)
fn scan_reduce(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    var s = 0u;
    for (var r = 0u; r < SCAN_PER; r++) {
        let i = block * SCAN_BLOCK + r * 256u + t;
        if (i < params.n) {
            s += counts[i];
        }
    }
    let total = workgroup_sum(t, s);
    if (t == 0u) {
        keys_out[block] = total;
    }
}

@compute @workgroup_size(256)
fn scan_reduce_from(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    var s = 0u;
    for (var r = 0u; r < SCAN_PER; r++) {
        let i = block * SCAN_BLOCK + r * 256u + t;
        if (i < params.n) {
            s += source[i];
        }
    }
    let total = workgroup_sum(t, s);
    if (t == 0u) {
        keys_out[block] = total;
    }
}

// One workgroup: keys_out[0..params.tiles] replaced by its exclusive scan, each thread taking a
// contiguous run of the totals.
@compute @workgroup_size(256)
fn scan_totals(@builtin(local_invocation_index) t: u32) {
    let per = (params.tiles + 255u) / 256u;
    let lo = min(t * per, params.tiles);
    let hi = min(lo + per, params.tiles);
    var s = 0u;
    for (var b = lo; b < hi; b++) {
        s += keys_out[b];
    }
    var run = exclusive_scan_256(t, s);
    for (var b = lo; b < hi; b++) {
        let v = keys_out[b];
        keys_out[b] = run;
        run += v;
    }
}

// Block `block`, staged, scanned from its prefix into counts. Every thread must call it.
fn apply_block(block: u32, t: u32) {
    var before = 0u;
    if (params.shift == 1u) {
        before = keys_out[block];
    } else {
        var s = 0u;
        for (var b = t; b < block; b += 256u) {
            s += keys_out[b];
        }
        before = workgroup_sum(t, s);
    }
    workgroupBarrier();
    var mine: array<u32, SCAN_PER>;
    var s = 0u;
    for (var r = 0u; r < SCAN_PER; r++) {
        mine[r] = staged[padded(SCAN_PER * t + r)];
        s += mine[r];
    }
    var run = before + exclusive_scan_256(t, s);
    for (var r = 0u; r < SCAN_PER; r++) {
        staged[padded(SCAN_PER * t + r)] = run;
        run += mine[r];
    }
    workgroupBarrier();
    for (var r = 0u; r < SCAN_PER; r++) {
        let e = r * 256u + t;
        let i = block * SCAN_BLOCK + e;
        if (i < params.n) {
            counts[i] = staged[padded(e)];
        }
    }
}

@compute @workgroup_size(256)
fn scan_apply(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    for (var r = 0u; r < SCAN_PER; r++) {
        let e = r * 256u + t;
        let i = block * SCAN_BLOCK + e;
        var v = 0u;
        if (i < params.n) {
            v = counts[i];
        }
        staged[padded(e)] = v;
    }
    apply_block(block, t);
}

// `scan_apply` of `source` into `counts`, leaving `source` zeroed (each word is read by one
// thread only, so it can clear what it read).
@compute @workgroup_size(256)
fn scan_apply_from(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                   @builtin(local_invocation_index) t: u32) {
    let block = tile_of(wid, groups);
    for (var r = 0u; r < SCAN_PER; r++) {
        let e = r * 256u + t;
        let i = block * SCAN_BLOCK + e;
        var v = 0u;
        if (i < params.n) {
            v = source[i];
            // Only where it is not zero already: the flock's bucket counts are mostly zeros,
            // and writing zeros back over zeros made its scan much slower (docs/performance.md,
            // "Depth sort and the radix sort").
            if (v != 0u) {
                source[i] = 0u;
            }
        }
        staged[padded(e)] = v;
    }
    apply_block(block, t);
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
