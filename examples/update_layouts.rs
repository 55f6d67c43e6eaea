//! How should the update read a 32-byte particle? This experiment runs the same update
//! (x += v dt, v += g dt on two 16-byte words per particle, read and written in place) over N
//! particles with several memory layouts and access patterns, in one run, beside the copy
//! kernel that `plume bench` compares with, and prints each kernel's time per pass and its
//! ratio to the copy (copy time / its time):
//!
//! - `copy`: `plume bench`'s copy kernel (16 bytes a thread, one buffer to another);
//! - `copy in place`: the same words read and written back to one buffer;
//! - `aos direct`: particle-major words (particle i's words at 2i, 2i + 1), each thread loading
//!   its own particle: a warp's load touches every other 16 bytes of 1 KiB;
//! - `aos staged`: the same layout staged through workgroup memory (consecutive lanes move
//!   consecutive words, barrier, update, barrier, write back): what `update` emitted before;
//! - `aos shuffled`: the same layout, consecutive lanes loading consecutive words and
//!   exchanging them with subgroup shuffles instead of workgroup memory and barriers (only
//!   where every subgroup has 32 invocations);
//! - `word-major`: word k of particle i at k · N + i, each thread loading its own particle's
//!   words: every load and store of a warp covers 512 contiguous bytes, with no barrier.
//!
//! The copy also runs on zeros and on particles that are all alike (is the copy's speed the
//! data's?), and at the end on three more pairs of buffers in turn with the first (is it where
//! the buffers landed, or when the kernel ran?). Each figure is the fastest of 9 timed passes of
//! 20 dispatches (the GPU's bandwidth switches between two levels for seconds at a time, so the
//! fastest compares kernels at the same level), with the median and slowest beside it. Every variant's result is checked
//! against the CPU's. `cargo run --release --example update_layouts [N,N,...]`
//! (docs/performance.md, "The update at large sizes").

use plume::runtime::bench::{self, read_buffer, PassTimer};
use plume::runtime::{Gpu, GpuChoice};
use wgpu::util::DeviceExt;

const COMMON: &str = r#"
@group(0) @binding(0) var<storage, read_write> src: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> dst: array<vec4<u32>>;
struct Params { n: u32, pad0: u32, pad1: u32, pad2: u32 }
@group(0) @binding(2) var<uniform> params: Params;

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WG;
}

// The particle's two words after one step: position and id in the first, velocity in the
// second.
fn step_words(w: array<vec4<u32>, 2>) -> array<vec4<u32>, 2> {
    let dt = 0.01;
    let x = bitcast<vec3<f32>>(w[0].xyz);
    let v = bitcast<vec3<f32>>(w[1].xyz);
    let v2 = v + vec3<f32>(0.0, -9.81, 0.0) * dt;
    let x2 = x + v2 * dt;
    return array<vec4<u32>, 2>(vec4<u32>(bitcast<vec3<u32>>(x2), w[0].w), vec4<u32>(bitcast<vec3<u32>>(v2), w[1].w));
}

@compute @workgroup_size(WG)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if (i < 2u * params.n) { dst[i] = src[i]; }
}

@compute @workgroup_size(WG)
fn copy_in_place(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if (i < 2u * params.n) { src[i] = src[i] + vec4<u32>(1u); }
}

@compute @workgroup_size(WG)
fn aos_direct(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if (i >= params.n) { return; }
    let w = step_words(array<vec4<u32>, 2>(src[2u * i], src[2u * i + 1u]));
    src[2u * i] = w[0];
    src[2u * i + 1u] = w[1];
}

var<workgroup> staged: array<vec4<u32>, 2 * WG>;

@compute @workgroup_size(WG)
fn aos_staged(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) lane: u32) {
    let i = index(gid, groups);
    let first = (i - lane) * 2u;
    let words = params.n * 2u;
    for (var r = 0u; r < 2u; r++) {
        let k = r * WG + lane;
        if (first + k < words) { staged[k] = src[first + k]; }
    }
    workgroupBarrier();
    if (i < params.n) {
        let w = step_words(array<vec4<u32>, 2>(staged[2u * lane], staged[2u * lane + 1u]));
        staged[2u * lane] = w[0];
        staged[2u * lane + 1u] = w[1];
    }
    workgroupBarrier();
    for (var r = 0u; r < 2u; r++) {
        let k = r * WG + lane;
        if (first + k < words) { src[first + k] = staged[k]; }
    }
}

