// Pass 3, front-to-back integration (Hillaire 2015, slides 27-28) along each column's centre ray:
// L += T S (1 - e^{-sigma_t D})/sigma_t, then T *= e^{-sigma_t D}; (L, T) stored at each slice's FAR boundary.

override BUG_BACK_TO_FRONT: bool = false;        // walks the slices from the far end
override BUG_NO_TRANSMITTANCE_CARRY: bool = false; // T restarts at every slice (not carried)
override BENIGN_OPTICAL_DEPTH: bool = false;     // T = exp(-sum sigma_t D) instead of the running product

@group(0) @binding(0) var<uniform> fx: Froxel;
@group(0) @binding(1) var<storage, read> slices: array<f32>;
@group(0) @binding(2) var lit_tex: texture_3d<f32>;
@group(0) @binding(3) var integrated_out: texture_storage_3d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let d = u32(fx.grid.z);
    if (id.x >= u32(fx.grid.x) || id.y >= u32(fx.grid.y)) {
        return;
    }
    let cos_f = dot(column_ray(id.x, id.y, 0.5, 0.5), fx.fwd.xyz);
    var l = vec3f(0.0);
    var t = 1.0;
    var tau = 0.0;
    for (var i = 0u; i < d; i++) {
        let k = select(i, d - 1u - i, BUG_BACK_TO_FRONT);
        let delta = (slices[k + 1u] - slices[k]) / cos_f;
        let v = textureLoad(lit_tex, vec3i(i32(id.x), i32(id.y), i32(k)), 0);
        let ext = exp(-v.w * delta);
        let s_int = select((1.0 - ext) / v.w, delta, v.w == 0.0);
        if (BUG_NO_TRANSMITTANCE_CARRY) {
            l += v.rgb * s_int;
            t = ext;
        } else {
            l += t * v.rgb * s_int;
            tau += v.w * delta;
            t = select(t * ext, exp(-tau), BENIGN_OPTICAL_DEPTH);
        }
        textureStore(integrated_out, vec3i(i32(id.x), i32(id.y), i32(k)), vec4f(l, t));
    }
}
