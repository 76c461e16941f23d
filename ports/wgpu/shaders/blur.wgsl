// Pass 7/8: separable bilateral Gaussian blur, 7 taps (thesis 4.2.6): G_k / (|z_k - z_0| + eps), normalised,
// clamp addressing; tap order centre, -3..-1, 1..3 (TECHNIQUES: thesis_blur_pass).
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var light_tex: texture_2d<f32>;
@group(0) @binding(2) var depth_tex: texture_depth_2d;

override AXIS: u32 = 0u;                     // 0 horizontal, 1 vertical
override BENIGN_REVERSED_SUM: bool = false;  // taps summed -3..3 in order
override BUG_GAUSS_NO_TWO: bool = false;     // Gaussian exp(-k^2 / sigma^2): the factor 2 of 2 sigma^2 missing
override BUG_BLUR_EPS_X10: bool = false;     // depth weight 1 / (|dz| + 10 eps): the bilateral guard 10x too loose

const TAP_ORDER = array<i32, 7>(0, -3, -2, -1, 1, 2, 3);

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let px = vec2i(pos.xy);
    let size = vec2i(g.size.xy);
    let axis = select(vec2i(1, 0), vec2i(0, 1), AXIS == 1u);
    let z0 = linear_depth(textureLoad(depth_tex, px, 0));
    let sigma = g.march.w;
    var acc = vec3f(0.0);
    var wsum = 0.0;
    for (var j = 0; j < 7; j++) {
        let k = select(TAP_ORDER[j], j - 3, BENIGN_REVERSED_SUM);
        let q = clamp(px + k * axis, vec2i(0), size - 1);
        let gk = exp(-f32(k * k) / (select(2.0, 1.0, BUG_GAUSS_NO_TWO) * sigma * sigma)) / sqrt(2.0 * PI * sigma * sigma);
        let eps = select(g.march.z, 10.0 * g.march.z, BUG_BLUR_EPS_X10);
        let w = gk / (depth_delta(linear_depth(textureLoad(depth_tex, q, 0)), z0) + eps);
        acc += w * textureLoad(light_tex, q, 0).rgb;
        wsum += w;
    }
    return vec4f(acc / wsum, 0.0);
}
