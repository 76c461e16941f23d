// Pass 5: one light's volume mesh (back faces, additive blend into the fp16 march target), marched per
// fragment (thesis 4.2.2, 4.2.5; Vos): t_i = a + (beta + i) step, step = (b - a) / N,
// L += T_i sigma_s p_HG(d.l_i) E_l(x_i) V_l(x_i) step,  T_{i+1} = T_i exp(-sigma_t step),  T_0 = exp(-sigma_t t_0).
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var shadow_tex: texture_depth_2d_array;
@group(0) @binding(3) var depth_lo: texture_2d<f32>;
@group(1) @binding(0) var<uniform> light_index: vec4u;

override BUG_STEPS_MINUS_ONE: bool = false;  // loop runs N - 1 samples (step still (b - a) / N)
override BUG_ADVANCE_TWICE: bool = false;    // t advanced by the step at the top and the bottom of the loop
override BUG_BAYER_TRANSPOSED: bool = false; // B[x mod 4][y mod 4]
override BUG_SIGMA_S_FOR_T: bool = false;    // extinction taken as the scattering coefficient
override BUG_NO_MAX_DISTANCE: bool = false;  // view ray cut at the scene depth only, not at render.max_distance
override BUG_BALL_T0_UNCLAMPED: bool = false; // ray-ball entry not clamped at the eye (camera inside a volume)
override BUG_PHASE_SCHLICK: bool = false;    // Schlick's approximation (k = 1.55 g - 0.55 g^3) instead of HG

const BAYER4 = array<u32, 16>(0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);

@vertex
fn vs_volume(@location(0) p: vec3f) -> @builtin(position) vec4f {
    return g.view_proj * vec4f(p, 1.0);
}

fn hg(cos_t: f32, gg: f32) -> f32 {
    if (BUG_PHASE_SCHLICK) {
        let k = 1.55 * gg - 0.55 * gg * gg * gg;
        let q = 1.0 + k * cos_t;
        return (1.0 - k * k) / (4.0 * PI * q * q);
    }
    let k = 1.0 + gg * gg - 2.0 * gg * cos_t;
    return (1.0 - gg * gg) / (4.0 * PI * k * sqrt(k));
}

// [t0, t1] of the ray o + t d inside the ball |x - p| <= R; empty when t1 <= t0.
fn ball(p: vec3f, r: f32, o: vec3f, d: vec3f, t_end: f32) -> vec2f {
    let v = o - p;
    let beta = -dot(v, d);
    let h = v + beta * d;
    let disc = r * r - dot(h, h);
    if (!(disc > 0.0)) {
        return vec2f(0.0);
    }
    let s = sqrt(disc);
    return vec2f(select(max(beta - s, 0.0), beta - s, BUG_BALL_T0_UNCLAMPED), min(beta + s, t_end));
}

fn in_cone(li: Light, x: vec3f) -> bool {
    let w = x - li.pos_kind.xyz;
    return dot(w, li.dir_range.xyz) >= li.cone.x * length(w);
}

// Ball inside the cone of half-angle spot_angle/2: the ball's interval is cut at the roots of
// (a.(x-p))^2 = cos^2 |x-p|^2 that fall inside it; each piece is classified at its midpoint.
fn spot_segment(li: Light, o: vec3f, d: vec3f, t_end: f32) -> vec2f {
    let s = ball(li.pos_kind.xyz, li.dir_range.w, o, d, t_end);
    if (!(s.y > s.x)) {
        return s;
    }
    let a = li.dir_range.xyz;
    let v = o - li.pos_kind.xyz;
    let c2 = li.cone.x * li.cone.x;
    let da = dot(d, a);
    let va = dot(v, a);
    let qa = da * da - c2;
    let qb = 2.0 * (da * va - c2 * dot(d, v));
    let qc = va * va - c2 * dot(v, v);
    var cuts = array<f32, 4>(s.x, s.y, s.y, s.y);
    let disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
        let q = -0.5 * (qb + select(-sqrt(disc), sqrt(disc), qb >= 0.0));
        var r1 = s.y;
        var r2 = s.y;
        if (qa != 0.0) {
            r1 = q / qa;
        }
        if (q != 0.0) {
            r2 = qc / q;
        }
        let lo = min(r1, r2);
        let hi = max(r1, r2);
        cuts[1] = select(s.y, lo, lo > s.x && lo < s.y);
        cuts[2] = select(s.y, hi, hi > s.x && hi < s.y);
        if (cuts[1] == s.y) {
            cuts[1] = cuts[2];
            cuts[2] = s.y;
        }
    }
    var first = s.y;
    var last = s.x;
    for (var k = 0; k < 3; k++) {
        let e0 = cuts[k];
        let e1 = cuts[k + 1];
        if (e1 > e0 && in_cone(li, o + (0.5 * (e0 + e1)) * d)) {
            first = min(first, e0);
            last = e1;
        }
    }
    return vec2f(first, last);
}

@fragment
fn fs_march(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let li = lights[light_index.x];
    let px = vec2u(pos.xy);
    let d = pixel_ray(pos.xy, g.size.zw);
    let t_surf = textureLoad(depth_lo, px, 0).r / dot(d, g.fwd.xyz);
    let t_end = select(min(t_surf, g.medium.x), t_surf, BUG_NO_MAX_DISTANCE);
    var seg: vec2f;
    if (li.pos_kind.w == 1.0) {
        seg = spot_segment(li, g.eye.xyz, d, t_end);
    } else {
        seg = ball(li.pos_kind.xyz, li.dir_range.w, g.eye.xyz, d, t_end);
    }
    if (!(seg.y > seg.x)) {
        discard;
    }
    let n = u32(g.march.x);
    let step = (seg.y - seg.x) / f32(n);
    let b = px % 4u;
    let beta = f32(select(BAYER4[b.y * 4u + b.x], BAYER4[b.x * 4u + b.y], BUG_BAYER_TRANSPOSED)) / 16.0;
    let sigma_t = select(g.medium.z, g.medium.y, BUG_SIGMA_S_FOR_T);
    var t = seg.x + beta * step;
    var trans = exp(-sigma_t * t);
    let decay = exp(-sigma_t * step);
    var acc = vec3f(0.0);
    let count = select(n, n - 1u, BUG_STEPS_MINUS_ONE);
    for (var i = 0u; i < count; i++) {
        if (BUG_ADVANCE_TWICE) {
            t += step;
        }
        let x = g.eye.xyz + t * d;
        let inc = incidence(li, x);
        if (any(inc.e > vec3f(0.0))) {
            let k = trans * g.medium.y * hg(dot(d, inc.l), g.medium.w) * step;
            acc += k * inc.e * shadow_visibility(li, x);
        }
        trans *= decay;
        t += step;
    }
    return vec4f(acc, 0.0);
}
