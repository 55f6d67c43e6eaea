// The radix sort's downsweep without subgroup operations (appended to radix.wgsl): a partition
// is taken as KPT tiles of 256 consecutive keys, in order. Each tile ranks its keys by sorting
// (digit, lane) in workgroup memory with a bitonic network (equal digits keep their lane order),
// then writes each key after the keys of its digit from earlier tiles and partitions.

var<workgroup> order: array<u32, 256>;
var<workgroup> tile_start: array<u32, 256>;
var<workgroup> digit_next: array<u32, 256>;

// Where the keys of digit `t` from partition `part` start in the output: the keys of every
// smaller digit, plus this digit's keys in earlier partitions. Every thread must call it.
fn partition_digit_base(t: u32, part: u32) -> u32 {
    let smaller = exclusive_scan_256(t, digit_totals[t]);
    var earlier = 0u;
    if (part < params.partitions) {
        earlier = pass_hist[t * params.partitions + part];
    }
    return smaller + earlier;
}

@compute @workgroup_size(256)
fn rs_downsweep(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) t: u32) {
    downsweep(wid, groups, t, plain_keys());
}

@compute @workgroup_size(256)
fn rs_downsweep_depth(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                      @builtin(local_invocation_index) t: u32) {
    downsweep(wid, groups, t, depth_keys_map());
}

fn downsweep(wid: vec3<u32>, groups: vec3<u32>, t: u32, map: KeyMap) {
    let part = partition_of(wid, groups);
    let len = partition_len(part);
    // Where the next key of digit t goes; advanced by each tile's count of digit t.
    digit_next[t] = partition_digit_base(t, part);
    let base = part * PART;
    for (var k = 0u; k < KPT; k++) {
        let local = k * THREADS + t;
        let valid = local < len;
        var digit = 255u;
        if (valid) {
            digit = digit_of(load_key(base + local, map));
        }
        atomicStore(&counts[t], 0u);
        workgroupBarrier();
        if (valid) {
            atomicAdd(&counts[digit], 1u);
        }
        // Invalid lanes sort last.
        order[t] = select(0xffffffffu, (digit << 8u) | t, valid);
        workgroupBarrier();
        let count = atomicLoad(&counts[t]);
        tile_start[t] = exclusive_scan_256(t, count);
        for (var size = 2u; size <= THREADS; size <<= 1u) {
            for (var j = size >> 1u; j > 0u; j >>= 1u) {
                let other = t ^ j;
                if (other > t) {
                    let a = order[t];
                    let b = order[other];
                    if ((a > b) == ((t & size) == 0u)) {
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
            let src = base + k * THREADS + (entry & 255u);
            let dst = digit_next[d] + (t - tile_start[d]);
            keys_out[dst] = load_key(src, map);
            vals_out[dst] = load_val(src, map);
        }
        workgroupBarrier();
        digit_next[t] += count;
    }
}
