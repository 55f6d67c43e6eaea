// What the tile kernels share (`splat.wgsl` and `additive_lists.wgsl` are each compiled after
// this): the parameters, the bindings both read or write (the layout is `binding.rs`'s
// TILE_BINDINGS), and the thread index of a 2D grid.

struct Params {
    width: u32,
    height: u32,
    tiles_x: u32,
    tiles: u32,
    count: u32,
    entries: u32,
    additive: u32,
    background: u32,
    // Light at which an HDR pixel is finished (the composite's; unused here).
    light_ceiling: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(3) var<storage, read> tile_counts: array<u32>;
// The entries' sprites, by tile.
@group(0) @binding(5) var<storage, read_write> vals: array<u32>;
// Each tile's run of entries.
@group(0) @binding(6) var<storage, read_write> ranges: array<vec2<u32>>;
// [0]: entries needed this frame (more than `params.entries` means some were dropped).
@group(0) @binding(8) var<storage, read_write> status: array<u32>;
// Each sprite's tiles, as `project` counted them: (x0 | y0 << 16, x1 | y1 << 16).
@group(0) @binding(9) var<storage, read> tile_boxes: array<vec2<u32>>;

fn index2d(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 256u;
}
