// OneSweep (Adinets and Merrill 2022), appended to radix.wgsl and radix_subgroup.wgsl: one
// dispatch per 8-bit pass instead of three, for adapters that let a workgroup wait on one that
// started before it (the runtime allows it on NVIDIA only: neither WebGPU nor Vulkan promises
// such forward progress).
//
//   rs_sweep_clear:      zeroes the digit counts of every pass and the partition tickets.
//   rs_sweep_histogram:  counts every pass's digits over all the keys at once (one read of the
//                        keys for every pass, where reduce-then-scan reads them again each
//                        pass), and zeroes the partitions' look-back words.
//   rs_sweep_offsets:    each pass's digit counts to where each digit's keys start.
//   rs_sweep:            per pass, per partition: takes the next partition ticket (so every
//                        partition before it has started), ranks its keys as rs_downsweep
//                        does, publishes its count of each digit, looks back over the
//                        partitions before it for their counts (decoupled look-back), publishes
//                        the inclusive count for the partitions after it, and scatters.
//
// The output is the reduce-then-scan sort's, bit for bit: both are stable, and a partition's
// keys go where the counts of the keys before them say.

// Per pass: 256 digit counts, then (scanned) where each digit's keys start.
@group(0) @binding(8) var<storage, read_write> sweep_hist: array<atomic<u32>>;
// Per pass, partition and digit: 0 until the partition publishes; then its count of the digit
// with FLAG_AGGREGATE, or the count of the digit in it and every partition before it with
// FLAG_INCLUSIVE.
@group(0) @binding(9) var<storage, read_write> sweep_status: array<atomic<u32>>;
// Per pass: the next partition ticket.
@group(0) @binding(10) var<storage, read_write> sweep_next: array<atomic<u32>>;

const FLAG_AGGREGATE: u32 = 0x40000000u;
const FLAG_INCLUSIVE: u32 = 0x80000000u;
const COUNT_BITS: u32 = 0x3fffffffu;
// Partitions one workgroup of rs_sweep_histogram counts (one atomic per digit and pass each
// workgroup on the global counts).
const HIST_PARTS: u32 = 4u;

var<workgroup> sweep_ticket: u32;

// The pass a dispatch runs (its shift is 8 bits a pass).
fn sweep_pass() -> u32 {
    return params.shift / 8u;
}

@compute @workgroup_size(256)
fn rs_sweep_clear(@builtin(local_invocation_index) t: u32) {
    for (var j = t; j < arrayLength(&sweep_hist); j += THREADS) {
        atomicStore(&sweep_hist[j], 0u);
    }
    if (t < arrayLength(&sweep_next)) {
        atomicStore(&sweep_next[t], 0u);
    }
}

@compute @workgroup_size(256)
fn rs_sweep_histogram(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                      @builtin(local_invocation_index) t: u32) {
    sweep_histogram(wid, groups, t, plain_keys());
}

@compute @workgroup_size(256)
fn rs_sweep_histogram_depth(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                            @builtin(local_invocation_index) t: u32) {
    sweep_histogram(wid, groups, t, depth_keys_map());
}

fn sweep_histogram(wid: vec3<u32>, groups: vec3<u32>, t: u32, map: KeyMap) {
    let passes = arrayLength(&sweep_next);
    // sub_counts (radix_subgroup.wgsl's per-subgroup counters) holds pass p's digit d at
    // p * 256 + d here.
    for (var j = t; j < 4u * 256u; j += THREADS) {
        atomicStore(&sub_counts[j], 0u);
    }
    workgroupBarrier();
    let first_part = partition_of(wid, groups) * HIST_PARTS;
    for (var q = 0u; q < HIST_PARTS; q++) {
        let part = first_part + q;
        if (part < params.partitions) {
            for (var p = 0u; p < passes; p++) {
                atomicStore(&sweep_status[(p * params.partitions + part) * 256u + t], 0u);
            }
        }
        var keys: array<u32, KPT>;
        for (var k = 0u; k < KPT; k++) {
            let i = part * PART + k * THREADS + t;
            keys[k] = 0xffffffffu;
            if (part < params.partitions && i < params.n) {
                keys[k] = load_key(i, map);
            }
        }
        for (var k = 0u; k < KPT; k++) {
            let i = part * PART + k * THREADS + t;
            if (part < params.partitions && i < params.n) {
                for (var p = 0u; p < passes; p++) {
                    atomicAdd(&sub_counts[p * 256u + ((keys[k] >> (8u * p)) & 255u)], 1u);
                }
            }
        }
    }
    workgroupBarrier();
    for (var p = 0u; p < passes; p++) {
        let c = atomicLoad(&sub_counts[p * 256u + t]);
        if (c > 0u) {
            atomicAdd(&sweep_hist[p * 256u + t], c);
        }
    }
}

