// Pass 6: depth-aware bilateral upsample (thesis 4.2.4): bilinear weights b_k (9/16, 3/16, 3/16, 1/16 at
// half resolution) divided by |z - z_k| + eps, normalised; taps 00, 10, 01, 11 (x first, row 0 on top).
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var light_lo: texture_2d<f32>;
@group(0) @binding(2) var depth_lo: texture_2d<f32>;
@group(0) @binding(3) var depth_tex: texture_depth_2d;

override BUG_UPSAMPLE_NO_DEPTH: bool = false;  // bilinear weights only
override BENIGN_REVERSED_SUM: bool = false;    // sums in the order 11, 01, 10, 00
override BUG_BLUR_EPS_X10: bool = false;       // depth weight 1 / (|dz| + 10 eps): the bilateral guard 10x too loose

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let lo = vec2i(g.size.zw);
    let p = pos.xy * g.size.zw / g.size.xy - 0.5;   // (i + 0.5) n_lo / n_hi - 1/2
    let i0 = floor(p);
    let t = p - i0;
    let c0 = clamp(vec2i(i0), vec2i(0), lo - 1);
    let c1 = clamp(vec2i(i0) + 1, vec2i(0), lo - 1);
    let taps = array<vec2i, 4>(c0, vec2i(c1.x, c0.y), vec2i(c0.x, c1.y), c1);
    let b = array<f32, 4>((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    let z = linear_depth(textureLoad(depth_tex, vec2i(pos.xy), 0));
    var w: array<f32, 4>;
    for (var k = 0; k < 4; k++) {
        w[k] = b[k];
        if (!BUG_UPSAMPLE_NO_DEPTH) {
            let eps = select(g.march.z, 10.0 * g.march.z, BUG_BLUR_EPS_X10);
            w[k] = b[k] / (depth_delta(z, textureLoad(depth_lo, taps[k], 0).r) + eps);
        }
    }
    var wsum = ((w[0] + w[1]) + w[2]) + w[3];
    if (wsum == 0.0) {
        w = b;
        wsum = ((b[0] + b[1]) + b[2]) + b[3];
    }
    var acc = vec3f(0.0);
    for (var k = 0; k < 4; k++) {
        let m = select(k, 3 - k, BENIGN_REVERSED_SUM);
        acc += w[m] * textureLoad(light_lo, taps[m], 0).rgb;
    }
    return vec4f(acc / wsum, 0.0);
}
