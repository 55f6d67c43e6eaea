//! Where should a baked field live? The thesis sampled 3D textures; Plume bakes into a storage
//! buffer. This experiment samples the same n³ grid at N hashed positions three ways, in one
//! run on one GPU, and prints the time per sampling pass (GPU timestamps) and the largest
//! difference from the storage-buffer result:
//!
//! - `buffer`: a storage buffer of vec4<f32>, trilinear by hand (8 loads), as `field.rs` emits;
//! - `texture f32`: an rgba32float 3D texture, trilinear by hand with `textureLoad`;
//! - `texture f16`: an rgba16float 3D texture with a linear sampler (`textureSampleLevel`):
//!   hardware filtering, half the bytes, f16 values and the hardware's filter weights.
//!
//! `cargo run --release --example field_storage` (docs/performance.md, "Baked fields").

use plume::runtime::bench::{read_buffer, PassTimer};
use plume::runtime::{Gpu, GpuChoice};
use wgpu::util::DeviceExt;

const WGSL: &str = r#"
const RES: u32 = RES_VALUE;
@group(0) @binding(0) var<storage, read> grid: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(2) var tex32: texture_3d<f32>;
@group(0) @binding(3) var tex16: texture_3d<f32>;
@group(0) @binding(4) var samp: sampler;

fn pcg(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
fn position(i: u32) -> vec3<f32> {
    let a = pcg(i);
    let b = pcg(a);
    let c = pcg(b);
    return vec3<f32>(f32(a >> 8u), f32(b >> 8u), f32(c >> 8u)) * 5.9604645e-8;
}
fn at_buffer(i: u32, j: u32, k: u32) -> vec3<f32> {
    return grid[i + RES * (j + RES * k)].xyz;
}
fn at_tex(i: u32, j: u32, k: u32) -> vec3<f32> {
    return textureLoad(tex32, vec3<u32>(i, j, k), 0).xyz;
}
fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 256u;
}

@compute @workgroup_size(256)
fn texture16(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = index(gid, groups);
    if (n >= arrayLength(&out)) { return; }
    // Texel centres sit at (i + 0.5) / RES: map node coordinates onto them.
    let u = position(n) * f32(RES - 1u);
    let t = (u + vec3<f32>(0.5)) / f32(RES);
    out[n] = vec4<f32>(textureSampleLevel(tex16, samp, t, 0.0).xyz, 0.0);
}
"#;

/// A kernel that samples the grid trilinearly by hand through `fetch(i, j, k)`: the buffer and
/// the f32 texture differ only in how they read a node.
fn manual_trilinear_kernel(entry: &str, fetch: &str) -> String {
    format!(
        r#"
@compute @workgroup_size(256)
fn {entry}(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let n = index(gid, groups);
    if (n >= arrayLength(&out)) {{ return; }}
    let u = position(n) * f32(RES - 1u);
    let c = min(floor(u), vec3<f32>(f32(RES - 2u)));
    let f = u - c;
    let i = u32(c.x); let j = u32(c.y); let k = u32(c.z);
    let x00 = mix({fetch}(i, j, k), {fetch}(i + 1u, j, k), f.x);
    let x10 = mix({fetch}(i, j + 1u, k), {fetch}(i + 1u, j + 1u, k), f.x);
    let x01 = mix({fetch}(i, j, k + 1u), {fetch}(i + 1u, j, k + 1u), f.x);
    let x11 = mix({fetch}(i, j + 1u, k + 1u), {fetch}(i + 1u, j + 1u, k + 1u), f.x);
    out[n] = vec4<f32>(mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z), 0.0);
}}
"#
    )
}

/// A smooth test field: a few sines, values of order 1.
fn value(i: u32, j: u32, k: u32, res: u32) -> [f32; 4] {
    let s = 6.0 / res as f32;
    let (x, y, z) = (i as f32 * s, j as f32 * s, k as f32 * s);
    [
        (x + 2.0 * y).sin(),
        (y - z).cos(),
        (0.5 * x * z).sin() + 0.3,
        0.0,
    ]
}

