// Pass 2: one shadow tile (spot map or cube face) into a depth32float layer, reversed-Z.
// Bias is applied caster-side along the texel's ray (vlref/lights/shadow_cast.py): the depth written is
// that of the point at radial distance r + bias + slope_bias * min(tan a, 10) on the same ray.
struct Tile {
    view_proj: mat4x4f,
    view: mat4x4f,
    params: vec4f,   // near, far (= range), bias, slope bias
}
@group(0) @binding(0) var<uniform> tile: Tile;

override BUG_BIAS_SIGN: bool = false;   // caster-side bias subtracted: r - bias (the caster moves toward the light)
override BUG_SLOPE_COT: bool = false;   // slope as cos/sin (cot) instead of sin/cos (tan)

struct VsOut {
    @builtin(position) pos: vec4f,
    @location(0) pv: vec3f,
    @location(1) nv: vec3f,
}

@vertex
fn vs_main(@location(0) p: vec3f, @location(1) n: vec3f, @location(2) albedo: vec3f) -> VsOut {
    return VsOut(tile.view_proj * vec4f(p, 1.0), (tile.view * vec4f(p, 1.0)).xyz, (tile.view * vec4f(n, 0.0)).xyz);
}

@fragment
fn fs_main(v: VsOut) -> @builtin(frag_depth) f32 {
    let r = length(v.pv);
    let c = abs(dot(normalize(v.nv), v.pv / r));
    let s = sqrt(max(1.0 - c * c, 0.0));
    let slope = min(select(s / max(c, 1e-12), c / max(s, 1e-12), BUG_SLOPE_COT), 10.0);
    let bias = tile.params.z + tile.params.w * slope;
    let z = v.pv.z * (r + select(bias, -bias, BUG_BIAS_SIGN)) / r;
    let n = tile.params.x;
    let f = tile.params.y;
    return clamp(n * (f / z - 1.0) / (f - n), 0.0, 1.0);
}
