// Sprites on quads the CPU placed, one instance per particle, six vertices per quad: soft round
// dots, or the texel rectangle of the flipbook frame the CPU chose. Not generated: this shader is
// the same for every effect (the effect kernels are generated). Its camera uniform and
// blend_out are reference_camera.wgsl's, put before it.

// The effect's texture (a 1x1 white one when it has none) and a linear, clamped sampler.
@group(0) @binding(1) var sprite_texture: texture_2d<f32>;
@group(0) @binding(2) var sprite_sampler: sampler;

// The lights in world space (outputs/world_lights.wgsl, put before this shader).
@group(0) @binding(3) var<uniform> lights: Lights;
// A lit look's maps, laid out as the texture (flat 1x1 ones where it has fewer): a normal map,
// or the six-way lightmaps (right, top, back; left, bottom, front).
@group(0) @binding(4) var lit_map_0: texture_2d<f32>;
@group(0) @binding(5) var lit_map_1: texture_2d<f32>;
// The texture's second image, laid out as it (a white 1x1 one when it has none).
@group(0) @binding(6) var second_texture: texture_2d<f32>;

// A texel as a sample mapping makes it (0 Modulate, 1 ModulateRgb, 2 OpacityFromRed).
fn mapped(raw: vec4<f32>, sample: f32) -> vec4<f32> {
    if (sample == 1.0) {
        return vec4<f32>(raw.rgb, 1.0);
    }
    if (sample == 2.0) {
        return vec4<f32>(1.0, 1.0, 1.0, raw.r);
    }
    return raw;
}

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
    @location(2) @interpolate(flat) texels: vec4<f32>,
    // The pixel's point and the quad's half axes, in world space.
    @location(3) world: vec3<f32>,
    @location(4) @interpolate(flat) half_x: vec3<f32>,
    @location(5) @interpolate(flat) half_y: vec3<f32>,
}

// A lit sprite's colour at corner coordinates uv, point p (world space): the normal of its
// flat quad, of a half sphere over it, or of its normal map (maps[0]: the map's texel, the
// normal in the sprite's frame), facing the viewer; or six-way lightmaps (maps: their texels),
// each light weighted t^2 per axis of the sprite's frame, its map by the sign, ambient light by
// the six maps' mean; ambient light plus each source's
// light times max((n . l + wrap) / (1 + wrap), 0), a point light's falling off as 1 / d^2
// (d no less than 10 cm) and to zero at its range; the emissive part unlit.
fn lit(c: vec4<f32>, uv: vec2<f32>, maps: array<vec3<f32>, 2>, half_x: vec3<f32>, half_y: vec3<f32>, p: vec3<f32>) -> vec4<f32> {
    if (camera.lit.x == 0.0) {
        return c;
    }
    let ux = normalize(half_x);
    let uy = normalize(half_y);
    var facing = normalize(cross(ux, uy));
    let toward_eye = select(camera.eye.xyz, camera.eye.xyz - p, camera.eye.w == 1.0);
    if (dot(facing, toward_eye) < 0.0) {
        facing = -facing;
    }
    var n = facing;
    if (camera.lit.y == 1.0) {
        n = normalize(uv.x * ux + uv.y * uy + sqrt(max(1.0 - dot(uv, uv), 0.0)) * facing);
    }
    if (camera.lit.y == 2.0) {
        let tangent = maps[0] * 2.0 - 1.0;
        n = normalize(tangent.x * ux + tangent.y * uy + tangent.z * facing);
    }
    let wrap = camera.lit.z;
    let six_way = camera.lit.y == 3.0;
    var light = lights.ambient.rgb;
    if (six_way) {
        light = light * (maps[0].x + maps[0].y + maps[0].z + maps[1].x + maps[1].y + maps[1].z) / 6.0;
    }
    for (var i = 0u; i < light_count(); i++) {
        let a = arriving(i, p);
        let toward = a.toward;
        let color = a.color;
        if (six_way) {
            let t = vec3<f32>(dot(toward, ux), dot(toward, uy), dot(toward, facing));
            var response = maps[1];
            if (t.x > 0.0) {
                response.x = maps[0].x;
            }
            if (t.y > 0.0) {
                response.y = maps[0].y;
            }
            if (t.z <= 0.0) {
                response.z = maps[0].z;
            }
            light += color * dot(t * t, response);
        } else {
            light += color * max((dot(n, toward) + wrap) / (1.0 + wrap), 0.0);
        }
    }
    let emissive = camera.lit.w;
    return vec4<f32>(c.rgb * (emissive + (1.0 - emissive) * light), c.a);
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
    out.world = corner;
    out.half_x = half_x;
    out.half_y = half_y;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    if (camera.blend.x == 3.0) {
        // Premultiplied: the coverage shaded at opacity 1, the colour written times it.
        var pin = in;
        pin.color.a = 1.0;
        let c = shade(pin);
        return vec4<f32>(c.rgb * c.a, in.color.a * c.a);
    }
    return blend_out(shade(in));
}

fn shade(in: Out) -> vec4<f32> {
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
        let first = textureSampleGrad(sprite_texture, sprite_sampler, at / size, gx, gy);
        let second = textureSampleGrad(second_texture, sprite_sampler, at / size, gx, gy);
        let texel = in.color * mapped(first, camera.blend.z) * mapped(second, camera.blend.w);
        let maps = array<vec3<f32>, 2>(
            textureSampleGrad(lit_map_0, sprite_sampler, at / size, gx, gy).xyz,
            textureSampleGrad(lit_map_1, sprite_sampler, at / size, gx, gy).xyz,
        );
        return lit(texel, in.uv, maps, in.half_x, in.half_y, in.world);
    }
    let r2 = dot(in.uv, in.uv);
    if (r2 >= 1.0) {
        discard;
    }
    // Soft round falloff: full at the centre, zero at the rim.
    let falloff = (1.0 - r2) * (1.0 - r2);
    let none = array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
    return lit(vec4<f32>(in.color.rgb, in.color.a * falloff), in.uv, none, in.half_x, in.half_y, in.world);
}
