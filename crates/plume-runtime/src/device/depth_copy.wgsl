// Copies a depth texture into a buffer of f32, row by row from the top, in a compute pass: GL
// can neither copy depth to a buffer nor load from texture_depth_2d, but every backend loads a
// depth texture bound as texture_2d<f32>. The runtime puts the declaration of `depth`
// (binding 0) before this: texture_2d<f32>, or for a multisampled texture
// texture_multisampled_2d<f32>, whose sample 0 is taken.

@group(0) @binding(1) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(depth);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    out[id.y * size.x + id.x] = textureLoad(depth, id.xy, 0).r;
}
