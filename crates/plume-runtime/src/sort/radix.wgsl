// The radix sort's shared kernels: a stable LSD radix sort of (key, value) pairs by 8-bit
// digits, one pass per digit, in the reduce-then-scan shape (no waiting between workgroups):
//
//   rs_upsweep:   per partition of PART keys, count each digit:
//                 pass_hist[digit * partitions + partition].
//   rs_scan:      one workgroup per digit: the exclusive scan of its row over the partitions
//                 (where each partition's run of that digit starts among the digit's keys), and
//                 the digit's total in digit_totals.
//   downsweep:    per partition, ranks each key among the partition's keys of its digit, in input
//                 order, and writes it to
//                 (keys of smaller digits) + (this digit in earlier partitions) + rank.
//                 Two versions, in their own files: radix_portable.wgsl (no subgroup operations:
//                 every adapter, llvmpipe included) and radix_subgroup.wgsl (subgroup ballots, for
//                 adapters whose subgroups are exactly 32 wide).
//
// Not generated: the sort is the same for every effect (the keys are not).

const THREADS: u32 = 256u;
// Keys per thread and per partition. PART keys staged in workgroup memory, the subgroup
// downsweep's per-subgroup digit counts and two 256-word scan buffers take 14 of WebGPU's
// guaranteed 16 KiB of workgroup memory. 8 keys a thread gave the fastest downsweep: with
// more, fewer workgroups fit an SM at once; with fewer, the digit scan over more partitions
// costs what the downsweep saves (docs/performance.md, "Depth sort and the radix sort").
const KPT: u32 = 8u;
const PART: u32 = 2048u;

struct RadixParams {
    n: u32,
    shift: u32,
    partitions: u32,
    pad: u32,
}

@group(0) @binding(0) var<storage, read_write> keys_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> vals_in: array<u32>;
@group(0) @binding(2) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(3) var<storage, read_write> vals_out: array<u32>;
@group(0) @binding(4) var<storage, read_write> pass_hist: array<u32>;
@group(0) @binding(5) var<uniform> params: RadixParams;
@group(0) @binding(6) var<storage, read_write> digit_totals: array<u32, 256>;
// The depth sort's live range (depth_quantise.wgsl's `range`: the smallest and largest live
// key), read only by the `_depth` entry points.
@group(0) @binding(7) var<storage, read> depth_range: array<u32, 2>;

var<workgroup> counts: array<atomic<u32>, 256>;

fn partition_of(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

fn digit_of(key: u32) -> u32 {
    return (key >> params.shift) & 255u;
}

// `exclusive_scan_256` is the shared workgroup scan (device/workgroup_scan.wgsl).

// How a pass reads its keys: as they are, or (the first pass of a depth sort) mapped to 16
// bits over the live depth range (`quantised`), so that no pass of its own rewrites them.
struct KeyMap {
    quantise: bool,
    // Half the farthest live depth, and half the span to the nearest (see `quantised`).
    far: f32,
    span: f32,
}

// Keys as they are: the entry points that do not map keys never touch `depth_range`, so their
// bind groups need not hold it.
fn plain_keys() -> KeyMap {
    return KeyMap(false, 0.0, 0.0);
}

// The f32 depth a depth key stands for (the inverse of the effect's `depth_keys` map).
fn depth_of(key: u32) -> f32 {
    let ordered = ~key;
    let bits = select(~ordered, ordered & 0x7fffffffu, (ordered & 0x80000000u) != 0u);
    return bitcast<f32>(bits);
}

// A depth key mapped to 16 bits over the live range, exactly as depth_quantise.wgsl's `quantise`
// kernel maps it in place (the bitonic sort's path): 0 (farthest) ..= 65533 (nearest), 0xfffe
// for a non-finite depth, 0xffff for a free slot.
fn quantised(key: u32, map: KeyMap) -> u32 {
    if (key > 0xfffffffdu) {
        return key & 0xffffu;
    }
    var q = 0.0;
    // One live particle, or all at one depth: every key 0 (the sort keeps slot order).
    if (map.span > 0.0) {
        q = floor((map.far - 0.5 * depth_of(key)) / map.span * 65533.0);
    }
    return u32(clamp(q, 0.0, 65533.0));
}

// The value paired with key i: a depth sort's first pass pairs each key with its slot, which
// is its index (so the effect's `depth_keys` writes no values and this pass reads none).
fn load_val(i: u32, map: KeyMap) -> u32 {
    if (map.quantise) {
        return i;
    }
    return vals_in[i];
}

fn load_key(i: u32, map: KeyMap) -> u32 {
    let key = keys_in[i];
    if (map.quantise) {
        return quantised(key, map);
    }
    return key;
}

@compute @workgroup_size(256)
fn rs_upsweep(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) t: u32) {
    upsweep(wid, groups, t, plain_keys());
}

