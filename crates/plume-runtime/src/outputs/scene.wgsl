// The scene around an effect (outputs/scene.rs): triangles in world space, one flat grey lit
// by the scene's lights (a lit effect's own, else a plain light from above), both sides of each
// triangle lit as its front, and shadowed by the map of the light that casts one.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // The camera's position (w unused).
    eye: vec4<f32>,
    // The surfaces' colour (a unused).
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> u: Uniforms;

// The lights in world space (world_lights.wgsl and the shadow lookup, put before this shader).
@group(0) @binding(1) var<uniform> lights: Lights;
// The shadow map of the light that casts one (a 1x1 stand-in while none does).
@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var shadow_standard: sampler_comparison;
@group(0) @binding(4) var shadow_reversed: sampler_comparison;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) world: vec3<f32>,
}

@vertex
fn vs(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Out {
    var out: Out;
    out.clip = u.view_proj * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.world = position;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    var n = in.normal;
    let l = length(n);
    n = select(vec3<f32>(0.0, 1.0, 0.0), n / l, l > 0.0);
    // The side the camera sees is lit as the front.
    n = select(n, -n, dot(n, u.eye.xyz - in.world) < 0.0);
    // Lambert's law: the ambient light plus each source's light times max(n . l, 0), the
    // shadowed one's times what its map lets through.
    var light = lights.ambient.rgb;
    for (var i = 0u; i < light_count(); i++) {
        let a = arriving(i, in.world);
        var color = a.color;
        if (i == lights.shadow.x) {
            color = color * shadow_visibility(in.world);
        }
        light += color * max(dot(n, a.toward), 0.0);
    }
    return vec4<f32>(u.color.rgb * light, 1.0);
}
