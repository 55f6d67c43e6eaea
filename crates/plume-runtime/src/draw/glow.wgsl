// Bloom for `plume render` (render.glow): the light above a threshold (and at most the glow's
// clamp), blurred with a separable Gaussian, added back to the HDR image, clamped to an RGBA8
// image. Not generated: this shader is the same for every effect (the effect kernels are
// generated).

struct Params {
    threshold: f32,
    strength: f32,
    // Taps on each side of the centre (about 3 sigma).
    taps: i32,
    // -1 / (2 sigma^2), in texels.
    falloff: f32,
    // Light past this blooms as this (render.glow.clamp, at least 1: the image itself, clamped
    // to 1 at the end, does not change).
    clamp: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var source: texture_2d<f32>;

// The light above `threshold` (and at most `most`) around `p`, blurred along `step` (one texel
// in x or in y), the taps clamped to the image.
fn blur(p: vec2<i32>, step: vec2<i32>, threshold: f32, most: f32) -> vec3<f32> {
    let last = vec2<i32>(textureDimensions(source)) - vec2<i32>(1);
    var sum = vec3<f32>(0.0);
    var weights = 0.0;
    for (var k = -params.taps; k <= params.taps; k++) {
        let w = exp(f32(k * k) * params.falloff);
        let c = min(textureLoad(source, clamp(p + k * step, vec2<i32>(0), last), 0).rgb, vec3<f32>(most));
        sum += w * max(c - vec3<f32>(threshold), vec3<f32>(0.0));
        weights += w;
    }
    return sum / weights;
}

// Pass 1: the bright part of the HDR image, blurred along x.
@group(0) @binding(2) var blurred_x: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8)
fn blur_x(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if (any(p >= vec2<i32>(textureDimensions(source)))) {
        return;
    }
    textureStore(blurred_x, p, vec4<f32>(blur(p, vec2<i32>(1, 0), params.threshold, params.clamp), 1.0));
}

// Pass 2: pass 1 blurred along y (it is never negative and already clamped: no threshold, no
// clamp), added to the HDR image, clamped to [0, 1].
@group(0) @binding(3) var hdr: texture_2d<f32>;
@group(0) @binding(4) var image: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8)
fn blur_y_and_add(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if (any(p >= vec2<i32>(textureDimensions(source)))) {
        return;
    }
    let c = textureLoad(hdr, p, 0);
    let lit = c.rgb + params.strength * blur(p, vec2<i32>(0, 1), 0.0, 3.0e38);
    textureStore(image, p, clamp(vec4<f32>(lit, c.a), vec4<f32>(0.0), vec4<f32>(1.0)));
}