@compute @workgroup_size(256)
fn rs_upsweep_depth(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) t: u32) {
    upsweep(wid, groups, t, depth_keys_map());
}

fn upsweep(wid: vec3<u32>, groups: vec3<u32>, t: u32, map: KeyMap) {
    let part = partition_of(wid, groups);
    atomicStore(&counts[t], 0u);
    workgroupBarrier();
    if (part < params.partitions) {
        let base = part * PART;
        // Runs of one digit (common in the high digits of depth keys) are counted with one
        // atomic each, not one a key: every thread adding to the same counter serialises.
        // Every load first, so that they are all in flight at once.
        var keys: array<u32, KPT>;
        for (var k = 0u; k < KPT; k++) {
            let i = base + k * THREADS + t;
            if (i < params.n) {
                keys[k] = load_key(i, map);
            }
        }
        var run_digit = 0u;
        var run = 0u;
        for (var k = 0u; k < KPT; k++) {
            if (base + k * THREADS + t < params.n) {
                let d = digit_of(keys[k]);
                if (d != run_digit && run > 0u) {
                    atomicAdd(&counts[run_digit], run);
                    run = 0u;
                }
                run_digit = d;
                run += 1u;
            }
        }
        if (run > 0u) {
            atomicAdd(&counts[run_digit], run);
        }
    }
    workgroupBarrier();
    if (part < params.partitions) {
        pass_hist[t * params.partitions + part] = atomicLoad(&counts[t]);
    }
}

// One workgroup a digit (256 workgroups): each thread scans a contiguous stretch of the row.
@compute @workgroup_size(256)
fn rs_scan(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let d = wid.x;
    let parts = params.partitions;
    let per = (parts + THREADS - 1u) / THREADS;
    let first = min(t * per, parts);
    let last = min(first + per, parts);
    let row = d * parts;
    var sum = 0u;
    for (var p = first; p < last; p++) {
        sum += pass_hist[row + p];
    }
    var run = exclusive_scan_256(t, sum);
    for (var p = first; p < last; p++) {
        let c = pass_hist[row + p];
        pass_hist[row + p] = run;
        run += c;
    }
    if (t == THREADS - 1u) {
        digit_totals[d] = run;
    }
}

// The same scan for few partitions, in one workgroup: each thread scans its digit's row
// alone, with no barrier (on a CPU adapter the 256 workgroups of rs_scan cost more than the
// whole sort of a few thousand keys).
@compute @workgroup_size(256)
fn rs_scan_small(@builtin(local_invocation_index) d: u32) {
    let parts = params.partitions;
    let row = d * parts;
    var run = 0u;
    for (var p = 0u; p < parts; p++) {
        let c = pass_hist[row + p];
        pass_hist[row + p] = run;
        run += c;
    }
    digit_totals[d] = run;
}

// How many keys partition `part` holds (0 past the last).
fn partition_len(part: u32) -> u32 {
    if (part >= params.partitions) {
        return 0u;
    }
    return min(PART, params.n - part * PART);
}

// The map of a depth sort's first pass, from the live range (halves, so that neither
// difference overflows to Inf for depths near the f32 limit).
fn depth_keys_map() -> KeyMap {
    let far = 0.5 * depth_of(depth_range[0]);
    let near = 0.5 * depth_of(depth_range[1]);
    return KeyMap(true, far, far - near);
}
