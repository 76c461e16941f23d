// Pass 4: min of linear eye depth over each march texel's block of full-res pixels (thesis 4.2.3).
// Block of texel j: [floor(j N / n), ceil((j + 1) N / n)) per axis (TECHNIQUES / CONVENTIONS: floor sizes).
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var depth_tex: texture_depth_2d;

override BUG_AVERAGE_DEPTH: bool = false;   // mean of the block instead of its min
override BUG_BLOCK_END_FLOOR: bool = false; // block end rounded down: odd sizes drop their last row/column

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let j = vec2u(pos.xy);
    let hi = vec2u(g.size.xy);
    let lo = vec2u(g.size.zw);
    let start = j * hi / lo;
    let stop = select(((j + 1u) * hi + lo - 1u) / lo, (j + 1u) * hi / lo, BUG_BLOCK_END_FLOOR);
    var z = SKY;
    var sum = 0.0;
    for (var r = start.y; r < stop.y; r++) {
        for (var c = start.x; c < stop.x; c++) {
            let zk = linear_depth(textureLoad(depth_tex, vec2u(c, r), 0));
            z = min(z, zk);
            sum += zk;
        }
    }
    if (BUG_AVERAGE_DEPTH) {
        z = sum / f32((stop.x - start.x) * (stop.y - start.y));
    }
    return vec4f(z, 0.0, 0.0, 0.0);
}
