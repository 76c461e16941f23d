// One cascade of a directional light's shadow map, appended to the killzone port's shadow.wgsl (its Tile
// block, params = (0, far, bias, slope bias), and vertex stage): orthographic, reversed-Z depth 1 - z/far on
// the tile's view axis, the light's direction of travel. Bias is applied caster-side along the parallel
// texel rays (CONVENTIONS.md): the depth written is that of z + bias + slope_bias * min(tan a, 10), a the
// angle between the caster's normal and the light.

@fragment
fn fs_ortho(v: VsOut) -> @builtin(frag_depth) f32 {
    let c = abs(normalize(v.nv).z);
    let slope = min(sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-12), 10.0);
    let z = v.pv.z + tile.params.z + tile.params.w * slope;
    return clamp(1.0 - z / tile.params.y, 0.0, 1.0);
}
