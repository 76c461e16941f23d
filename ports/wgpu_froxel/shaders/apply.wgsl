// Pass 4, apply: per pixel, the integrated grid read by the hardware trilinear sampler at
// (u, v, (s - 1/2)/D), s the slice coordinate of the pixel's eye depth (sky and beyond: D); boundary 0 is
// (0, 0, 0, 1), so below the first texel (s < 1) the bilinear value of slice 0 is blended with it.
// final = scene T + L (alpha T); `inscatter_out` holds (L, T).

override BUG_HALF_TEXEL: bool = false;       // w = s / D (texel centres taken at the boundaries)
override BENIGN_WEIGHTS8: bool = false;      // trilinear_8bit instead of the sampler

@group(0) @binding(0) var<uniform> fx: Froxel;
@group(0) @binding(1) var<storage, read> slices: array<f32>;
@group(0) @binding(2) var depth_tex: texture_depth_2d;
@group(0) @binding(3) var integrated_tex: texture_3d<f32>;
@group(0) @binding(4) var lin: sampler;
@group(0) @binding(5) var colour_tex: texture_2d<f32>;
@group(0) @binding(6) var final_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var inscatter_out: texture_storage_2d<rgba16float, write>;

fn fetch(p: vec3f) -> vec4f {
    if (BENIGN_WEIGHTS8) {
        return trilinear_8bit(integrated_tex, p);
    }
    return textureSampleLevel(integrated_tex, lin, p, 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= u32(fx.size.x) || id.y >= u32(fx.size.y)) {
        return;
    }
    let px = vec2i(id.xy);
    let d = u32(fx.grid.z);
    let dd = f32(d);
    let s = depth_to_slice(0u, d, min(linear_depth(textureLoad(depth_tex, px, 0)), slices[d]));
    let uv = (vec2f(id.xy) + 0.5) / fx.size.xy;
    var v: vec4f;
    if (s >= 1.0) {
        v = fetch(vec3f(uv, select((s - 0.5) / dd, s / dd, BUG_HALF_TEXEL)));
    } else {
        v = mix(vec4f(0.0, 0.0, 0.0, 1.0), fetch(vec3f(uv, 0.5 / dd)), s);
    }
    let scene = textureLoad(colour_tex, px, 0).rgb;
    textureStore(final_out, px, vec4f(scene * v.a + v.rgb, v.a));
    textureStore(inscatter_out, px, v);
}