fn main() {
    let gpu = Gpu::new(&GpuChoice::default()).unwrap_or_else(|e| panic!("{e}"));
    let device = &gpu.device;
    let timer = PassTimer::new(&gpu);
    println!("{}", gpu.describe());
    println!(
        "{:>6} {:>10} {:>14} {:>14} {:>14} {:>14} {:>14}",
        "nodes", "samples", "buffer (us)", "tex f32 (us)", "tex f16 (us)", "f32 diff", "f16 diff"
    );
    for res in [16u32, 64, 128] {
        let texels: Vec<[f32; 4]> = (0..res)
            .flat_map(|k| (0..res).flat_map(move |j| (0..res).map(move |i| value(i, j, k, res))))
            .collect();
        let bytes32: Vec<u8> = texels
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let bytes16: Vec<u8> = texels
            .iter()
            .flatten()
            .flat_map(|v| half_bits(*v).to_le_bytes())
            .collect();
        let grid = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid"),
            contents: &bytes32,
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = wgpu::Extent3d {
            width: res,
            height: res,
            depth_or_array_layers: res,
        };
        let texture = |format: wgpu::TextureFormat, bytes: &[u8], texel: u32| {
            device.create_texture_with_data(
                &gpu.queue,
                &wgpu::TextureDescriptor {
                    label: Some("field"),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                &bytes[..(res * res * res * texel) as usize],
            )
        };
        let tex32 = texture(wgpu::TextureFormat::Rgba32Float, &bytes32, 16);
        let tex16 = texture(wgpu::TextureFormat::Rgba16Float, &bytes16, 8);
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("field storage"),
            source: wgpu::ShaderSource::Wgsl(
                (WGSL.replace("RES_VALUE", &format!("{res}u"))
                    + &manual_trilinear_kernel("buffer", "at_buffer")
                    + &manual_trilinear_kernel("texture32", "at_tex"))
                    .into(),
            ),
        });
        for samples in [1_000_000u64, 10_000_000] {
            if samples * 16 > gpu.limits.max_storage_buffer_binding_size {
                continue; // llvmpipe binds 128 MiB at most
            }
            let out = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("out"),
                size: samples * 16,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let mut results = Vec::new();
            let mut outputs = Vec::new();
            for entry in ["buffer", "texture32", "texture16"] {
                let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: None,
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                });
                let layout = pipeline.get_bind_group_layout(0);
                let v32 = tex32.create_view(&Default::default());
                let v16 = tex16.create_view(&Default::default());
                // Auto layouts only hold what the entry point uses.
                let mut entries = vec![wgpu::BindGroupEntry {
                    binding: 1,
                    resource: out.as_entire_binding(),
                }];
                match entry {
                    "buffer" => entries.push(wgpu::BindGroupEntry {
                        binding: 0,
                        resource: grid.as_entire_binding(),
                    }),
                    "texture32" => entries.push(wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&v32),
                    }),
                    _ => {
                        entries.push(wgpu::BindGroupEntry {
                            binding: 3,
                            resource: wgpu::BindingResource::TextureView(&v16),
                        });
                        entries.push(wgpu::BindGroupEntry {
                            binding: 4,
                            resource: wgpu::BindingResource::Sampler(&sampler),
                        });
                    }
                }
                let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: None,
                    layout: &layout,
                    entries: &entries,
                });
                let groups = samples.div_ceil(256);
                let x = groups.min(65535) as u32;
                let y = groups.div_ceil(u64::from(x)) as u32;
                let repeats = 20;
                let pass = |p: &mut wgpu::ComputePass<'_>| {
                    p.set_pipeline(&pipeline);
                    p.set_bind_group(0, &group, &[]);
                    for _ in 0..repeats {
                        p.dispatch_workgroups(x, y, 1);
                    }
                    Ok(())
                };
                timer.time(pass).unwrap(); // warm-up
                let seconds = timer.time(pass).unwrap() / f64::from(repeats);
                results.push(seconds);
                let bytes = read_buffer(&gpu, &out).unwrap();
                outputs.push(
                    bytes
                        .chunks_exact(4)
                        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .collect::<Vec<f32>>(),
                );
            }
            let diff = |a: &[f32], b: &[f32]| {
                a.iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0f32, f32::max)
            };
            println!(
                "{:>5}³ {:>10} {:>14.1} {:>14.1} {:>14.1} {:>14.2e} {:>14.2e}",
                res,
                samples,
                results[0] * 1e6,
                results[1] * 1e6,
                results[2] * 1e6,
                diff(&outputs[0], &outputs[1]),
                diff(&outputs[0], &outputs[2])
            );
        }
    }
}

/// f32 to IEEE half bits (round to nearest even; the field's values are of order 1).
fn half_bits(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    let mant = bits & 0x7f_ffff;
    if exp <= 0 {
        return sign; // tiny values flush to zero here
    }
    if exp >= 31 {
        return sign | 0x7c00;
    }
    let mut half = sign | ((exp as u16) << 10) | ((mant >> 13) as u16);
    let rest = mant & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && (half & 1) == 1) {
        half += 1;
    }
    half
}
