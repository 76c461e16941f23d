// Cascaded shadow maps of directional lights (kind 2 of lights.wgsl's Light), for shaders that include
// lights.wgsl and declare `cascade_tex` (texture_depth_2d_array: one orthographic reversed-Z layer per
// cascade, cascade.wgsl) and `cascades` (storage array<vec4f>, two per cascade: (centre, radius) of the
// bounding sphere of its slice of the view frustum, and (back, far, -, -): the distance from its view plane
// to the centre and its far plane). Shared by the killzone port's scene colour and the froxel port's injection.

// The lookup in the first of the light's cascades whose sphere holds x (layer -1 outside every one: lit):
// uv in the light's frame (right, up) scaled by the sphere, d_ref the distance of x from the cascade's view
// plane along the light.
fn cascade_lookup(li: Light, x: vec3f) -> MapLookup {
    let first = i32(li.shadow.x);
    for (var k = first; first >= 0 && k < first + i32(li.cone.x); k++) {
        let sphere = cascades[2 * k];
        let w = x - sphere.xyz;
        if (dot(w, w) <= sphere.w * sphere.w) {
            let uv = 0.5 + vec2f(0.5, -0.5) * vec2f(dot(w, li.right_tan.xyz), dot(w, li.up_bias.xyz)) / sphere.w;
            return MapLookup(uv, k, dot(w, li.dir_range.xyz) + cascades[2 * k + 1].x, 1.0);
        }
    }
    return MapLookup(vec2f(0.0), -1, 0.0, 1.0);
}

// The distance from cascade `layer`'s view plane stored by texel t (1 - z/far decoded); empty texels
// (nothing before the far plane) are infinitely far (SKY).
fn cascade_distance(t: vec2i, layer: i32) -> f32 {
    let dc = textureLoad(cascade_tex, t, layer, 0);
    return select((1.0 - dc) * cascades[2 * layer + 1].y, SKY, dc <= 0.0);
}

const NORMAL_OFFSET_TEXELS: f32 = 1.5;

// The normal offset of a spot or point light's lookup at the surface point x of normal n (cos_n = n.l):
// NORMAL_OFFSET_TEXELS texels of its map at x's distance (2 d tan(half fov) / res), times 1 - n.l, as
// cascade_visibility offsets the sun's: a receiver's own map climbs by more than the bias over a texel where the
// light grazes it, and a lookup at the point itself would shadow it (acne).
fn local_normal_offset(li: Light, x: vec3f, n: vec3f, cos_n: f32) -> vec3f {
    let m = local_map_lookup(li, x);
    if (m.layer < 0) {
        return vec3f(0.0);
    }
    return n * (NORMAL_OFFSET_TEXELS * 2.0 * m.d_ref * m.tan_h / li.shadow.y * (1.0 - cos_n));
}

// Visibility of a directional light `li` at the surface point x of normal n: ONE nearest texel of its cascade
// (hard filter, as shadow_visibility); strength applied. The point is looked up offset along its normal by
// NORMAL_OFFSET_TEXELS texels of the cascade that holds it, times 1 - n.l (normal-offset shadows, Holbert
// 2011): under a low sun one texel of a receiver's own map spans more depth than the caster-side bias, so a
// point looked up on its surface would shadow itself (acne); vlref shades surfaces with exact shadow rays.
fn cascade_visibility(li: Light, x: vec3f, n: vec3f) -> f32 {
    let at = cascade_lookup(li, x);
    if (at.layer < 0) {
        return 1.0;
    }
    let texel = 2.0 * cascades[2 * at.layer].w / li.shadow.y;
    let m = cascade_lookup(li, x + n * (NORMAL_OFFSET_TEXELS * texel * (1.0 - max(-dot(n, li.dir_range.xyz), 0.0))));
    if (m.layer < 0) {
        return 1.0;
    }
    let t = clamp(vec2i(floor(m.uv * li.shadow.y)), vec2i(0), vec2i(i32(li.shadow.y) - 1));
    let lit = select(0.0, 1.0, m.d_ref <= cascade_distance(t, m.layer));
    return 1.0 - li.color_strength.w * (1.0 - lit);
}
