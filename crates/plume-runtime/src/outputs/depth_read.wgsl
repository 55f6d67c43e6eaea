// Copies a depth texture (read as texture_2d<f32>, which every backend loads from, GL
// included) into a buffer of f32, row by row from the top: GL cannot copy depth to a buffer.

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(depth);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    out[id.y * size.x + id.x] = textureLoad(depth, id.xy, 0).r;
}
