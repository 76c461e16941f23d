// Per grid column: the farthest linear eye depth over the pixels of its own and its 8 neighbours' screen
// tiles (tile of column c: pixel columns floor(c W / gw) .. ceil((c + 1) W / gw) - 1, likewise rows),
// sky = SKY. Kept for the next frame's disocclusion test (TECHNIQUES.md `froxel`, temporal).

@group(0) @binding(0) var<uniform> fx: Froxel;
@group(0) @binding(1) var<storage, read> slices: array<f32>;
@group(0) @binding(2) var depth_tex: texture_depth_2d;
@group(0) @binding(3) var<storage, read_write> tile_out: array<f32>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let gw = u32(fx.grid.x);
    let gh = u32(fx.grid.y);
    if (id.x >= gw || id.y >= gh) {
        return;
    }
    let W = u32(fx.size.x);
    let H = u32(fx.size.y);
    let c0 = select(id.x - 1u, 0u, id.x == 0u);
    let r0 = select(id.y - 1u, 0u, id.y == 0u);
    let c1 = min(id.x + 1u, gw - 1u);
    let r1 = min(id.y + 1u, gh - 1u);
    var far = 0.0;
    for (var i = r0 * H / gh; i < ((r1 + 1u) * H + gh - 1u) / gh; i++) {
        for (var j = c0 * W / gw; j < ((c1 + 1u) * W + gw - 1u) / gw; j++) {
            far = max(far, linear_depth(textureLoad(depth_tex, vec2i(i32(j), i32(i)), 0)));
        }
    }
    tile_out[id.y * gw + id.x] = far;
}
