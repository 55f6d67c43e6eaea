// The compute renderer's image put over a host's colour attachment: one triangle covering the
// target, each fragment reading its pixel's premultiplied light and coverage (the compute renderer's HDR
// image: (r, g) and (b, coverage) as f16 pairs, rows of `pitch` pixels). The pipeline blends
// with (One, OneMinusSrcAlpha): the host's colour shows through as much as the particles
// leave uncovered, and additive light adds.

// pitch.w: the NDC depth the triangle lies at (f32 bits), for a pipeline that tests it against
// the pass's depth (`HostSplat::set_composite_depth`); the other pipeline passes any depth.
@group(0) @binding(0) var<uniform> pitch: vec4<u32>;
@group(0) @binding(1) var<storage, read> image: array<vec2<u32>>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, bitcast<f32>(pitch.w), 1.0);
}

@fragment
fn fs(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<u32>(frag.xy);
    // A pixel past the image (a target larger than the renderer was made for) adds nothing.
    if (p.x >= pitch.y || p.y >= pitch.z) {
        return vec4<f32>(0.0);
    }
    let w = image[p.y * pitch.x + p.x];
    return vec4<f32>(unpack2x16float(w.x), unpack2x16float(w.y));
}
