// Pass 2, temporal reprojection (TECHNIQUES.md `froxel`, vlref/froxel/temporal.py's docstring): each
// froxel CENTRE through the previous view-projection, rejected outside the previous frustum or behind the
// previous tile depth (+ one previous slice), else the history fetched with the hardware trilinear
// sampler, optionally clamped to this frame's 3x3x3 neighbourhood, blended with alpha_n = max(alpha, 1/(n+1)).

override BUG_CURRENT_VP: bool = false;     // reprojects with this frame's view-projection
override BUG_NO_CLAMP: bool = false;       // skips the neighbourhood clamp the scene asks for
override BENIGN_WEIGHTS8: bool = false;    // history fetched by trilinear_8bit instead of the sampler

@group(0) @binding(0) var<uniform> fx: Froxel;
@group(0) @binding(1) var<storage, read> slices: array<f32>;
@group(0) @binding(2) var scatter_tex: texture_3d<f32>;
@group(0) @binding(3) var hist_tex: texture_3d<f32>;
@group(0) @binding(4) var count_tex: texture_3d<f32>;
@group(0) @binding(5) var<storage, read> prev_tile: array<f32>;
@group(0) @binding(6) var lin: sampler;
@group(0) @binding(7) var hist_out: texture_storage_3d<rgba16float, write>;
@group(0) @binding(8) var count_out: texture_storage_3d<rgba16float, write>;

fn fetch(tex: texture_3d<f32>, p: vec3f) -> vec4f {
    if (BENIGN_WEIGHTS8) {
        return trilinear_8bit(tex, p);
    }
    return textureSampleLevel(tex, lin, p, 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let gw = u32(fx.grid.x);
    let gh = u32(fx.grid.y);
    let d = u32(fx.grid.z);
    if (id.x >= gw || id.y >= gh || id.z >= d) {
        return;
    }
    let cur = textureLoad(scatter_tex, vec3i(id), 0);
    var ok = fx.flags.y != 0.0;
    var u = 0.0;
    var v = 0.0;
    var s = 0.0;
    let pgw = u32(fx.prev.x);
    let pgh = u32(fx.prev.y);
    let pd = u32(fx.prev.z);
    let pb = u32(fx.prev.w);
    var cw = 0.0;
    if (ok) {
        let ray = column_ray(id.x, id.y, 0.5, 0.5);
        let k = id.z;
        let x = fx.eye.xyz + (0.5 * (slices[k] + slices[k + 1u]) / dot(ray, fx.fwd.xyz)) * ray;
        var vp = fx.prev_view_proj;
        if (BUG_CURRENT_VP) {
            vp = fx.view_proj;
        }
        let clip = vp * vec4f(x, 1.0);
        cw = clip.w;
        ok = cw > 0.0 && cw <= slices[pb + pd];
        if (ok) {
            u = 0.5 + 0.5 * clip.x / cw;
            v = 0.5 - 0.5 * clip.y / cw;
            ok = u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0;
        }
    }
    if (ok) {
        s = depth_to_slice(pb, pd, cw);
        let px = min(u32(u * f32(pgw)), pgw - 1u);
        let py = min(u32(v * f32(pgh)), pgh - 1u);
        let sk = min(u32(s), pd - 1u);
        ok = cw <= prev_tile[py * pgw + px] + (slices[pb + sk + 1u] - slices[pb + sk]);
    }
    if (!ok) {
        textureStore(hist_out, id, cur);
        textureStore(count_out, id, vec4f(1.0, 0.0, 0.0, 0.0));
        return;
    }
    let p = vec3f(u, v, s / f32(pd));
    var h = fetch(hist_tex, p);
    let n = fetch(count_tex, p).x;
    if (fx.flags.x != 0.0 && !BUG_NO_CLAMP) {
        var lo = vec4f(3.0e38);
        var hi = vec4f(-3.0e38);
        let top = vec3i(i32(gw) - 1, i32(gh) - 1, i32(d) - 1);
        let c = vec3i(id);
        for (var e = 0; e < 27; e++) {
            let q = c + vec3i(e % 3 - 1, (e / 3) % 3 - 1, e / 9 - 1);
            if (all(q >= vec3i(0)) && all(q <= top)) {
                let t = textureLoad(scatter_tex, q, 0);
                lo = min(lo, t);
                hi = max(hi, t);
            }
        }
        h = clamp(h, lo, hi);
    }
    let a = max(fx.jitter.w, 1.0 / (n + 1.0));
    textureStore(hist_out, id, h + a * (cur - h));
    textureStore(count_out, id, vec4f(min(n + 1.0, fx.size.w), 1.0, 0.0, 0.0));
}
