// The exclusive scan (scan_blocks / add_sums: 256 per workgroup, applied level by level; up to
// 256 blocks, add_block_prefix adds each block's prefix of the block totals in one dispatch) and the
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
// What `scan_blocks_from` scans out of place, zeroing it as it reads it (the flock grid's bucket
// counts, ready for the next step's counting with no kernel to clear them).
@group(0) @binding(6) var<storage, read_write> source: array<u32>;

var<workgroup> start: array<u32, 256>;

fn tile_of(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
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
        source[i] = 0u;
    }
    scan_block(block, i, t, v);
}

// Block `block`'s exclusive scan of the values `v` its threads hold into counts[i], and its
// total into keys_out[block]. Every thread must call it.
fn scan_block(block: u32, i: u32, t: u32, v: u32) {
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

// Up to 256 blocks: each workgroup sums the totals of the blocks before its own (keys_out, as
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
