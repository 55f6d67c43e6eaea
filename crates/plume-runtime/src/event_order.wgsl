// The order of an event's firings (crate::event_order): the firing group's update appended
// (id, slot) pairs to `keys`/`vals` and counted them in the records' first word; this puts the
// slots in id order in `order`. Up to `rank_max` firings are ranked by counting (each firing
// counts the smaller ids, 256 at a time through workgroup memory); past that, the keys are
// padded to the whole buffer and radix-sorted, and the sorted slots copied. `order_prepare`
// writes the indirect arguments that run one way or the other.

struct OrderParams {
    // Slots of the firing group (the keys' and values' length).
    n: u32,
    // The most firings ranked by counting.
    rank_max: u32,
    // Dispatches of the radix sort (their arguments follow the first three in `args`).
    sort_dispatches: u32,
    pad0: u32,
}

const NONE: u32 = 0xffffffffu;
// Workgroups per dimension of the arguments written here (WebGPU's least limit).
const PER_DIM: u32 = 65535u;

@group(0) @binding(0) var<storage, read_write> keys: array<u32>;
@group(0) @binding(1) var<storage, read_write> vals: array<u32>;
@group(0) @binding(2) var<storage, read> records: array<u32>;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;
// Indirect arguments (x, y, z): rank, pad, copy, then each radix dispatch.
@group(0) @binding(4) var<storage, read_write> args: array<u32>;
// The radix dispatches' own arguments, written once when the program is built.
@group(0) @binding(5) var<storage, read> sort_args: array<u32>;
@group(0) @binding(6) var<uniform> params: OrderParams;

fn set_args(at: u32, threads: u32) {
    let groups = (threads + 255u) / 256u;
    args[3u * at] = min(groups, PER_DIM);
    args[3u * at + 1u] = (groups + PER_DIM - 1u) / PER_DIM;
    args[3u * at + 2u] = 1u;
}

@compute @workgroup_size(1)
fn order_prepare() {
    let count = records[0];
    let counted = count <= params.rank_max;
    set_args(0u, select(0u, count, counted));
    set_args(1u, select(params.n - count, 0u, counted));
    set_args(2u, select(count, 0u, counted));
    for (var d = 0u; d < params.sort_dispatches; d++) {
        for (var c = 0u; c < 3u; c++) {
            args[3u * (3u + d) + c] = select(sort_args[3u * d + c], 0u, counted);
        }
    }
}

var<workgroup> tile: array<u32, 256>;
var<workgroup> shared_count: u32;

@compute @workgroup_size(256)
fn order_rank(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) lane: u32) {
    // The workgroup's first index is uniform across it (the early return below must be).
    let first = (wid.x + wid.y * groups.x) * 256u;
    let k = first + lane;
    if (lane == 0u) {
        shared_count = records[0];
    }
    let count = workgroupUniformLoad(&shared_count);
    // A whole workgroup past the count (dispatched over every slot) has nothing to rank.
    if (first >= count) {
        return;
    }
    var mine = NONE;
    if (k < count) {
        mine = keys[k];
    }
    var rank = 0u;
    for (var base = 0u; base < count; base += 256u) {
        let m = base + lane;
        var key = NONE;
        if (m < count) {
            key = keys[m];
        }
        tile[lane] = key;
        workgroupBarrier();
        let len = min(256u, count - base);
        for (var t = 0u; t < len; t++) {
            rank += select(0u, 1u, tile[t] < mine);
        }
        workgroupBarrier();
    }
    if (k < count) {
        order[rank] = vals[k];
    }
}

@compute @workgroup_size(256)
fn order_pad(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let count = records[0];
    let k = count + gid.x + gid.y * groups.x * 256u;
    if (k < params.n) {
        keys[k] = NONE;
    }
}

@compute @workgroup_size(256)
fn order_copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * groups.x * 256u;
    if (k < records[0]) {
        order[k] = vals[k];
    }
}
