// The radix sort's downsweep with subgroup ballots (appended to radix.wgsl; the device's
// SUBGROUP feature allows the builtins), for adapters whose subgroups are exactly 32 wide (the
// runtime checks): each of the 8 subgroups ranks a contiguous stretch of 32 * KPT keys of the
// partition, in KPT rounds of 32 keys in input order. In a round, 8 ballots (one per digit bit)
// give each lane the mask of lanes holding its digit; its rank is its count of such lanes below
// it, plus the keys of its digit this subgroup has already seen (per-subgroup counters, two
// 16-bit digits a word). The partition's keys are then placed in workgroup memory in sorted
// order, so that the writes to the output are contiguous runs per digit.

const SUBGROUPS: u32 = 8u;

var<workgroup> staged: array<u32, 2048>;
// Per subgroup, 128 words: digit 2m in the low half of word m, 2m + 1 in the high half.
var<workgroup> sub_counts: array<atomic<u32>, 1024>;
var<workgroup> digit_dst: array<u32, 256>;
var<workgroup> subgroup_sums: array<u32, SUBGROUPS>;

// Exclusive prefix sum of `v` over the workgroup's 256 threads by subgroup scans (one per
// subgroup of 32, then the 8 subgroup totals). Every thread must call it.
fn exclusive_scan_subgroups(sg: u32, lane: u32, v: u32) -> u32 {
    let inclusive = subgroupInclusiveAdd(v);
    workgroupBarrier();
    if (lane == 31u) {
        subgroup_sums[sg] = inclusive;
    }
    workgroupBarrier();
    var before = 0u;
    for (var s = 0u; s < sg; s++) {
        before += subgroup_sums[s];
    }
    return before + inclusive - v;
}

@compute @workgroup_size(256)
fn rs_downsweep(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) t: u32,
                @builtin(subgroup_id) sg: u32,
                @builtin(subgroup_invocation_id) lane: u32) {
    downsweep(wid, groups, t, sg, lane, plain_keys());
}

@compute @workgroup_size(256)
fn rs_downsweep_depth(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                      @builtin(local_invocation_index) t: u32,
                      @builtin(subgroup_id) sg: u32,
                      @builtin(subgroup_invocation_id) lane: u32) {
    downsweep(wid, groups, t, sg, lane, depth_keys_map());
}

fn downsweep(wid: vec3<u32>, groups: vec3<u32>, t: u32, sg: u32, lane: u32, map: KeyMap) {
    let part = partition_of(wid, groups);
    let len = partition_len(part);
    let ranked = rank_partition(part, len, t, sg, lane, map);
    // Where this digit's keys of the partition start in the output: the keys of every smaller
    // digit, plus this digit's keys in earlier partitions.
    let digit = sg * 32u + lane;
    var base = exclusive_scan_subgroups(sg, lane, digit_totals[digit]);
    if (part < params.partitions) {
        base += pass_hist[digit * params.partitions + part];
    }
    place_partition(part, len, t, sg, lane, ranked, base, map);
}

// A partition's keys ranked within it: each key's place among the partition's keys of its
// digit (`pos`, before `place_partition` adds the digit's start), and, for the digit of thread
// (sg, lane) (digit sg * 32 + lane), the partition's count of it and where its run starts in
// the partition's sorted order.
struct Ranked {
    keys: array<u32, KPT>,
    pos: array<u32, KPT>,
    total: u32,
    local_start: u32,
}

fn rank_partition(part: u32, len: u32, t: u32, sg: u32, lane: u32, map: KeyMap) -> Ranked {
    for (var j = t; j < SUBGROUPS * 128u; j += THREADS) {
        atomicStore(&sub_counts[j], 0u);
    }
    workgroupBarrier();
    // This subgroup's stretch of the partition, as offsets from the partition's start.
    let first = sg * 32u * KPT;
    let below = (1u << lane) - 1u;
    var keys: array<u32, KPT>;
    var pos: array<u32, KPT>;
    // Every key load first, so that they are all in flight before the ranking needs them
    // rather than each key loaded as it is ranked. The values are not loaded here too: their
    // registers cost more than their early loads save (docs/performance.md, "Depth sort and the
    // radix sort").
    for (var k = 0u; k < KPT; k++) {
        let local = first + k * 32u + lane;
        keys[k] = 0u;
        if (local < len) {
            keys[k] = load_key(part * PART + local, map);
        }
    }
    for (var k = 0u; k < KPT; k++) {
        let valid = first + k * 32u + lane < len;
        let key = keys[k];
        let d = digit_of(key);
        var peers = subgroupBallot(valid).x;
        for (var b = 0u; b < 8u; b++) {
            let bit = ((d >> b) & 1u) == 1u;
            let ones = subgroupBallot(bit).x;
            peers &= select(~ones, ones, bit);
        }
        // The lowest lane of each digit adds the digit's count and learns the count before.
        let leader = firstTrailingBit(peers);
        let half = (d & 1u) * 16u;
        var before = 0u;
        if (valid && leader == lane) {
            before = atomicAdd(&sub_counts[sg * 128u + (d >> 1u)], countOneBits(peers) << half);
        }
        before = subgroupShuffle(before, select(0u, leader, valid));
        pos[k] = ((before >> half) & 0xffffu) + countOneBits(peers & below);
    }
    workgroupBarrier();
    // Per digit pair, the counts of earlier subgroups (exclusive) and the partition's totals.
    if (t < 128u) {
        var sum = 0u;
        for (var s = 0u; s < SUBGROUPS; s++) {
            let c = atomicLoad(&sub_counts[s * 128u + t]);
            atomicStore(&sub_counts[s * 128u + t], sum);
            sum += c;
        }
        digit_dst[2u * t] = sum & 0xffffu;
        digit_dst[2u * t + 1u] = sum >> 16u;
    }
    workgroupBarrier();
    // From here on, thread (sg, lane) handles digit sg * 32 + lane, the order the subgroup
    // scans run in (the local index need not follow it).
    let digit = sg * 32u + lane;
    let total = digit_dst[digit];
    let local_start = exclusive_scan_subgroups(sg, lane, total);
    return Ranked(keys, pos, total, local_start);
}

