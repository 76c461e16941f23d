// One cascade of a directional light's shadow map into a depth32float layer: orthographic, reversed-Z
// (depth 1 - z/far on the tile's view axis, which is the light's direction of travel). Bias is applied
// caster-side along the parallel texel rays (CONVENTIONS.md): the depth written is that of
// z + bias + slope_bias * min(tan a, 10), a the angle between the caster's normal and the light.
struct Tile {
    view_proj: mat4x4f,
    view: mat4x4f,
    params: vec4f,   // 0, far, bias, slope bias
}
@group(0) @binding(0) var<uniform> tile: Tile;

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
    let c = abs(normalize(v.nv).z);
    let slope = min(sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-12), 10.0);
    let z = v.pv.z + tile.params.z + tile.params.w * slope;
    return clamp(1.0 - z / tile.params.y, 0.0, 1.0);
}
