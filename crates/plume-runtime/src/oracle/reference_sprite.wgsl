// Sprites on quads the CPU placed, one instance per particle, six vertices per quad: soft round
// dots, or the texel rectangle of the flipbook frame the CPU chose. Not generated: this shader is
// the same for every effect (the effect kernels are generated).

struct Camera {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
// The effect's texture (a 1x1 white one when it has none) and a linear, clamped sampler.
@group(0) @binding(1) var sprite_texture: texture_2d<f32>;
@group(0) @binding(2) var sprite_sampler: sampler;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
    @location(2) @interpolate(flat) texels: vec4<f32>,
}

@vertex
fn vs(
    @builtin(vertex_index) vi: u32,
    @location(0) center: vec3<f32>,
    @location(1) half_x: vec3<f32>,
    @location(2) half_y: vec3<f32>,
    @location(3) color: vec4<f32>,
    @location(4) texels: vec4<f32>,
) -> Out {
    // Split along the same diagonal as the draw module's 4-vertex strip, so that both
    // rasterise the same two triangles (and take the same derivatives for mip levels).
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(-1.0, 1.0),
        vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
    );
    let uv = corners[vi % 6u];
    // The corner in world space, from the half axes the CPU computed in f64.
    let corner = center + uv.x * half_x + uv.y * half_y;
    var out: Out;
    out.clip = camera.proj * camera.view * vec4<f32>(corner, 1.0);
    out.uv = uv;
    out.color = color;
    out.texels = texels;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    // Corner (-1, 1) is the frame's top-left texel corner.
    let local = vec2<f32>(in.uv.x + 1.0, 1.0 - in.uv.y) * 0.5 * in.texels.zw;
    let size = vec2<f32>(textureDimensions(sprite_texture));
    // The mip level's derivatives, in uniform control flow, before the clamp.
    let gx = dpdxFine((in.texels.xy + local) / size);
    let gy = dpdyFine((in.texels.xy + local) / size);
    // A frame's texel rectangle (x0, y0, width, height); zero width: no texture.
    if (in.texels.z > 0.0) {
        // Sample no nearer the frame's edge than half a texel of the coarser mip level in use,
        // so no neighbouring frame blends in.
        let rho = max(length(gx * size), length(gy * size));
        let half_texel = min(0.5 * in.texels.zw, vec2<f32>(0.5 * exp2(ceil(log2(max(rho, 1.0))))));
        let at = in.texels.xy + clamp(local, half_texel, in.texels.zw - half_texel);
        return in.color * textureSampleGrad(sprite_texture, sprite_sampler, at / size, gx, gy);
    }
    let r2 = dot(in.uv, in.uv);
    if (r2 >= 1.0) {
        discard;
    }
    // Soft round falloff: full at the centre, zero at the rim.
    let falloff = (1.0 - r2) * (1.0 - r2);
    return vec4<f32>(in.color.rgb, in.color.a * falloff);
}
