// Shared block and helpers of the froxel port (docs/TECHNIQUES.md `froxel`, docs/CONVENTIONS.md).
// Every shader that includes this file declares `fx` (group 0, binding 0) and `slices` (binding 1).

struct Froxel {
    view_proj: mat4x4f,       // this frame: world -> clip, reversed-Z, clip.w = eye depth
    prev_view_proj: mat4x4f,  // the previous frame's (reprojection)
    eye: vec4f,
    right: vec4f,
    up: vec4f,
    fwd: vec4f,
    cam: vec4f,      // tan(fov/2), aspect W/H, near, far
    grid: vec4f,     // gw, gh, D, frame
    jitter: vec4f,   // sample offset xi (x, y, z) inside every froxel, history alpha
    medium: vec4f,   // sigma_s, sigma_t, g (Henyey-Greenstein), light-leg extinction (0/1)
    size: vec4f,     // W, H, lights, frame-count cap ceil(1/alpha)
    prev: vec4f,     // previous grid gw, gh, D; offset of its boundaries in `slices`
    flags: vec4f,    // history clamp (0/1), history present (0/1)
}

const SKY: f32 = 3.0e38;   // linear depth of sky pixels (finite stand-in for inf)
const PI: f32 = 3.14159265358979;

// Unit world ray through screen uv (u right, v down from the top): the camera's NDC (2u - 1, 1 - 2v).
fn screen_ray(uv: vec2f) -> vec3f {
    let t = fx.cam.x;
    let ndc = vec2f(2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y);
    return normalize(fx.fwd.xyz + (ndc.x * t * fx.cam.y) * fx.right.xyz + (ndc.y * t) * fx.up.xyz);
}

// The ray of column c, row r of this frame's grid through slice coordinates (c + ox, r + oy).
fn column_ray(c: u32, r: u32, ox: f32, oy: f32) -> vec3f {
    return screen_ray(vec2f((f32(c) + ox) / fx.grid.x, (f32(r) + oy) / fx.grid.y));
}

// Reversed-Z device depth (1 at near, 0 at far) -> linear eye depth; 0 (cleared) is sky.
fn linear_depth(d: f32) -> f32 {
    if (d <= 0.0) {
        return SKY;
    }
    let n = fx.cam.z;
    let f = fx.cam.w;
    return f * n / (d * (f - n) + n);
}

// Continuous slice coordinate in [0, d] of eye depth z over the d + 1 boundaries slices[base .. base + d]
// (linear inside a slice; binary search).
fn depth_to_slice(base: u32, d: u32, z: f32) -> f32 {
    if (!(z > slices[base])) {
        return 0.0;
    }
    if (z >= slices[base + d]) {
        return f32(d);
    }
    var lo = 0u;
    var hi = d;
    loop {
        if (hi - lo <= 1u) {
            break;
        }
        let mid = (lo + hi) / 2u;
        if (slices[base + mid] <= z) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return f32(lo) + (z - slices[base + lo]) / (slices[base + lo + 1u] - slices[base + lo]);
}

// Trilinear, clamp-to-edge fetch at normalised coordinates `p` with the sub-texel weights rounded to
// 1/256: what a GPU's texture unit computes (8-bit fractions), written out to run on any adapter.
fn trilinear_8bit(tex: texture_3d<f32>, p: vec3f) -> vec4f {
    let size = vec3i(textureDimensions(tex));
    let q = p * vec3f(size) - 0.5;
    let f = floor(q);
    let w = round((q - f) * 256.0) / 256.0;
    let i0 = vec3i(f);
    var acc = vec4f(0.0);
    for (var e = 0; e < 8; e++) {
        let o = vec3i(e & 1, (e >> 1) & 1, (e >> 2) & 1);
        let i = clamp(i0 + o, vec3i(0), size - 1);
        let ww = select(1.0 - w, w, vec3<bool>(o == vec3i(1)));
        acc += ww.x * ww.y * ww.z * textureLoad(tex, i, 0);
    }
    return acc;
}
