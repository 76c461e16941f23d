// Pass 9: final = scene * T + L with T = exp(-sigma_t min(t_surf, max_distance)) (thesis 2.2.4); alpha = T.
@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var light_tex: texture_2d<f32>;
@group(0) @binding(2) var colour_tex: texture_2d<f32>;
@group(0) @binding(3) var depth_tex: texture_depth_2d;

override BUG_SIGMA_S_FOR_T: bool = false;  // extinction taken as the scattering coefficient
override BUG_T_ON_LIGHT: bool = false;     // the in-scattered light attenuated too: (scene + L) T

@fragment
fn fs_main(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let px = vec2i(pos.xy);
    let d = pixel_ray(pos.xy, g.size.xy);
    let t = min(linear_depth(textureLoad(depth_tex, px, 0)) / dot(d, g.fwd.xyz), g.medium.x);
    let trans = exp(-select(g.medium.z, g.medium.y, BUG_SIGMA_S_FOR_T) * t);
    let l = textureLoad(light_tex, px, 0).rgb;
    let scene = textureLoad(colour_tex, px, 0).rgb;
    return vec4f(select(scene * trans + l, (scene + l) * trans, BUG_T_ON_LIGHT), trans);
}
