// The order of an event's firings by buckets (crate::sim::events, Ordering::Bucketed): a stream
// compaction in id order, with no sort, in three dispatches. The firing group's update appended
// (id, slot) pairs to `keys`/`vals` in whatever order its threads ran, counted them, and noted
// the complement of the smallest id and the largest id in the records' header. At the next
// step's start, one of two ways by the range of the ids (n = the firing group's slots):
//
// While the ids span fewer than 32 n, one bit an id (`shift` 0): the n words are a bitmap.
//   bucket_count:      each firing sets its id's bit (atomicOr) and counts itself in its
//                      word's quad (4 words) and in its word's group (a run of quads: at most
//                      GROUPS groups cover the words). Its first thread also prepares the
//                      children's spawn (event_prepare.wgsl, before this file): the child's
//                      counters read at its start, written at its end.
//   bucket_place:      each workgroup scans the groups' counts in workgroup memory; a firing's
//                      place is its group's start, plus the firings of its group's quads before
//                      its quad, of its quad's words before its word, and the bits below its
//                      own in the word: order[place] = slot.
//   bucket_rank:       clears the words and the groups' counts (no one reads them after the
//                      place).
// Past that, buckets of 2^shift ids (the least shift that fits the ids' range into n buckets),
// which a word each counts:
//   bucket_count:      each firing counts itself in its bucket (its place among the bucket's
//                      firings, in whatever order threads ran), its quad and its group.
//   bucket_place:      the same scan gives the bucket's run; the firing is staged there and
//                      the run noted in `runs`.
//   bucket_rank:       each staged firing's rank is its run's start plus the staged ids of the
//                      run smaller than its own; the counts are cleared.
//
// The words' counts are not scanned across the device (a reduce and a scan of blocks of 2,048
// words, five dispatches, one word an id): each dispatch costs its launch before any work, and
// the step with those scans was slower for fireworks' sparks and rain's drops at 10M slots
// (docs/performance.md, "Events").
// The work follows the firings and the range of their ids, not the group's slots: each kernel
// is dispatched on a fixed grid (at most 256 workgroups) whose threads stride over this
// step's firings, so that a step with few firings launches few threads. Ids are unique, so a
// bucket of width 2^shift holds at most 2^shift firings, and at most as many as fired: the
// ranking's comparisons stay below n * 2^32 / n = 2^32 in the worst case.
// Every word and group count is zero again for the next step.

const THREADS: u32 = 256u;
// The most groups of words (their counts scanned by every workgroup of bucket_place).
const GROUPS: u32 = 2048u;
// GROUPS = THREADS * PER_THREAD: each thread scans 8 groups.
const PER_THREAD: u32 = 8u;
// Words a quad count covers: 1 << QUAD_SHIFT.
const QUAD_SHIFT: u32 = 2u;

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
// n words: a bit an id, or a bucket's count (zero between steps).
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
// GROUPS groups' counts, then a count for every 4 words (zero between steps).
@group(0) @binding(5) var<storage, read_write> group_counts: array<atomic<u32>>;
// Each firing's place in its bucket (wider buckets only).
@group(0) @binding(6) var<storage, read_write> within: array<u32>;
// The firings (id, slot) staged by bucket (wider buckets only).
@group(0) @binding(7) var<storage, read_write> staged: array<vec2<u32>>;
// Each bucket's run of staged firings, first and end (wider buckets only).
@group(0) @binding(8) var<storage, read_write> runs: array<vec2<u32>>;

// This step's firings and their words: with shift 0 a word holds 32 ids' bits, otherwise it
// is the count of a bucket of 2^shift ids. A group counts 2^group_shift words (at least a
// quad's 4).
struct Window {
    count: u32,
    min_id: u32,
    shift: u32,
    words: u32,
    group_shift: u32,
}

var<workgroup> shared_window: Window;
// The groups' starts (bucket_place).
var<workgroup> group_starts: array<u32, GROUPS>;
// bucket_count's windows: 256 words' bits, then 256 quads' and 256 groups' counts, from the
// first words, quads and groups in `shared_bases`.
var<workgroup> local_words: array<atomic<u32>, THREADS>;
var<workgroup> local_counts: array<atomic<u32>, 512>;
var<workgroup> shared_bases: vec3<u32>;

