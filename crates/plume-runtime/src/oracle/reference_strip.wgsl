// Ribbons whose vertices the CPU placed (in f64, world space): the reference drawing of
// render.trail and render.ribbon. Not generated: the same for every effect.

// The reference sprite shader's camera (reference_sprite.wgsl), whose blend terms it reads.
struct Camera {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    eye: vec4<f32>,
    lit: vec4<f32>,
    blend: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) across: f32,
    @location(1) color: vec4<f32>,
}

@vertex
fn vs(@location(0) position: vec3<f32>, @location(1) across: f32, @location(2) color: vec4<f32>) -> Out {
    var out: Out;
    out.clip = camera.proj * camera.view * vec4<f32>(position, 1.0);
    out.across = across;
    out.color = color;
    return out;
}

// What a fragment writes for the blend, as reference_sprite.wgsl's blend_out.
fn blend_out(c: vec4<f32>) -> vec4<f32> {
    if (camera.blend.x == 1.0) {
        return vec4<f32>(c.rgb * c.a, c.a);
    }
    if (camera.blend.x == 2.0) {
        if (c.a < camera.blend.y) {
            discard;
        }
        return vec4<f32>(c.rgb, 1.0);
    }
    return c;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    // Soft across the strip: full on the centre line, zero at the edges.
    let across = 1.0 - in.across * in.across;
    if (camera.blend.x == 3.0) {
        return vec4<f32>(in.color.rgb * across, in.color.a * across);
    }
    return blend_out(vec4<f32>(in.color.rgb, in.color.a * across));
}
