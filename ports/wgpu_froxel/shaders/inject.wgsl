// Pass 1, light injection (Wronski 2014; Hillaire 2015): per froxel, (S, sigma_t) at its jittered sample,
// S = sigma_s sum_l p(d.l) V_l T_l E_l (TECHNIQUES.md `froxel`). Includes froxel_common and the killzone
// port's lights.wgsl (Light, incidence, the spot / cube-face map lookup) and cascade_lookup.wgsl.

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

// Distance stored by texel `t` of the lookup `m`'s layer (lights.wgsl, cascade_lookup.wgsl): spot / point, the
// radial distance from the light; directional, the distance from the cascade's view plane along the light.
fn stored_distance(li: Light, t: vec2i, m: MapLookup) -> f32 {
    if (li.pos_kind.w == 2.0) {
        return cascade_distance(t, m.layer);
    }
    return radial_distance(li, t, m.layer, m.tan_h);
}

// Shadow visibility 1 - strength (1 - lit) of light `li` at x: `shadow.w` 0 = hard (the texel holding the
// sample), 1 = pcf (2x2 texels around uv res - 1/2, compared, bilinear weights, clamped to the face).
// Directional lights use the first cascade whose sphere holds x (lit outside every one).
fn visibility(li: Light, x: vec3f) -> f32 {
    var m: MapLookup;
    if (li.pos_kind.w == 2.0) {
        m = cascade_lookup(li, x);
    } else {
        m = local_map_lookup(li, x);
    }
    if (m.layer < 0) {
        return 1.0;
    }
    let res = li.shadow.y;
    let last = vec2i(i32(res) - 1);
    var lit = 0.0;
    if (li.shadow.w == 0.0) {
        let t = clamp(vec2i(floor(m.uv * res)), vec2i(0), last);
        lit = select(0.0, 1.0, m.d_ref <= stored_distance(li, t, m));
    } else {
        let s = m.uv * res - 0.5;
        let f = floor(s);
        let wt = s - f;
        let t0 = vec2i(f);
        for (var e = 0; e < 4; e++) {
            let o = vec2i(e & 1, e >> 1);
            let t = clamp(t0 + o, vec2i(0), last);
            let ww = select(1.0 - wt, wt, vec2<bool>(o == vec2i(1)));
            lit += select(0.0, ww.x * ww.y, m.d_ref <= stored_distance(li, t, m));
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
            let inc = incidence(li, x);
            var tl = 1.0;    // light-leg extinction; none for a directional light (unbounded medium)
            if (fx.medium.w != 0.0 && li.pos_kind.w != 2.0) {
                tl = exp(-st * distance(li.pos_kind.xyz, x));
            }
            if (inc.e.x + inc.e.y + inc.e.z == 0.0) {
                continue;
            }
            s += (ss * hg(dot(ray, inc.l), fx.medium.z) * tl * visibility(li, x)) * inc.e;
        }
    }
    textureStore(scatter_out, id, vec4f(s, st));
}
