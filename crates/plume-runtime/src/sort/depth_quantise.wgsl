// Depth keys quantised to 16 bits over the live particles' depth range, so the depth sort needs
// two 8-bit radix passes instead of four (quantise.rs says what the draw loses). The radix sort
// maps the keys as its first pass reads them (radix.wgsl's `quantised`, the same map); the
// `quantise` kernel here maps them in place for the bitonic sort.
//
// In: `keys[slot]` as the effect's `depth_keys` kernel writes them: the order-preserving u32 of
// the f32 depth, inverted so the farthest is smallest, at most 0xfffffffd; 0xfffffffe for a
// non-finite depth, 0xffffffff for a free slot. Out, in place: 0 (farthest) ..= 65533
// (nearest), 0xfffe, 0xffff.

struct Params {
    n: u32,
    // Row length of a 2D dispatch, in threads.
    row: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<storage, read_write> keys: array<u32>;
// (smallest live key, largest live key): the farthest and the nearest live depth.
@group(0) @binding(1) var<storage, read_write> range: array<atomic<u32>, 2>;
@group(0) @binding(2) var<uniform> params: Params;
// The sort's values, for the bitonic sort (the radix sort pairs each key with its index itself).
@group(0) @binding(3) var<storage, read_write> vals: array<u32>;

const WORKGROUP: u32 = 256u;
const LIVE_MAX: u32 = 0xfffffffdu;
const STEPS: f32 = 65533.0;

var<workgroup> group_min: atomic<u32>;
var<workgroup> group_max: atomic<u32>;

@compute @workgroup_size(1)
fn range_reset() {
    atomicStore(&range[0], 0xffffffffu);
    atomicStore(&range[1], 0u);
}

// Keys each thread of `range_reduce` reads: a workgroup covers 4,096, so that 16.7M keys take
// 4,096 workgroups and as many pairs of atomics on `range` (one a workgroup of 256 keys, 65,536
// pairs on the same two words, waited on each other).
const RANGE_KEYS_PER_THREAD: u32 = 16u;

// The smallest and largest live key: one atomic per workgroup on `range`.
@compute @workgroup_size(WORKGROUP)
fn range_reduce(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lane: u32) {
    if (lane == 0u) {
        atomicStore(&group_min, 0xffffffffu);
        atomicStore(&group_max, 0u);
    }
    workgroupBarrier();
    let first = (wid.x + wid.y * groups.x) * WORKGROUP * RANGE_KEYS_PER_THREAD;
    var lo = 0xffffffffu;
    var hi = 0u;
    for (var k = 0u; k < RANGE_KEYS_PER_THREAD; k++) {
        // Consecutive threads read consecutive keys.
        let slot = first + k * WORKGROUP + lane;
        if (slot < params.n) {
            let key = keys[slot];
            if (key <= LIVE_MAX) {
                lo = min(lo, key);
                hi = max(hi, key);
            }
        }
    }
    if (lo != 0xffffffffu) {
        atomicMin(&group_min, lo);
        atomicMax(&group_max, hi);
    }
    workgroupBarrier();
    if (lane == 0u) {
        let group_lo = atomicLoad(&group_min);
        if (group_lo != 0xffffffffu) {
            atomicMin(&range[0], group_lo);
            atomicMax(&range[1], atomicLoad(&group_max));
        }
    }
}

// The f32 depth a key stands for (the inverse of depth_keys' map).
fn depth_of(key: u32) -> f32 {
    let ordered = ~key;
    let bits = select(~ordered, ordered & 0x7fffffffu, (ordered & 0x80000000u) != 0u);
    return bitcast<f32>(bits);
}

@compute @workgroup_size(WORKGROUP)
fn quantise(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x + gid.y * params.row;
    if (slot >= params.n) {
        return;
    }
    let key = keys[slot];
    if (key > LIVE_MAX) {
        keys[slot] = key & 0xffffu;
        return;
    }
    // Halves, so that neither difference overflows to Inf for depths near the f32 limit.
    let far = 0.5 * depth_of(atomicLoad(&range[0]));
    let near = 0.5 * depth_of(atomicLoad(&range[1]));
    let span = far - near;
    var q = 0.0;
    // One live particle, or all at one depth: every key 0 (the sort keeps slot order).
    if (span > 0.0) {
        // Monotonic in the depth (a subtraction, a division by a positive constant, a floor),
        // so no two particles swap; equal quanta keep slot order.
        q = floor((far - 0.5 * depth_of(key)) / span * STEPS);
    }
    keys[slot] = u32(clamp(q, 0.0, STEPS));
}

// Every slot its own value: the bitonic sort's input pairs (the effect's `depth_keys` writes keys
// only).
@compute @workgroup_size(WORKGROUP)
fn identity_vals(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x + gid.y * params.row;
    if (slot < params.n) {
        vals[slot] = slot;
    }
}
