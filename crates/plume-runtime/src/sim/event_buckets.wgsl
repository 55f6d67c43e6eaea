// The order of an event's firings by buckets (crate::sim::events, Ordering::Bucketed): a stream
// compaction in id order, with no sort. The firing group's update appended (id, slot) pairs to
// `keys`/`vals` in whatever order its threads ran, counted them, and noted the complement of
// the smallest id and the largest id in the records' header. Then, at the next step's start:
//
//   bucket_count:      each firing drops into the bucket (id - smallest) >> shift, the shift
//                      the least that fits the ids' range into the n buckets (n = the firing
//                      group's slots): 0, one id a bucket, while the range is under n.
//   bucket_reduce,
//   bucket_scan:       the exclusive scan of the used buckets' counts (reduce-then-scan, blocks
//                      of 2,048 buckets; each block sums the totals before it), into `starts`.
//   bucket_place:      with one id a bucket, each firing's slot goes to order[its bucket's
//                      start]; otherwise the firing is staged in its bucket's run.
//   bucket_rank:       (wider buckets only) each staged firing's rank is its bucket's start plus
//                      the staged ids of its bucket smaller than its own.
//
// The work follows the firings and the range of their ids, not the group's slots: each kernel
// is dispatched on a fixed grid (at most 1,024 workgroups) whose threads, or workgroups, stride
// over this step's firings (or used buckets), so that a step with few firings launches few
// threads (a grid over every slot of a 5.6M-slot group cost more, on an H100, than the work).
// Ids are unique, so a bucket of width 2^shift holds at most 2^shift firings, and at most as
// many as fired: the ranking's comparisons stay below n * 2^32 / n = 2^32 in the worst case,
// and are none while the ids span fewer than n. `bucket_place` clears the counts it used, so
// every bucket is zero again for the next step.

const THREADS: u32 = 256u;
// Buckets per thread and per block of the scan.
const PER_THREAD: u32 = 8u;
const BLOCK: u32 = 2048u;

struct Header {
    count: u32,
    not_min_id: u32,
    max_id: u32,
    pad: u32,
}

@group(0) @binding(0) var<storage, read> keys: array<u32>;
@group(0) @binding(1) var<storage, read> vals: array<u32>;
@group(0) @binding(2) var<storage, read> header: Header;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;
// n buckets' counts: zero between steps.
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
// n buckets' starts, then each block's total.
@group(0) @binding(5) var<storage, read_write> starts: array<u32>;
// Each firing's place in its bucket (wider buckets only).
@group(0) @binding(6) var<storage, read_write> within: array<u32>;
// The firings (id, slot) staged by bucket (wider buckets only).
@group(0) @binding(7) var<storage, read_write> staged: array<vec2<u32>>;

// This step's firings and their buckets.
struct Window {
    count: u32,
    min_id: u32,
    shift: u32,
    buckets: u32,
}

var<workgroup> shared_window: Window;
var<workgroup> scan_buf: array<u32, 256>;

fn window_of(h: Header) -> Window {
    if (h.count == 0u) {
        return Window(0u, 0u, 0u, 0u);
    }
    let min_id = ~h.not_min_id;
    let spread = h.max_id - min_id;
    let n = arrayLength(&counts);
    var shift = 0u;
    while (shift < 31u && (spread >> shift) >= n) {
        shift += 1u;
    }
    return Window(h.count, min_id, shift, (spread >> shift) + 1u);
}

fn window() -> Window {
    return window_of(header);
}

// The window, uniform across the workgroup (the kernels with barriers return early on it).
fn uniform_window(lane: u32) -> Window {
    if (lane == 0u) {
        shared_window = window();
    }
    return workgroupUniformLoad(&shared_window);
}

fn bucket_of(w: Window, id: u32) -> u32 {
    return (id - w.min_id) >> w.shift;
}

