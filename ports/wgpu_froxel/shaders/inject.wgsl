// Pass 1, light injection (Wronski 2014; Hillaire 2015): per froxel, (S, sigma_t) at its jittered sample,
// S = sigma_s sum_l p(d.l) V_l T_l E_l (TECHNIQUES.md `froxel`). Includes froxel_common and the killzone
// port's lights.wgsl (Light, incidence, cube-face tables).

@group(0) @binding(0) var<uniform> fx: Froxel;
@group(0) @binding(1) var<storage, read> slices: array<f32>;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var shadow_tex: texture_depth_2d_array;
@group(0) @binding(4) var scatter_out: texture_storage_3d<rgba16float, write>;
@group(0) @binding(5) var cascade_tex: texture_depth_2d_array;
@group(0) @binding(6) var<storage, read> cascades: array<vec4f>;   // per cascade: (centre, radius), (back, far, -, -)

fn hg(c: f32, g: f32) -> f32 {
    let d = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// Distance stored by texel `t` of layer `layer`: spot / point, the radial distance from the light (reversed-Z
// depth decoded along the texel-centre ray); directional, the distance from the cascade's view plane along the
// light (orthographic reversed-Z, 1 - z/far). Empty texels are infinitely far (lit).
fn stored_distance(li: Light, t: vec2i, layer: i32, tan_h: f32) -> f32 {
    if (li.pos_kind.w == 2.0) {
        let dc = textureLoad(cascade_tex, t, layer, 0);
        return select((1.0 - dc) * cascades[2 * layer + 1].y, SKY, dc <= 0.0);
    }
    let d = textureLoad(shadow_tex, t, layer, 0);
    if (d <= 0.0) {
        return SKY;
    }
    let n = li.shadow.z;
    let fr = li.dir_range.w;
    let res = li.shadow.y;
    let c = (2.0 * (vec2f(t) + 0.5) / res - 1.0) * tan_h;
    return fr * n / (d * (fr - n) + n) * sqrt(1.0 + c.x * c.x + c.y * c.y);
}

// Shadow visibility 1 - strength (1 - lit) of light `li` at x: `shadow.w` 0 = hard (the texel holding the
// sample), 1 = pcf (2x2 texels around uv res - 1/2, compared, bilinear weights, clamped to the face).
// Directional lights use the first cascade whose sphere holds x (lit outside every one).
fn visibility(li: Light, x: vec3f) -> f32 {
    let layer0 = i32(li.shadow.x);
    if (layer0 < 0) {
        return 1.0;
    }
    let res = li.shadow.y;
    var w = x - li.pos_kind.xyz;
    var d_ref = length(w);
    var layer = layer0;
    var uv: vec2f;
    var tan_h = 1.0;
    if (li.pos_kind.w == 2.0) {
        layer = -1;
        for (var k = layer0; k < layer0 + i32(li.cone.x); k++) {
            let sphere = cascades[2 * k];
            w = x - sphere.xyz;
            if (dot(w, w) <= sphere.w * sphere.w) {
                uv = 0.5 + vec2f(0.5, -0.5) * vec2f(dot(w, li.right_tan.xyz), dot(w, li.up_bias.xyz)) / sphere.w;
                d_ref = dot(w, li.dir_range.xyz) + cascades[2 * k + 1].x;
                layer = k;
                break;
            }
        }
        if (layer < 0) {
            return 1.0;
        }
    } else if (li.pos_kind.w == 1.0) {
        let zl = dot(w, li.dir_range.xyz);
        if (!(zl > 0.0)) {
            return 1.0;
        }
        let k = 0.5 / (zl * li.right_tan.w);
        uv = vec2f(0.5 + dot(w, li.right_tan.xyz) * k, 0.5 - dot(w, li.up_bias.xyz) * k);
        tan_h = li.right_tan.w;
    } else {
        let a = abs(w);
        var f = 0;
        var ma = a.x;
        if (a.x >= a.y && a.x >= a.z) {
            f = select(1, 0, w.x >= 0.0);
        } else if (a.y >= a.z) {
            f = select(3, 2, w.y >= 0.0);
            ma = a.y;
        } else {
            f = select(5, 4, w.z >= 0.0);
            ma = a.z;
        }
        if (ma == 0.0) {
            return 1.0;
        }
        uv = vec2f(0.5 + 0.5 * dot(w, CUBE_RIGHT[f]) / ma, 0.5 - 0.5 * dot(w, CUBE_UP[f]) / ma);
        layer = layer0 + f;
    }
    let last = vec2i(i32(res) - 1);
    var lit = 0.0;
    if (li.shadow.w == 0.0) {
        let t = clamp(vec2i(floor(uv * res)), vec2i(0), last);
        lit = select(0.0, 1.0, d_ref <= stored_distance(li, t, layer, tan_h));
    } else {
        let s = uv * res - 0.5;
        let f = floor(s);
        let wt = s - f;
        let t0 = vec2i(f);
        for (var e = 0; e < 4; e++) {
            let o = vec2i(e & 1, e >> 1);
            let t = clamp(t0 + o, vec2i(0), last);
            let ww = select(1.0 - wt, wt, vec2<bool>(o == vec2i(1)));
            lit += select(0.0, ww.x * ww.y, d_ref <= stored_distance(li, t, layer, tan_h));
        }
    }
    return 1.0 - li.color_strength.w * (1.0 - lit);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= u32(fx.grid.x) || id.y >= u32(fx.grid.y) || id.z >= u32(fx.grid.z)) {
        return;
    }
    let ray = column_ray(id.x, id.y, fx.jitter.x, fx.jitter.y);
    let k = id.z;
    let z = slices[k] + fx.jitter.z * (slices[k + 1u] - slices[k]);
    let x = fx.eye.xyz + (z / dot(ray, fx.fwd.xyz)) * ray;
    let ss = fx.medium.x;
    let st = fx.medium.y;
    var s = vec3f(0.0);
    if (ss > 0.0) {
        for (var i = 0u; i < u32(fx.size.z); i++) {
            let li = lights[i];
            var l: vec3f;
            var e: vec3f;
            var tl = 1.0;
            if (li.pos_kind.w == 2.0) {      // directional: E = colour * intensity from -direction, unbounded medium
                l = -li.dir_range.xyz;
                e = li.color_strength.xyz;
            } else {
                let inc = incidence(li, x);
                l = inc.l;
                e = inc.e;
                if (fx.medium.w != 0.0) {
                    tl = exp(-st * distance(li.pos_kind.xyz, x));
                }
            }
            if (e.x + e.y + e.z == 0.0) {
                continue;
            }
            s += (ss * hg(dot(ray, l), fx.medium.z) * tl * visibility(li, x)) * e;
        }
    }
    textureStore(scatter_out, id, vec4f(s, st));
}