@compute @workgroup_size(WG)
fn word_major(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if (i >= params.n) { return; }
    let w = step_words(array<vec4<u32>, 2>(src[i], src[params.n + i]));
    src[i] = w[0];
    src[params.n + i] = w[1];
}
"#;

/// The shuffled variant, in a module of its own (it needs the subgroup feature).
const SHUFFLED: &str = r#"
@compute @workgroup_size(WG)
fn aos_shuffled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(subgroup_invocation_id) lane: u32) {
    let i = index(gid, groups);
    // The subgroup's 32 particles are 64 consecutive words: lane l loads words l and 32 + l.
    let first = (i - lane) * 2u;
    let words = params.n * 2u;
    var a = vec4<u32>(0u);
    var b = vec4<u32>(0u);
    if (first + lane < words) { a = src[first + lane]; }
    if (first + 32u + lane < words) { b = src[first + 32u + lane]; }
    // Particle `lane` holds words 2 lane and 2 lane + 1.
    let lo = (2u * lane) & 31u;
    let hi = (2u * lane + 1u) & 31u;
    let in_a = lane < 16u;
    let w0 = select(subgroupShuffle(b, lo), subgroupShuffle(a, lo), in_a);
    let w1 = select(subgroupShuffle(b, hi), subgroupShuffle(a, hi), in_a);
    var n = array<vec4<u32>, 2>(w0, w1);
    if (i < params.n) { n = step_words(array<vec4<u32>, 2>(w0, w1)); }
    // Word `lane` is word lane % 2 of particle lane / 2; word 32 + lane of particle 16 + lane / 2.
    let n0a = subgroupShuffle(n[0], lane / 2u);
    let n1a = subgroupShuffle(n[1], lane / 2u);
    let n0b = subgroupShuffle(n[0], 16u + lane / 2u);
    let n1b = subgroupShuffle(n[1], 16u + lane / 2u);
    let odd = (lane & 1u) == 1u;
    if (first + lane < words) { src[first + lane] = select(n0a, n1a, odd); }
    if (first + 32u + lane < words) { src[first + 32u + lane] = select(n0b, n1b, odd); }
}
"#;

/// The CPU's result of `steps` updates of particle `i` (f32, as the kernels compute it).
fn expected(i: u32, steps: u32) -> [f32; 6] {
    let (mut x, mut v) = initial(i);
    for _ in 0..steps {
        v[1] += -9.81 * 0.01;
        for k in 0..3 {
            x[k] += v[k] * 0.01;
        }
    }
    [x[0], x[1], x[2], v[0], v[1], v[2]]
}

fn initial(i: u32) -> ([f32; 3], [f32; 3]) {
    // Scattered values, as real particles' are (a buffer of equal or zero words can move
    // faster than real data on GPUs that compress memory).
    let u = |k: u32| (pcg(i.wrapping_mul(8).wrapping_add(k)) >> 8) as f32 / 16_777_216.0;
    (
        [10.0 * u(0) - 5.0, 10.0 * u(1), 10.0 * u(2) - 5.0],
        [2.0 * u(3) - 1.0, 5.0 + u(4), u(5) - 0.5],
    )
}

