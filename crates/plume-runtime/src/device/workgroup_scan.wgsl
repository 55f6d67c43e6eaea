// The 256-thread workgroup scan that every kernel placing work by counts shares: the radix
// sort's passes and its word scans (the compute renderer's tile lists and the flock grid's
// buckets scan through them), the events' bucket placement, and the compute renderer's
// additive lists. Hillis-Steele over `scan_buf`: eight rounds of two barriers. A module that
// uses it is built with this text before its own (`crate::device::gpu::WORKGROUP_SCAN`).

var<workgroup> scan_buf: array<u32, 256>;

// Inclusive prefix sum of `v` over the workgroup's 256 threads: thread t gets the sum of the
// values of threads 0..=t (thread 255 the workgroup's total). Every thread must call it (it
// has barriers).
fn inclusive_scan_256(t: u32, v: u32) -> u32 {
    workgroupBarrier();
    scan_buf[t] = v;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off <<= 1u) {
        var add = 0u;
        if (t >= off) {
            add = scan_buf[t - off];
        }
        workgroupBarrier();
        scan_buf[t] += add;
        workgroupBarrier();
    }
    return scan_buf[t];
}

// Exclusive prefix sum of `v` over the workgroup's 256 threads: the sum of threads 0..t.
// Every thread must call it.
fn exclusive_scan_256(t: u32, v: u32) -> u32 {
    return inclusive_scan_256(t, v) - v;
}
