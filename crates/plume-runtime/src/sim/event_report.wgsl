// The gather of a reported event's firings (crate::sim::reports; the contract is
// plume_compiler::event_report's). After each step, one workgroup appends the step's firings,
// in the order the firing group's update appended them, to the report buffer, up to its bound,
// and counts them all. `gather_and_clear`, for an event with no target, also clears the
// firings' header for the next step, which the target group's spawn does otherwise.

struct EventRecord {
    x: vec3<f32>,
    tint: u32,
    v: vec4<f32>,
}

struct EventRecords {
    count: u32,
    not_min_id: u32,
    max_id: u32,
    pad: u32,
    records: array<EventRecord>,
}

// A kept firing: where it fired and its id, its velocity and the step (its low 32 bits).
struct Firing {
    x: vec3<f32>,
    id: u32,
    v: vec3<f32>,
    step: u32,
}

// Firings counted since the last readback (saturating), steps gathered since the effect
// started, the most firings kept, padding; then the kept firings.
struct Report {
    fired: u32,
    steps: u32,
    most: u32,
    pad: u32,
    firings: array<Firing>,
}

@group(0) @binding(0) var<storage, read> keys: array<u32>;
@group(0) @binding(1) var<storage, read> slots: array<u32>;
@group(0) @binding(2) var<storage, read_write> records: EventRecords;
@group(0) @binding(3) var<storage, read_write> report: Report;

// The step's firings, the firings counted before them, and the step.
var<workgroup> header: vec3<u32>;

fn gather_step(t: u32) {
    if (t == 0u) {
        header = vec3<u32>(records.count, report.fired, report.steps);
    }
    let h = workgroupUniformLoad(&header);
    let room = select(0u, report.most - h.y, h.y < report.most);
    let n = min(h.x, room);
    for (var i = t; i < n; i = i + 256u) {
        let r = records.records[slots[i]];
        report.firings[h.y + i] = Firing(r.x, keys[i], r.v.xyz, h.z);
    }
    if (t == 0u) {
        report.fired = select(0xffffffffu, h.y + h.x, h.y <= 0xffffffffu - h.x);
        report.steps = h.z + 1u;
    }
}

@compute @workgroup_size(256)
fn gather(@builtin(local_invocation_index) t: u32) {
    gather_step(t);
}

@compute @workgroup_size(256)
fn gather_and_clear(@builtin(local_invocation_index) t: u32) {
    gather_step(t);
    // The count was read into the workgroup's header before any thread went on.
    if (t == 0u) {
        records.count = 0u;
        records.not_min_id = 0u;
        records.max_id = 0u;
    }
}