// One workgroup: each pass's digit counts to exclusive starts, in place.
@compute @workgroup_size(256)
fn rs_sweep_offsets(@builtin(local_invocation_index) t: u32) {
    let passes = arrayLength(&sweep_next);
    for (var p = 0u; p < passes; p++) {
        let count = atomicLoad(&sweep_hist[p * 256u + t]);
        let start = exclusive_scan_256(t, count);
        atomicStore(&sweep_hist[p * 256u + t], start);
    }
}

@compute @workgroup_size(256)
fn rs_sweep(@builtin(local_invocation_index) t: u32,
            @builtin(subgroup_id) sg: u32,
            @builtin(subgroup_invocation_id) lane: u32) {
    sweep(t, sg, lane, plain_keys());
}

@compute @workgroup_size(256)
fn rs_sweep_depth(@builtin(local_invocation_index) t: u32,
                  @builtin(subgroup_id) sg: u32,
                  @builtin(subgroup_invocation_id) lane: u32) {
    sweep(t, sg, lane, depth_keys_map());
}

fn sweep(t: u32, sg: u32, lane: u32, map: KeyMap) {
    let this_pass = sweep_pass();
    // Partitions in the order workgroups start, not the order of their ids: a partition waits
    // only on partitions whose workgroups are already running.
    if (t == 0u) {
        sweep_ticket = atomicAdd(&sweep_next[this_pass], 1u);
    }
    let part = workgroupUniformLoad(&sweep_ticket);
    // A 2D grid (past 65,535 partitions) may hold more workgroups than partitions: the tickets
    // past the last partition have nothing to sort and must publish nothing (their look-back
    // words would land in the next pass's).
    if (part >= params.partitions) {
        return;
    }
    let len = partition_len(part);
    let ranked = rank_partition(part, len, t, sg, lane, map);
    let digit = sg * 32u + lane;
    let row = this_pass * params.partitions;
    // This partition's counts for the partitions after it, before anything else.
    if (part == 0u) {
        atomicStore(&sweep_status[row * 256u + digit], FLAG_INCLUSIVE | ranked.total);
    } else {
        atomicStore(&sweep_status[(row + part) * 256u + digit], FLAG_AGGREGATE | ranked.total);
    }
    // The keys in sorted order in workgroup memory, while the partitions before finish theirs.
    let pos = stage_partition(len, t, sg, lane, ranked);
    // And the values on their way from memory.
    let vals = load_vals(part, len, sg, lane, map);
    var before = 0u;
    if (part > 0u) {
        // Back over the partitions before this one until one has published its inclusive count
        // (partition 0 always does).
        var j = part - 1u;
        loop {
            let word = atomicLoad(&sweep_status[(row + j) * 256u + digit]);
            if (word == 0u) {
                // Not published yet: its workgroup is running (it took an earlier ticket).
                continue;
            }
            before += word & COUNT_BITS;
            if ((word & FLAG_INCLUSIVE) != 0u) {
                break;
            }
            j -= 1u;
        }
        atomicStore(
            &sweep_status[(row + part) * 256u + digit],
            FLAG_INCLUSIVE | (before + ranked.total)
        );
    }
    let base = atomicLoad(&sweep_hist[this_pass * 256u + digit]) + before;
    write_partition_loaded(len, t, sg, lane, ranked.local_start, pos, base, vals);
}
