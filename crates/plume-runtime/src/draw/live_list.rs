//! A compacted list of the live slots of a stateful effect, in slot order, and the indirect
//! draw arguments of exactly that many instances: the alternative to drawing every slot and
//! hiding the free ones (degenerate quads). Three passes, all on the GPU: a flag per slot
//! (alive or not), the exclusive prefix sum of the flags (each live slot's place in the list),
//! and a scatter of the live slots to their places; the thread of the last slot writes the
//! count. Order-preserving (a scan, not an atomic counter), so the draw order, and the image,
//! are the same run after run. `plume bench --occupancy` measures it against hidden quads.

use plume_compiler::passes::layout::Attribute;
use plume_compiler::wgsl::draw::Primitive;
use plume_compiler::CompiledEffect;

use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::device::resources::Resources;
use crate::error::RuntimeError;
use crate::sort::radix::{GpuSorter, SortProgram};

const LIVE_LIST_WGSL: &str = r#"
// One particle buffer's slots: global slots base .. base + len, stored word-major (16-byte
// word k of slot i at k * len + i); the id in lane `id_lane` of word `id_vec4`.
struct Part {
    id_vec4: u32,
    id_lane: u32,
    base: u32,
    len: u32,
    last: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> particles: array<u32>;
@group(0) @binding(1) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(2) var<storage, read_write> list: array<u32>;
@group(0) @binding(3) var<storage, read_write> args: array<u32>;
@group(0) @binding(4) var<uniform> part: Part;

fn alive(i: u32) -> bool {
    return particles[4u * (part.id_vec4 * part.len + i) + part.id_lane] != 0xffffffffu;
}

@compute @workgroup_size(256)
fn flags(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i >= part.len) {
        return;
    }
    offsets[part.base + i] = select(0u, 1u, alive(i));
}

@compute @workgroup_size(256)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if (i >= part.len) {
        return;
    }
    let slot = part.base + i;
    let live = alive(i);
    if (live) {
        list[offsets[slot]] = slot;
    }
    // Word 0, the vertices per sprite, is written once by the host.
    if (slot == part.last) {
        args[1] = offsets[slot] + select(0u, 1u, live);
    }
}
"#;

/// The live list's buffers and passes.
pub(crate) struct LiveList {
    /// The live slots, in slot order (the first `args[1]` entries).
    pub list: wgpu::Buffer,
    /// The indirect draw's arguments: the vertices per sprite, the live count of instances.
    pub args: wgpu::Buffer,
    flags: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    /// Per particle buffer: its flags and scatter bind groups and its slot count.
    parts: Vec<(wgpu::BindGroup, wgpu::BindGroup, u64)>,
    scan: SortProgram,
    gpu: Gpu,
}

impl LiveList {
    /// The live list of `effect`, whose buffers `res` holds.
    pub(crate) fn new(
        gpu: &Gpu,
        res: &Resources,
        effect: &CompiledEffect,
        primitive: Primitive,
    ) -> Result<Self, RuntimeError> {
        let device = &gpu.device;
        let cap = u64::from(effect.ir.capacity);
        let words = |n: u64, label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: n.max(1) * 4,
                usage: STORAGE,
                mapped_at_creation: false,
            })
        };
        let (offsets, list) = (words(cap, "live offsets"), words(cap, "live list"));
        let args = filled_buffer(
            gpu,
            "live draw args",
            16,
            STORAGE | wgpu::BufferUsages::INDIRECT,
            |b| b[..4].copy_from_slice(&primitive.vertices().to_le_bytes()),
        )?;
        let module = gpu.shader_module("live list", LIVE_LIST_WGSL);
        let pipeline = |entry| gpu.compute_pipeline(&module, entry, None);
        let (flags, scatter) = (pipeline("flags"), pipeline("scatter"));
        let id_word = effect
            .layout
            .word_offset(Attribute::Id)
            .ok_or_else(|| RuntimeError::Gpu("the layout has no id".into()))?
            as u32;
        let mut parts = Vec::new();
        for chunk in res.chunks(effect)? {
            let words: [u32; 8] = [
                id_word / 4,
                id_word % 4,
                chunk.base as u32,
                chunk.len as u32,
                effect.ir.capacity - 1,
                0,
                0,
                0,
            ];
            let part = filled_buffer(gpu, "live part", 32, wgpu::BufferUsages::UNIFORM, |b| {
                for (w, out) in words.iter().zip(b.chunks_exact_mut(4)) {
                    out.copy_from_slice(&w.to_le_bytes());
                }
            })?;
            let group = |pipeline: &wgpu::ComputePipeline, entries: &[(u32, &wgpu::Buffer)]| {
                gpu.bind_buffers("live list", &pipeline.get_bind_group_layout(0), entries)
            };
            parts.push((
                group(&flags, &[(0, &chunk.buffer), (1, &offsets), (4, &part)]),
                group(
                    &scatter,
                    &[
                        (0, &chunk.buffer),
                        (1, &offsets),
                        (2, &list),
                        (3, &args),
                        (4, &part),
                    ],
                ),
                chunk.len,
            ));
        }
        Ok(Self {
            scan: GpuSorter::new(gpu).scan_program(&offsets, cap)?,
            list,
            args,
            flags,
            scatter,
            parts,
            gpu: gpu.clone(),
        })
    }

    /// Records the flags, their scan and the scatter into `pass`.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) -> Result<(), RuntimeError> {
        pass.set_pipeline(&self.flags);
        for (flags, _, len) in &self.parts {
            let (x, y) = self.gpu.grid(*len, 256)?;
            pass.set_bind_group(0, flags, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        self.scan.record(pass);
        pass.set_pipeline(&self.scatter);
        for (_, scatter, len) in &self.parts {
            let (x, y) = self.gpu.grid(*len, 256)?;
            pass.set_bind_group(0, scatter, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        Ok(())
    }
}
