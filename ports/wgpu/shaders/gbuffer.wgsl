// Pass 1: the scene's triangles into depth32float (reversed-Z) + normal + albedo.
@group(0) @binding(0) var<uniform> g: Globals;

struct VsOut {
    @builtin(position) pos: vec4f,
    @location(0) normal: vec3f,
    @location(1) albedo: vec3f,
}

@vertex
fn vs_main(@location(0) p: vec3f, @location(1) n: vec3f, @location(2) albedo: vec3f) -> VsOut {
    return VsOut(g.view_proj * vec4f(p, 1.0), n, albedo);
}

struct GOut {
    @location(0) normal: vec4f,
    @location(1) albedo: vec4f,
}

@fragment
fn fs_main(v: VsOut, @builtin(front_facing) front: bool) -> GOut {
    var n = normalize(v.normal);
    // flat normals of either winding: face the camera
    let d = pixel_ray(v.pos.xy, g.size.xy);
    if (dot(n, d) > 0.0) {
        n = -n;
    }
    return GOut(vec4f(n, 0.0), vec4f(v.albedo, 1.0));
}