// Writes a ranked partition's keys and values out, digit d's run from `base` (given by the
// thread of digit d: the keys of every smaller digit plus this digit's keys in earlier
// partitions).
fn place_partition(part: u32, len: u32, t: u32, sg: u32, lane: u32, ranked: Ranked, base: u32,
                   map: KeyMap) {
    let pos = stage_partition(len, t, sg, lane, ranked);
    write_partition(part, len, t, sg, lane, ranked.local_start, pos, base, map);
}

// Puts a ranked partition's keys in workgroup memory in sorted order (`staged`), and returns
// each of this thread's keys' places there. Needs nothing from other partitions, so OneSweep
// does it before it waits for them.
fn stage_partition(len: u32, t: u32, sg: u32, lane: u32, ranked: Ranked) -> array<u32, KPT> {
    let first = sg * 32u * KPT;
    let digit = sg * 32u + lane;
    let keys = ranked.keys;
    var pos = ranked.pos;
    workgroupBarrier();
    staged[digit] = ranked.local_start;
    workgroupBarrier();
    for (var k = 0u; k < KPT; k++) {
        let d = digit_of(keys[k]);
        let earlier = (atomicLoad(&sub_counts[sg * 128u + (d >> 1u)]) >> ((d & 1u) * 16u)) & 0xffffu;
        pos[k] += staged[d] + earlier;
    }
    workgroupBarrier();
    for (var k = 0u; k < KPT; k++) {
        if (first + k * 32u + lane < len) {
            staged[pos[k]] = keys[k];
        }
    }
    return pos;
}

// Writes the staged keys, then the values, to their places: digit d's run from `base`, given
// by the thread of digit d.
fn write_partition(part: u32, len: u32, t: u32, sg: u32, lane: u32, local_start: u32,
                   pos: array<u32, KPT>, base: u32, map: KeyMap) {
    let first = sg * 32u * KPT;
    let dst = write_keys(len, t, sg, lane, local_start, base);
    for (var k = 0u; k < KPT; k++) {
        let local = first + k * 32u + lane;
        if (local < len) {
            staged[pos[k]] = load_val(part * PART + local, map);
        }
    }
    write_vals(len, t, dst);
}

// This thread's values (its keys' partners, in input order), loaded before they are needed.
fn load_vals(part: u32, len: u32, sg: u32, lane: u32, map: KeyMap) -> array<u32, KPT> {
    let first = sg * 32u * KPT;
    var vals: array<u32, KPT>;
    for (var k = 0u; k < KPT; k++) {
        let local = first + k * 32u + lane;
        vals[k] = 0u;
        if (local < len) {
            vals[k] = load_val(part * PART + local, map);
        }
    }
    return vals;
}

// [`write_partition`] with the values loaded beforehand (`load_vals`).
fn write_partition_loaded(len: u32, t: u32, sg: u32, lane: u32, local_start: u32,
                          pos: array<u32, KPT>, base: u32, vals: array<u32, KPT>) {
    let first = sg * 32u * KPT;
    let dst = write_keys(len, t, sg, lane, local_start, base);
    for (var k = 0u; k < KPT; k++) {
        if (first + k * 32u + lane < len) {
            staged[pos[k]] = vals[k];
        }
    }
    write_vals(len, t, dst);
}

// Writes the staged keys to their places and returns where each of this thread's went; the
// staging memory is free for the values once it returns.
fn write_keys(len: u32, t: u32, sg: u32, lane: u32, local_start: u32, base: u32) -> array<u32, KPT> {
    // The output index of local sorted position j (of this digit) is digit_dst[digit] + j.
    digit_dst[sg * 32u + lane] = base - local_start;
    workgroupBarrier();
    var dst: array<u32, KPT>;
    for (var k = 0u; k < KPT; k++) {
        let j = k * THREADS + t;
        dst[k] = 0u;
        if (j < len) {
            let key = staged[j];
            dst[k] = digit_dst[digit_of(key)] + j;
            keys_out[dst[k]] = key;
        }
    }
    workgroupBarrier();
    return dst;
}

// Writes the values staged in sorted order to the places their keys went.
fn write_vals(len: u32, t: u32, dst: array<u32, KPT>) {
    workgroupBarrier();
    for (var k = 0u; k < KPT; k++) {
        let j = k * THREADS + t;
        if (j < len) {
            vals_out[dst[k]] = staged[j];
        }
    }
}