fn flat(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

fn workgroups(groups: vec3<u32>) -> u32 {
    return groups.x * groups.y;
}

// Exclusive prefix sum of `v` over the workgroup's 256 threads (Hillis-Steele); every thread
// calls it.
fn exclusive_scan_256(t: u32, v: u32) -> u32 {
    workgroupBarrier();
    scan_buf[t] = v;
    workgroupBarrier();
    for (var off = 1u; off < THREADS; off <<= 1u) {
        var add = 0u;
        if (t >= off) {
            add = scan_buf[t - off];
        }
        workgroupBarrier();
        scan_buf[t] += add;
        workgroupBarrier();
    }
    return scan_buf[t] - v;
}

@compute @workgroup_size(256)
fn bucket_count(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lane: u32) {
    let w = window();
    for (var k = flat(wid, groups) * THREADS + lane; k < w.count; k += workgroups(groups) * THREADS) {
        let b = bucket_of(w, keys[k]);
        if (w.shift == 0u) {
            atomicStore(&counts[b], 1u);
        } else {
            within[k] = atomicAdd(&counts[b], 1u);
        }
    }
}

// The total of a block's used buckets, after the n starts.
@compute @workgroup_size(256)
fn bucket_reduce(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                 @builtin(local_invocation_index) lane: u32) {
    let w = uniform_window(lane);
    for (var block = flat(wid, groups); block * BLOCK < w.buckets; block += workgroups(groups)) {
        let first = block * BLOCK + lane * PER_THREAD;
        var sum = 0u;
        for (var j = 0u; j < PER_THREAD; j++) {
            if (first + j < w.buckets) {
                sum += atomicLoad(&counts[first + j]);
            }
        }
        let before = exclusive_scan_256(lane, sum);
        if (lane == THREADS - 1u) {
            starts[arrayLength(&counts) + block] = before + sum;
        }
    }
}

// Each used bucket's start: the totals of the blocks before its block (each workgroup sums
// them itself: at most n / 2,048 words, a few loads a thread, where a dispatch of its own to
// scan them cost a dependent launch a step) plus the buckets before it in the block.
@compute @workgroup_size(256)
fn bucket_scan(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) lane: u32) {
    let w = uniform_window(lane);
    // The blocks' totals follow the n buckets' starts.
    let totals_at = arrayLength(&counts);
    for (var block = flat(wid, groups); block * BLOCK < w.buckets; block += workgroups(groups)) {
        var before = 0u;
        for (var b = lane; b < block; b += THREADS) {
            before += starts[totals_at + b];
        }
        // The scan leaves the workgroup's total in its last entry, read before the next scan's
        // first barrier lets anyone write it again.
        _ = exclusive_scan_256(lane, before);
        let block_start = scan_buf[THREADS - 1u];
        let first = block * BLOCK + lane * PER_THREAD;
        var mine: array<u32, PER_THREAD>;
        var sum = 0u;
        for (var j = 0u; j < PER_THREAD; j++) {
            mine[j] = 0u;
            if (first + j < w.buckets) {
                mine[j] = atomicLoad(&counts[first + j]);
            }
            sum += mine[j];
        }
        var run = block_start + exclusive_scan_256(lane, sum);
        for (var j = 0u; j < PER_THREAD; j++) {
            if (first + j < w.buckets) {
                starts[first + j] = run;
            }
            run += mine[j];
        }
    }
}

@compute @workgroup_size(256)
fn bucket_place(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lane: u32) {
    let w = window();
    for (var k = flat(wid, groups) * THREADS + lane; k < w.count; k += workgroups(groups) * THREADS) {
        let id = keys[k];
        let b = bucket_of(w, id);
        let start = starts[b];
        if (w.shift == 0u) {
            order[start] = vals[k];
        } else {
            staged[start + within[k]] = vec2<u32>(id, vals[k]);
        }
        // Every firing of the bucket clears it (no one reads the counts from here on).
        atomicStore(&counts[b], 0u);
    }
}

@compute @workgroup_size(256)
fn bucket_rank(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) lane: u32) {
    let w = window();
    if (w.shift == 0u) {
        return;
    }
    for (var q = flat(wid, groups) * THREADS + lane; q < w.count; q += workgroups(groups) * THREADS) {
        let mine = staged[q];
        let b = bucket_of(w, mine.x);
        let lo = starts[b];
        var hi = w.count;
        if (b + 1u < w.buckets) {
            hi = starts[b + 1u];
        }
        var rank = lo;
        for (var m = lo; m < hi; m++) {
            rank += select(0u, 1u, staged[m].x < mine.x);
        }
        order[rank] = mine.y;
    }
}
