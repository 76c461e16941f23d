// Pass 3: the lit scene colour (deferred): albedo (sum E max(0, n.l) V / pi + ambient); sky colour. V: one
// texel of the light's map (spot, point) or of its cascade (directional), looked up offset along the normal.
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var shadow_tex: texture_depth_2d_array;
@group(0) @binding(3) var depth_tex: texture_depth_2d;
@group(0) @binding(4) var normal_tex: texture_2d<f32>;
@group(0) @binding(5) var albedo_tex: texture_2d<f32>;
@group(0) @binding(6) var cascade_tex: texture_depth_2d_array;
@group(0) @binding(7) var<storage, read> cascades: array<vec4f>;

override BUG_NO_INV_PI: bool = false;         // Lambert without its 1/pi
override BUG_EYE_DEPTH_AS_RANGE: bool = false; // surface point at eye depth along the ray (as if ray length)
override BUG_SUN_TRAVEL_DIR: bool = false;    // directional: n.l with the direction of travel, not toward the light
override BUG_NO_NORMAL_OFFSET: bool = false;  // directional: cascade looked up at the surface point itself (acne)

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let px = vec2i(pos.xy);
    let z = linear_depth(textureLoad(depth_tex, px, 0));
    if (z >= SKY) {
        return vec4f(g.sky.xyz, 1.0);
    }
    let d = pixel_ray(pos.xy, g.size.xy);
    let n = textureLoad(normal_tex, px, 0).xyz;
    let x = g.eye.xyz + d * select(z / dot(d, g.fwd.xyz), z, BUG_EYE_DEPTH_AS_RANGE) + 1e-3 * n;
    var s = vec3f(0.0);
    for (var k = 0u; k < arrayLength(&lights); k++) {
        let li = lights[k];
        let inc = incidence(li, x);
        let sun = li.pos_kind.w == 2.0;
        let cos_n = dot(n, select(inc.l, -inc.l, BUG_SUN_TRAVEL_DIR && sun));
        if (cos_n > 0.0) {
            var v: f32;
            if (sun) {
                v = cascade_visibility(li, x, select(n, vec3f(0.0), BUG_NO_NORMAL_OFFSET));
            } else {
                v = shadow_visibility(li, x + local_normal_offset(li, x, n, cos_n));
            }
            s += inc.e * cos_n * v;
        }
    }
    let albedo = textureLoad(albedo_tex, px, 0).xyz;
    return vec4f(albedo * (s / select(PI, 1.0, BUG_NO_INV_PI) + g.ambient.xyz), 1.0);
}
