// Strips whose vertices the CPU placed (in f64, world space): the reference drawing of
// render.trail and render.ribbon. Not generated: the same for every effect.

// The camera uniform and blend_out: reference_camera.wgsl, put before this shader.

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
    if (camera.blend.x == 3.0) {
        return vec4<f32>(in.color.rgb * across, in.color.a * across);
    }
    return blend_out(vec4<f32>(in.color.rgb, in.color.a * across));
}