fn window_of(h: Header) -> Window {
    if (h.count == 0u) {
        return Window(0u, 0u, 0u, 0u, 0u);
    }
    let min_id = ~h.not_min_id;
    let spread = h.max_id - min_id;
    let n = arrayLength(&counts);
    var shift = 0u;
    var words = (spread >> 5u) + 1u;
    if ((spread >> 5u) >= n) {
        shift = 6u;
        while (shift < 31u && (spread >> shift) >= n) {
            shift += 1u;
        }
        words = (spread >> shift) + 1u;
    }
    var group_shift = QUAD_SHIFT;
    while (((words - 1u) >> group_shift) >= GROUPS) {
        group_shift += 1u;
    }
    return Window(h.count, min_id, shift, words, group_shift);
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

// A firing's word: its bit's word (shift 0), or its bucket.
fn word_of(w: Window, id: u32) -> u32 {
    return (id - w.min_id) >> select(w.shift, 5u, w.shift == 0u);
}

// What a word adds to the scan: its bits set, or its bucket's count.
fn word_total(w: Window, at: u32) -> u32 {
    let v = atomicLoad(&counts[at]);
    return select(v, countOneBits(v), w.shift == 0u);
}

fn flat(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

fn workgroups(groups: vec3<u32>) -> u32 {
    return groups.x * groups.y;
}

// `exclusive_scan_256` is the shared workgroup scan (device/workgroup_scan.wgsl).

// Counts `amount` at `at`: of the words (`array` 0, bits or'd) or of the group counts (1: a
// quad's, 2: a group's, added), through the workgroup's window of THREADS entries from `base`
// (`local_words`, or the first or second half of `local_counts`), or straight into the array
// where `at` lies outside the window.
fn count_local(array: u32, at: u32, base: u32, amount: u32) {
    let offset = at - base;
    if (offset < THREADS) {
        if (array == 0u) {
            atomicOr(&local_words[offset], amount);
        } else {
            atomicAdd(&local_counts[offset + (array - 1u) * THREADS], amount);
        }
    } else if (array == 0u) {
        atomicOr(&counts[at], amount);
    } else {
        atomicAdd(&group_counts[at], amount);
    }
}

// Each firing's bit (or its bucket's count), its quad's count and its group's. A workgroup
// gathers its 256 firings' in workgroup memory first, in windows of 256 entries around its
// first firing's, and adds each window entry it used to the arrays once: the firings of one
// parent's cohort have consecutive ids, and their atomics on the same few words serialised
// when each firing made its three global atomics itself.
@compute @workgroup_size(256)
fn bucket_count(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lane: u32) {
    let first0 = flat(wid, groups) * THREADS;
    // The first round's key, loaded with the header (not after it: one latency, not two);
    // past the count it is not used.
    let key0 = keys[min(first0 + lane, arrayLength(&keys) - 1u)];
    let w = uniform_window(lane);
    let preparer = first0 == 0u && lane == 0u;
    var loaded = vec2<u32>(0u);
    if (preparer) {
        loaded = prepare_loads();
    }
    for (var first = first0; first < w.count; first += workgroups(groups) * THREADS) {
        let k = first + lane;
        let live = k < w.count;
        var word = 0u;
        var bit = 0u;
        if (live) {
            var id = key0;
            if (first != first0) {
                id = keys[k];
            }
            word = word_of(w, id);
            bit = 1u << ((id - w.min_id) & 31u);
        }
        if (lane == 0u) {
            // Windows centred on the first firing's entries: the ids may run either way.
            let at = vec3<u32>(word, word >> QUAD_SHIFT, word >> w.group_shift);
            shared_bases = at - min(at, vec3<u32>(THREADS / 2u));
        }
        let bases = workgroupUniformLoad(&shared_bases);
        if (live) {
            if (w.shift == 0u) {
                count_local(0u, word, bases.x, bit);
            } else {
                within[k] = atomicAdd(&counts[word], 1u);
            }
            count_local(1u, GROUPS + (word >> QUAD_SHIFT), GROUPS + bases.y, 1u);
            count_local(2u, word >> w.group_shift, bases.z, 1u);
        }
        workgroupBarrier();
        let bits = atomicExchange(&local_words[lane], 0u);
        if (bits != 0u) {
            atomicOr(&counts[bases.x + lane], bits);
        }
        let quads = atomicExchange(&local_counts[lane], 0u);
        if (quads != 0u) {
            atomicAdd(&group_counts[GROUPS + bases.y + lane], quads);
        }
        let in_group = atomicExchange(&local_counts[THREADS + lane], 0u);
        if (in_group != 0u) {
            atomicAdd(&group_counts[bases.z + lane], in_group);
        }
    }
    if (preparer) {
        prepare_spawn(w.count, loaded);
    }
}

// A firing's place, but for its group's start: the firings of its group before it.
struct Firing {
    // Its id's word (shift 0) or bucket.
    word: u32,
    // The firings of its group's quads before its quad, of its quad's words before its word,
    // and (shift 0) of its word's bits below its own.
    partial: u32,
    // Its slot.
    slot: u32,
    // Its bucket's count (shift above 0).
    bucket: u32,
}

fn firing_at(w: Window, k: u32) -> Firing {
    return firing_of(w, keys[k], vals[k]);
}

// The firing of `id` in `slot`.
fn firing_of(w: Window, id: u32, slot: u32) -> Firing {
    let word = word_of(w, id);
    let quad = word >> QUAD_SHIFT;
    var partial = 0u;
    for (var q = (word >> w.group_shift) << (w.group_shift - QUAD_SHIFT); q < quad; q++) {
        partial += atomicLoad(&group_counts[GROUPS + q]);
    }
    for (var at = quad << QUAD_SHIFT; at < word; at++) {
        partial += word_total(w, at);
    }
    let own = atomicLoad(&counts[word]);
    if (w.shift == 0u) {
        partial += countOneBits(own & ((1u << ((id - w.min_id) & 31u)) - 1u));
    }
    return Firing(word, partial, slot, own);
}

fn place_firing(w: Window, k: u32, f: Firing) {
    let start = group_starts[f.word >> w.group_shift] + f.partial;
    if (w.shift == 0u) {
        order[start] = f.slot;
    } else {
        staged[start + within[k]] = vec2<u32>(keys[k], f.slot);
        // Every firing of the bucket notes the same run.
        runs[f.word] = vec2<u32>(start, start + f.bucket);
    }
}

@compute @workgroup_size(256)
fn bucket_place(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lane: u32) {
    let first_firing = flat(wid, groups) * THREADS;
    let k0 = first_firing + lane;
    // The first firing's id and slot, loaded with the header (one latency, not two); past
    // the count they are not used.
    let id0 = keys[min(k0, arrayLength(&keys) - 1u)];
    let slot0 = vals[min(k0, arrayLength(&vals) - 1u)];
    let w = uniform_window(lane);
    if (first_firing >= w.count) {
        return;
    }
    // The first firing's loads are issued before the scan below, so that they wait together.
    var f0 = Firing(0u, 0u, 0u, 0u);
    if (k0 < w.count) {
        f0 = firing_of(w, id0, slot0);
    }
    // Every group's start, in workgroup memory: a few thousand words read from L2 by each
    // workgroup, where a scan of its own would cost a dispatch.
    let used = ((w.words - 1u) >> w.group_shift) + 1u;
    var mine: array<u32, PER_THREAD>;
    var sum = 0u;
    for (var j = 0u; j < PER_THREAD; j++) {
        let g = lane * PER_THREAD + j;
        mine[j] = 0u;
        if (g < used) {
            mine[j] = atomicLoad(&group_counts[g]);
        }
        sum += mine[j];
    }
    var run = exclusive_scan_256(lane, sum);
    for (var j = 0u; j < PER_THREAD; j++) {
        group_starts[lane * PER_THREAD + j] = run;
        run += mine[j];
    }
    workgroupBarrier();
    if (k0 < w.count) {
        place_firing(w, k0, f0);
    }
    let stride = workgroups(groups) * THREADS;
    for (var k = k0 + stride; k < w.count; k += stride) {
        place_firing(w, k, firing_at(w, k));
    }
}

@compute @workgroup_size(256)
fn bucket_rank(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
               @builtin(local_invocation_index) lane: u32) {
    let w = window();
    let first = flat(wid, groups) * THREADS + lane;
    let stride = workgroups(groups) * THREADS;
    // A bit an id, with fewer words than firings: the words, quads and groups in use are
    // cleared in turn, a store each, rather than by each firing (the firings of one word or
    // group storing to it together were slower for fireworks' sparks).
    if (w.shift == 0u && w.words <= w.count) {
        for (var at = first; at < w.words; at += stride) {
            atomicStore(&counts[at], 0u);
            if ((at & ((1u << QUAD_SHIFT) - 1u)) == 0u) {
                atomicStore(&group_counts[GROUPS + (at >> QUAD_SHIFT)], 0u);
            }
            if ((at & ((1u << w.group_shift) - 1u)) == 0u) {
                atomicStore(&group_counts[at >> w.group_shift], 0u);
            }
        }
        return;
    }
    for (var q = first; q < w.count; q += stride) {
        // Every firing clears its word, its quad and its group (no one reads them from here on).
        let word = word_of(w, keys[q]);
        atomicStore(&counts[word], 0u);
        atomicStore(&group_counts[GROUPS + (word >> QUAD_SHIFT)], 0u);
        atomicStore(&group_counts[word >> w.group_shift], 0u);
        if (w.shift == 0u) {
            continue;
        }
        let mine = staged[q];
        let run = runs[word_of(w, mine.x)];
        var rank = run.x;
        for (var m = run.x; m < run.y; m++) {
            rank += select(0u, 1u, staged[m].x < mine.x);
        }
        order[rank] = mine.y;
    }
}
