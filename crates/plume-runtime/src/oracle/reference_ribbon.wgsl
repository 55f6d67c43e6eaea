// Ribbons whose vertices the CPU placed (in f64, world space): the reference drawing of
// render.trail. Not generated: the same for every effect.

struct Camera {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
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

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    // Soft across the strip: full on the centre line, zero at the edges.
    let across = 1.0 - in.across * in.across;
    return vec4<f32>(in.color.rgb, in.color.a * across);
}
