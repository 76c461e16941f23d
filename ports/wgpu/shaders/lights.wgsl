// Light incidence and shadow-map visibility (CONVENTIONS, vlref/lights/*.py docstrings), for shaders that
// declare `lights` (storage array<Light>), `shadow_tex` (texture_depth_2d_array) and the constant SKY.
// Shared by the killzone port and the froxel port (ports/wgpu_froxel), which both prepend this file.

struct Light {
    pos_kind: vec4f,        // position, kind (0 point, 1 spot, 2 directional: cascades.wgsl)
    dir_range: vec4f,       // direction of travel, range
    color_strength: vec4f,  // colour * intensity, shadow strength
    right_tan: vec4f,       // spot frame right, tan(spot_angle / 2)
    up_bias: vec4f,         // spot frame up, shadow bias
    cone: vec4f,            // cos outer, cos inner, half outer, half inner (radians)
    law: vec4f,             // attenuation law, cone law, unity A, unity B
    shadow: vec4f,          // first layer (-1: none), resolution, near, slope bias (froxel port: filter)
}
// A directional light (kind 2) uses: dir_range.xyz (unit direction of travel), color_strength, right_tan.xyz
// and up_bias.xyz (its frame: look_frame(direction)), cone.x (number of cascades), shadow.xy (first cascade
// in `cascade_tex`, -1: none; resolution).

override BUG_NO_RANGE_WINDOW: bool = false;   // windowed law without its (1 - (d/R)^4)^2 window
override BUG_SHADOW_HALF_TEXEL: bool = false; // nearest texel taken at u*res - 0.5 (texel-centre mix-up)
override BUG_CUBE_V_UP: bool = false;         // cube face v not flipped (GL-style t axis)
override BUG_UNITY_CONE_UNSQUARED: bool = false; // unity cone law saturate(a cos + b) without its square
override BUG_LINEAR_CONE_IN_COS: bool = false;   // linear cone law interpolated in cos instead of in angle
override BUG_UNITY_ATT_NO_FADE: bool = false;    // unity attenuation without its saturate(5 (1 - sqrt u)) fade
override BUG_STRENGTH_SWAPPED: bool = false;     // shadow strength as lerp(lit, 1, s) instead of lerp(1, lit, s)
override BUG_SHADOW_PLANAR: bool = false;        // stored depth taken as radial distance (no texel-ray factor)
override BUG_SHADOW_GROWN: bool = false;         // also shadowed by a neighbour texel's nearer caster (grown)
override BUG_SHADOW_SHRUNK: bool = false;        // also lit by a neighbour texel's farther surface (shrunk)

struct Incidence { l: vec3f, e: vec3f }

fn attenuation(li: Light, d2: f32) -> f32 {
    let r = li.dir_range.w;
    let u = d2 / (r * r);
    if (u >= 1.0) {
        return 0.0;
    }
    let law = i32(li.law.x);
    if (law == 1) {   // unity (folk LUT): 1/(1 + 25u) * saturate(5 (1 - sqrt u))
        let fade = select(clamp(5.0 * (1.0 - sqrt(u)), 0.0, 1.0), 1.0, BUG_UNITY_ATT_NO_FADE);
        return fade / (1.0 + 25.0 * u);
    }
    let inv = 1.0 / max(d2, 1e-4);
    if (law == 2 && !BUG_NO_RANGE_WINDOW) {   // windowed: saturate(1 - u^2)^2 / d^2
        let w = 1.0 - u * u;
        return w * w * inv;
    }
    return inv;
}

fn cone_falloff(li: Light, cos_t: f32) -> f32 {
    if (cos_t <= li.cone.x) {
        return 0.0;
    }
    let law = i32(li.law.y);
    if (law == 0) {
        let a = clamp(cos_t * li.law.z + li.law.w, 0.0, 1.0);
        return select(a * a, a, BUG_UNITY_CONE_UNSQUARED);
    }
    if (cos_t >= li.cone.y) {
        return 1.0;
    }
    if (law == 1) {
        if (BUG_LINEAR_CONE_IN_COS) {
            return clamp((cos_t - li.cone.x) / (li.cone.y - li.cone.x), 0.0, 1.0);
        }
        return clamp((li.cone.z - acos(cos_t)) / (li.cone.z - li.cone.w), 0.0, 1.0);
    }
    let x = (cos_t - li.cone.x) / (li.cone.y - li.cone.x);
    return x * x * (3.0 - 2.0 * x);
}

// E_l(x): colour * intensity * attenuation (* cone for spots); l the unit vector toward the light.
// Directional: colour * intensity (irradiance) from -direction.
fn incidence(li: Light, x: vec3f) -> Incidence {
    if (li.pos_kind.w == 2.0) {
        return Incidence(-li.dir_range.xyz, li.color_strength.xyz);
    }
    let w = li.pos_kind.xyz - x;
    let d2 = dot(w, w);
    var e = attenuation(li, d2);
    if (d2 == 0.0 || e == 0.0) {
        return Incidence(vec3f(0.0), vec3f(0.0));
    }
    let l = w / sqrt(d2);
    if (li.pos_kind.w == 1.0) {
        e *= cone_falloff(li, -dot(l, li.dir_range.xyz));
    }
    return Incidence(l, e * li.color_strength.xyz);
}

