// Lights in world space, as plume_compiler::lights lays out their uniform, for the fixed
// shaders that light in world space (the scene's meshes, the reference drawing); each declares
// `lights` at a binding of its own. Not generated: the generated draw modules light in the view.

// (direction the light travels, 0) or (position, 1), and (colour times intensity, range).
struct Source {
    place: vec4<f32>,
    color: vec4<f32>,
}

// The shadow (plume_compiler::shadow): (source, cascades, reversed, unused), then each
// cascade's projection; shadow_visibility reads them where a shader declares `shadow_map`.
struct Lights {
    ambient: vec4<f32>,
    count: vec4<u32>,
    sources: array<Source, 8>,
    shadow: vec4<u32>,
    cascades: array<mat4x4<f32>, 4>,
}

// Source i's light at world point p: the unit vector toward it (zero for a zero direction) and
// its colour there, a point light's falling off as 1 / d^2 (d no less than 10 cm) and to
// nothing at its range.
struct Arriving {
    toward: vec3<f32>,
    color: vec3<f32>,
}

fn arriving(i: u32, p: vec3<f32>) -> Arriving {
    let s = lights.sources[i];
    if (s.place.w > 0.5) {
        let d = s.place.xyz - p;
        let d2 = max(dot(d, d), 0.01);
        let q = d2 / (s.color.w * s.color.w);
        let window = clamp(1.0 - q * q, 0.0, 1.0);
        return Arriving(d * inverseSqrt(d2), s.color.rgb * window * window / d2);
    }
    return Arriving(-s.place.xyz * inverseSqrt(max(dot(s.place.xyz, s.place.xyz), 1e-30)), s.color.rgb);
}

// Lights a source count names, no more than the uniform holds.
fn light_count() -> u32 {
    return min(lights.count.x, 8u);
}