fn pcg(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The particles' words in particle-major (`word_major == false`) or word-major order.
fn words(n: u32, word_major: bool) -> Vec<[u32; 4]> {
    let mut out = vec![[0u32; 4]; 2 * n as usize];
    for i in 0..n {
        let (x, v) = initial(i);
        let w0 = [x[0].to_bits(), x[1].to_bits(), x[2].to_bits(), i];
        let w1 = [v[0].to_bits(), v[1].to_bits(), v[2].to_bits(), 0];
        let (a, b) = if word_major {
            (i as usize, (n + i) as usize)
        } else {
            (2 * i as usize, 2 * i as usize + 1)
        };
        out[a] = w0;
        out[b] = w1;
    }
    out
}

/// What a buffer holds before the kernels run.
#[derive(Clone, Copy, PartialEq)]
enum Fill {
    /// The particles (particle-major or word-major).
    Particles,
    /// Zeros.
    Zero,
    /// Every particle the same but for its id (what `plume bench` spawns for update-floor.ron).
    Equal,
}

struct Variant {
    name: &'static str,
    fill: Fill,
    entry: &'static str,
    word_major: bool,
    /// Threads per particle word (the copies) or per particle.
    threads_per_particle: u32,
    subgroups: bool,
}

const VARIANTS: [Variant; 10] = [
    Variant {
        name: "copy",
        fill: Fill::Particles,
        entry: "copy",
        word_major: false,
        threads_per_particle: 2,
        subgroups: false,
    },
    Variant {
        name: "copy of zeros",
        fill: Fill::Zero,
        entry: "copy",
        word_major: false,
        threads_per_particle: 2,
        subgroups: false,
    },
    Variant {
        name: "copy of equal particles",
        fill: Fill::Equal,
        entry: "copy",
        word_major: false,
        threads_per_particle: 2,
        subgroups: false,
    },
    Variant {
        name: "copy in place",
        fill: Fill::Particles,
        entry: "copy_in_place",
        word_major: false,
        threads_per_particle: 2,
        subgroups: false,
    },
    Variant {
        name: "aos direct",
        fill: Fill::Particles,
        entry: "aos_direct",
        word_major: false,
        threads_per_particle: 1,
        subgroups: false,
    },
    Variant {
        name: "aos staged",
        fill: Fill::Particles,
        entry: "aos_staged",
        word_major: false,
        threads_per_particle: 1,
        subgroups: false,
    },
    Variant {
        name: "aos staged, equal particles",
        fill: Fill::Equal,
        entry: "aos_staged",
        word_major: false,
        threads_per_particle: 1,
        subgroups: false,
    },
    Variant {
        name: "aos shuffled",
        fill: Fill::Particles,
        entry: "aos_shuffled",
        word_major: false,
        threads_per_particle: 1,
        subgroups: true,
    },
    Variant {
        name: "word-major",
        fill: Fill::Particles,
        entry: "word_major",
        word_major: true,
        threads_per_particle: 1,
        subgroups: false,
    },
    Variant {
        name: "copy (again)",
        fill: Fill::Particles,
        entry: "copy",
        word_major: false,
        threads_per_particle: 2,
        subgroups: false,
    },
];

fn main() {
    let gpu = Gpu::new(&GpuChoice::default()).unwrap_or_else(|e| panic!("{e}"));
    let device = &gpu.device;
    let timer = PassTimer::new(&gpu);
    let shuffles = gpu.has_subgroups_of(32);
    println!("{}", gpu.describe());
    let sizes: Vec<u32> = std::env::args()
        .nth(1)
        .map(|s| {
            s.split(',')
                .map(|n| n.parse().expect("sizes: comma-separated counts"))
                .collect()
        })
        .unwrap_or_else(|| vec![1 << 20, 10_000_000, 1 << 24, 60_000_000]);
    let repeats = 20u32;
    let storage = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[
            storage(0),
            storage(1),
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bind_layout)],
        immediate_size: 0,
    });
    for wg in [256u32] {
        let mut source = format!("const WG: u32 = {wg}u;\n{COMMON}");
        if shuffles {
            source = format!("{source}{SHUFFLED}");
        }
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("update layouts"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        for &n in &sizes {
            let bytes = u64::from(n) * 32;
            if bytes > gpu.limits.max_storage_buffer_binding_size {
                println!("{n}: {bytes} bytes is past this adapter's binding limit; skipped");
                continue;
            }
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: &[n.to_le_bytes(), [0; 4], [0; 4], [0; 4]].concat(),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let make = |label| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: bytes,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            // One pair of buffers for every variant, so that they all stream the same memory.
            let (src, dst) = (make("src"), make("dst"));
            let bind = |src: &wgpu::Buffer, dst: &wgpu::Buffer| {
                bench::bind_buffers(
                    &gpu,
                    "layouts",
                    &bind_layout,
                    &[(0, src), (1, dst), (2, &params)],
                )
            };
            let group = bind(&src, &dst);
            let time = |pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, threads: u64| {
                let (x, y) = bench::grid(&gpu, threads, u64::from(wg)).expect("grid");
                let record = |pass: &mut wgpu::ComputePass<'_>, k: u32| {
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, group, &[]);
                    for _ in 0..k {
                        pass.dispatch_workgroups(x, y, 1);
                    }
                    Ok(())
                };
                timer.time(|pass| record(pass, 1)).expect("warm-up");
                let mut times: Vec<f64> = (0..9)
                    .map(|_| {
                        timer.time(|pass| record(pass, repeats)).expect("time") / f64::from(repeats)
                    })
                    .collect();
                times.sort_by(f64::total_cmp);
                (times[0], times[4], times[8])
            };
            let mut copy_seconds = 0.0;
            println!("wg {wg:>3}  n {n:>10}");
            for v in &VARIANTS {
                if v.subgroups && !shuffles {
                    println!("    {:<28} -", v.name);
                    continue;
                }
                let init = match v.fill {
                    Fill::Particles => words(n, v.word_major),
                    Fill::Zero => vec![[0; 4]; 2 * n as usize],
                    Fill::Equal => (0..n)
                        .flat_map(|i| [[0, 0, 0, i], [0, 1f32.to_bits(), 0, 0]])
                        .collect(),
                };
                let init: Vec<u8> = init
                    .iter()
                    .flatten()
                    .flat_map(|w| w.to_le_bytes())
                    .collect();
                gpu.queue.write_buffer(&src, 0, &init);
                gpu.queue.write_buffer(&dst, 0, &init);
                let pipeline =
                    bench::compute_pipeline(&gpu, &module, v.entry, Some(&pipeline_layout));
                let threads = u64::from(n) * u64::from(v.threads_per_particle);
                let (seconds, median, slowest) = time(&pipeline, &group, threads);
                if v.name == "copy" {
                    copy_seconds = seconds;
                }
                let steps = 1 + 9 * repeats;
                let check = if v.threads_per_particle == 1 && v.fill == Fill::Particles {
                    check(&gpu, &src, n, steps, v.word_major)
                } else {
                    String::new()
                };
                println!(
                    "    {:<28} {:>8.4} ms (median {:.4}, slowest {:.4})  {:>6.3} of the copy  {:>6.0} GB/s{check}",
                    v.name,
                    seconds * 1e3,
                    median * 1e3,
                    slowest * 1e3,
                    copy_seconds / seconds,
                    u64::from(n) as f64 * 64.0 / seconds * 1e-9
                );
            }
            // Does where a buffer lands change its bandwidth? The copy on three more pairs of
            // buffers, alternating with the first pair.
            let copy = bench::compute_pipeline(&gpu, &module, "copy", Some(&pipeline_layout));
            let pairs: Vec<(wgpu::Buffer, wgpu::Buffer)> =
                (0..3).map(|_| (make("src"), make("dst"))).collect();
            let groups: Vec<wgpu::BindGroup> = std::iter::once(group)
                .chain(pairs.iter().map(|(a, b)| bind(a, b)))
                .collect();
            let mut line = String::from("    copy on pairs 0 1 2 3 0 1 2 3 (medians):");
            for round in 0..8 {
                let (_, seconds, _) = time(&copy, &groups[round % 4], 2 * u64::from(n));
                line += &format!(" {:.0}", u64::from(n) as f64 * 64.0 / seconds * 1e-9);
            }
            println!("{line} GB/s");
        }
    }
}

/// Reads particles back and compares a sample with the CPU's result: "" when they agree.
fn check(gpu: &Gpu, buffer: &wgpu::Buffer, n: u32, steps: u32, word_major: bool) -> String {
    let bytes = read_buffer(gpu, buffer).expect("readback");
    let word = |k: usize| -> [u32; 4] {
        let b = &bytes[16 * k..16 * k + 16];
        std::array::from_fn(|j| u32::from_le_bytes(b[4 * j..4 * j + 4].try_into().unwrap()))
    };
    for i in (0..n).step_by((n / 97).max(1) as usize) {
        let (a, b) = if word_major {
            (i as usize, (n + i) as usize)
        } else {
            (2 * i as usize, 2 * i as usize + 1)
        };
        let (w0, w1) = (word(a), word(b));
        let got = [w0[0], w0[1], w0[2], w1[0], w1[1], w1[2]].map(f32::from_bits);
        let want = expected(i, steps);
        if got
            .iter()
            .zip(&want)
            .any(|(g, w)| (g - w).abs() > 1e-3 * (1.0 + w.abs()))
            || w0[3] != i
        {
            return format!(" WRONG at {i}: {got:?} vs {want:?}");
        }
    }
    String::new()
}
