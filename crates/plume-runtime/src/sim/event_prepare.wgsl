// The spawn of a stream's children, prepared by the first kernel of the stream's ordering
// (crate::sim::events; the ordering files follow this one in the module). The firings' count
// is known from the step's start, so one thread takes it there: it pops the child's free slots
// for as many children as fit, counts the rest as dropped and hands out the children's ids.
// A one-thread dispatch of the child's own for this would cost a dispatch's launch a stream a
// step. The child's `event_spawn` is a direct dispatch over a fixed grid whose threads stride
// over the children (an indirect one, its workgroups written here, would start later than a
// direct one; docs/performance.md, "Events", measures both). The records' header is cleared by
// the spawn's first thread, after every kernel of the ordering has read it.

// Whether this pipeline prepares the spawn (`plume bench` times the orderings alone, again and
// again over the same firings, with it off).
override PREPARE: bool = true;
// Children a firing asks for.
override CHILD_COUNT: u32 = 1u;
// Words of the child's counters (plume_compiler::wgsl::COUNTER_FIELDS).
override FREE_COUNT: u32 = 0u;
override SPAWN_BASE: u32 = 1u;
override SPAWN_COUNT: u32 = 2u;
override SPAWNED: u32 = 3u;
override DROPPED: u32 = 4u;
override NEXT_ID: u32 = 6u;
override EVENT_FIRST_ID: u32 = 7u;

// The child group's counters.
@group(0) @binding(10) var<storage, read_write> child_counters: array<atomic<u32>>;

// The counters the preparation reads (free slots, next id), loaded by the kernel's first thread
// at its start, so that their latency passes under the ordering's own work.
fn prepare_loads() -> vec2<u32> {
    if (!PREPARE) {
        return vec2<u32>(0u);
    }
    return vec2<u32>(atomicLoad(&child_counters[FREE_COUNT]), atomicLoad(&child_counters[NEXT_ID]));
}

// One thread, at the kernel's end: `fired` firings of the last step ask for CHILD_COUNT
// children each; `loaded` is what `prepare_loads` read (no other kernel of the dispatch writes
// the child's counters).
fn prepare_spawn(fired: u32, loaded: vec2<u32>) {
    if (!PREPARE) {
        return;
    }
    let requested = fired * CHILD_COUNT;
    let free = loaded.x;
    let n = min(requested, free);
    atomicStore(&child_counters[FREE_COUNT], free - n);
    atomicStore(&child_counters[SPAWN_BASE], free - n);
    atomicStore(&child_counters[SPAWN_COUNT], n);
    atomicAdd(&child_counters[SPAWNED], n);
    atomicAdd(&child_counters[DROPPED], requested - n);
    atomicStore(&child_counters[EVENT_FIRST_ID], loaded.y);
    atomicStore(&child_counters[NEXT_ID], loaded.y + requested);
}