// Cube faces (right, up) in the D3D order +X, -X, +Y, -Y, +Z, -Z.
const CUBE_RIGHT = array<vec3f, 6>(vec3f(0, 0, -1), vec3f(0, 0, 1), vec3f(1, 0, 0), vec3f(1, 0, 0), vec3f(1, 0, 0), vec3f(-1, 0, 0));
const CUBE_UP = array<vec3f, 6>(vec3f(0, 1, 0), vec3f(0, 1, 0), vec3f(0, 0, -1), vec3f(0, 0, 1), vec3f(0, 1, 0), vec3f(0, 1, 0));

// Where light `li`'s map is read at x: the layer (-1: no lookup, lit), the texture coordinate uv of that
// layer (u right, v down), the distance d_ref the stored value is compared with, and tan_h, the tangent of
// the tile's half angle that turns a texel's depth into its ray's length (spot_angle / 2; cube face: 1).
struct MapLookup { uv: vec2f, layer: i32, d_ref: f32, tan_h: f32 }

// The lookup of a spot or point light: its map (spot) or the cube face the vector x - light leaves through;
// d_ref = |x - light|.
fn local_map_lookup(li: Light, x: vec3f) -> MapLookup {
    let layer0 = i32(li.shadow.x);
    let w = x - li.pos_kind.xyz;
    let none = MapLookup(vec2f(0.0), -1, 0.0, 1.0);
    if (layer0 < 0) {
        return none;
    }
    if (li.pos_kind.w == 1.0) {
        let zl = dot(w, li.dir_range.xyz);
        if (!(zl > 0.0)) {
            return none;
        }
        let k = 0.5 / (zl * li.right_tan.w);
        return MapLookup(vec2f(0.5 + dot(w, li.right_tan.xyz) * k, 0.5 - dot(w, li.up_bias.xyz) * k), layer0,
                         length(w), li.right_tan.w);
    }
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
        return none;
    }
    let sc = dot(w, CUBE_RIGHT[f]) / ma;
    let tc = dot(w, CUBE_UP[f]) / ma;
    return MapLookup(vec2f(0.5 + 0.5 * sc, select(0.5 - 0.5 * tc, 0.5 + 0.5 * tc, BUG_CUBE_V_UP)), layer0 + f,
                     length(w), 1.0);
}

// The radial distance from the light stored by texel t of `shadow_tex` layer `layer`: its reversed-Z depth
// decoded to eye depth, along the texel-centre ray; an empty texel (depth 0) is infinitely far (SKY).
fn radial_distance(li: Light, t: vec2i, layer: i32, tan_h: f32) -> f32 {
    let d = textureLoad(shadow_tex, t, layer, 0);
    if (d <= 0.0) {
        return SKY;
    }
    let n = li.shadow.z;
    let fr = li.dir_range.w;
    let z = fr * n / (d * (fr - n) + n);
    let c = (2.0 * (vec2f(t) + 0.5) / li.shadow.y - 1.0) * tan_h;
    return select(z * sqrt(1.0 + c.x * c.x + c.y * c.y), z, BUG_SHADOW_PLANAR);
}

// Visibility of a spot or point light `li` at x: ONE nearest texel (hard filter); lit when
// |x - light| <= stored; strength applied.
fn shadow_visibility(li: Light, x: vec3f) -> f32 {
    let m = local_map_lookup(li, x);
    if (m.layer < 0) {
        return 1.0;
    }
    let res = li.shadow.y;
    var st = m.uv * res;
    if (BUG_SHADOW_HALF_TEXEL) {
        st -= vec2f(0.5);
    }
    let texel = clamp(vec2i(floor(st)), vec2i(0), vec2i(i32(res) - 1));
    var stored = radial_distance(li, texel, m.layer, m.tan_h);
    if (BUG_SHADOW_GROWN || BUG_SHADOW_SHRUNK) {
        // a neighbour 10 % nearer (a caster's edge beside) or farther (a receiver beside) replaces the texel
        let own = stored;
        let last = vec2i(i32(res) - 1);
        for (var k = 0; k < 4; k++) {
            let step = select(vec2i(0, 2 * (k % 2) - 1), vec2i(2 * (k % 2) - 1, 0), k < 2);
            let other = radial_distance(li, clamp(texel + step, vec2i(0), last), m.layer, m.tan_h);
            if (BUG_SHADOW_GROWN && other < 0.9 * own) {
                stored = min(stored, other);
            }
            if (BUG_SHADOW_SHRUNK && 0.9 * other > own) {
                stored = max(stored, other);
            }
        }
    }
    let lit = select(0.0, 1.0, m.d_ref <= stored);
    if (BUG_STRENGTH_SWAPPED) {
        return mix(lit, 1.0, li.color_strength.w);
    }
    return 1.0 - li.color_strength.w * (1.0 - lit);
}
