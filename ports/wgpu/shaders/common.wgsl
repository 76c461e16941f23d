// Shared types and helpers of the killzone port (docs/CONVENTIONS.md, docs/TECHNIQUES.md).
// Every shader that includes this file declares `g` (group 0, binding 0).

struct Globals {
    view_proj: mat4x4f,
    eye: vec4f,
    right: vec4f,
    up: vec4f,
    fwd: vec4f,
    cam: vec4f,      // tan(fov/2), aspect W/H, near, far
    medium: vec4f,   // render.max_distance, sigma_s, sigma_t, g (Henyey-Greenstein)
    size: vec4f,     // W, H, w, h (frame and march target)
    march: vec4f,    // steps, lights, epsilon (m), blur sigma (texels)
    ambient: vec4f,
    sky: vec4f,
}

const SKY: f32 = 3.0e38;   // linear depth of sky pixels (finite stand-in for inf)
const PI: f32 = 3.14159265358979;

struct FullscreenOut { @builtin(position) pos: vec4f }

// One triangle covering the viewport (vertices 0, 1, 2).
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> FullscreenOut {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return FullscreenOut(vec4f(uv * 2.0 - 1.0, 0.0, 1.0));
}

// Unit world ray through the pixel centre `px` (framebuffer coordinates: x right, y down from the top,
// centres at +0.5) of a target of `size` covering the camera frustum (CONVENTIONS: NDC (2u-1, 1-2v)).
fn pixel_ray(px: vec2f, size: vec2f) -> vec3f {
    let ndc = vec2f(2.0 * px.x / size.x - 1.0, 1.0 - 2.0 * px.y / size.y);
    let t = g.cam.x;
    return normalize(g.fwd.xyz + (ndc.x * t * g.cam.y) * g.right.xyz + (ndc.y * t) * g.up.xyz);
}

// Reversed-Z device depth (1 at near, 0 at far) -> linear eye depth; 0 (cleared) is sky.
fn linear_depth(d: f32) -> f32 {
    if (d <= 0.0) {
        return SKY;
    }
    let n = g.cam.z;
    let f = g.cam.w;
    return f * n / (d * (f - n) + n);
}

// |a - b| with equal values (sky and sky) exactly 0.
fn depth_delta(a: f32, b: f32) -> f32 {
    return select(abs(a - b), 0.0, a == b);
}
