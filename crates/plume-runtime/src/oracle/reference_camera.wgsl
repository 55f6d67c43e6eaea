// The reference drawing's camera uniform and what a fragment writes for the effect's blend,
// shared by the reference sprite and strip shaders (put before each). Not generated: the same
// for every effect.

struct Camera {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    // The eye in world space (w = 1), or for an orthographic camera the world direction
    // toward the viewer (w = 0).
    eye: vec4<f32>,
    // A lit look (render.lit): (1 when lit; normals 0 flat, 1 sphere, 2 a normal map, 3 six-way
    // lightmaps; wrap; emissive).
    lit: vec4<f32>,
    // The blend's fragment output (render.blend): (0 as written; 1 Multiply; 2 Mask; 3
    // Premultiplied; 4 Opaque; the Mask's cutoff; the texture's sample mapping: 0 Modulate, 1
    // ModulateRgb, 2 OpacityFromRed; its second image's, alike).
    blend: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

// What a fragment of colour c (straight alpha) writes for the blend: Multiply, the colour
// times its opacity; Mask, the colour opaque, or nothing below the cutoff; Opaque, the colour.
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
    if (camera.blend.x == 4.0) {
        return vec4<f32>(c.rgb, 1.0);
    }
    return c;
}
