// The order of an event's firings, counted (crate::event_order): the firing group's update
// appended (id, slot) pairs to `keys`/`vals` and counted them in the records' first word;
// `order_rank` puts the slots in id order in `order`. Each firing counts the firings with
// smaller ids (ids are unique, so the ranks are too), 256 at a time through workgroup memory.
// Its first thread also prepares the children's spawn (event_prepare.wgsl, before this file),
// reading the child's counters at its start and writing them at its end.

const NONE: u32 = 0xffffffffu;

@group(0) @binding(0) var<storage, read_write> keys: array<u32>;
@group(0) @binding(1) var<storage, read_write> vals: array<u32>;
@group(0) @binding(2) var<storage, read> records: array<u32>;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;

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
    let preparer = first == 0u && lane == 0u;
    var loaded = vec2<u32>(0u);
    if (preparer) {
        loaded = prepare_loads();
    }
    // Dispatched over every slot: a whole workgroup past the count has nothing to rank.
    if (first >= count) {
        if (preparer) {
            prepare_spawn(count, loaded);
        }
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
        if (len == 256u) {
            // A full tile: a fixed trip count, eight comparisons an iteration, lets the loads
            // overlap, which counts most when a whole group fires at once. The last tile,
            // usually the only one, compares only what it holds.
            for (var t = 0u; t < 256u; t += 8u) {
                rank += select(0u, 1u, tile[t] < mine) + select(0u, 1u, tile[t + 1u] < mine)
                    + select(0u, 1u, tile[t + 2u] < mine) + select(0u, 1u, tile[t + 3u] < mine)
                    + select(0u, 1u, tile[t + 4u] < mine) + select(0u, 1u, tile[t + 5u] < mine)
                    + select(0u, 1u, tile[t + 6u] < mine) + select(0u, 1u, tile[t + 7u] < mine);
            }
        } else {
            for (var t = 0u; t < len; t++) {
                rank += select(0u, 1u, tile[t] < mine);
            }
        }
        workgroupBarrier();
    }
    if (k < count) {
        order[rank] = vals[k];
    }
    if (preparer) {
        prepare_spawn(count, loaded);
    }
}
