"""The ``killzone`` technique: the thesis (TH in docs/SOURCES.md) after Vos, "Volumetric Light Effects in Killzone:
Shadow Fall" (GPU Pro 5; SOURCES §4), pass by pass.

1. depth: linear eye depth min-downsampled to each calculation resolution in use (thesis §4.2.3:
   "finding the smallest value using a min function"): ``depth_half``, ``depth_quarter``;
2. per light, at its calculation resolution (``light_resolutions`` or ``render.resolution``): the
   view-ray segment inside its volume (sphere / cone / full screen) up to the scene depth and
   ``render.max_distance``, marched by :func:`vlref.march.killzone.kz_march` with the Bayer offset
   of the march target (``offsets_<res>``); lights of one resolution are summed: ``march_<res>``;
3. quarter is upsampled into half, half into full (thesis §4.2.3) by the depth-aware bilateral
   upsample 9/16, 3/16, 1/16 / |Δz| (§4.2.4): ``upsample_half``, ``upsample``; each is added to the
   buffer of the next resolution;
4. separable bilateral Gaussian blur, 7 taps (§4.2.6), H then V on the full-res buffer:
   ``blur_h``, ``blur_v`` (= ``inscatter``);
5. composite ``final = scene · T + L`` with ``T = exp(-τ(0, t_surf))`` (``transmittance``).
"""

from __future__ import annotations


import numpy as np

from ..errors import InputError
from ..march.killzone import kz_march, kz_segments, view_transmittance
from ..march.patterns import offsets
from ..medium import pack_medium
from ..post.blur import blur_hv, thesis_blur_pass
from ..post.composite import composite_physical
from ..post.downsample import downsample_min
from ..post.resolution import low_res_size
from ..post.upsample import thesis_upsample
from ..scene.technique_params import resolved

__all__ = ["render", "light_resolutions"]

ORDER = ("quarter", "half", "full")


def light_resolutions(scene) -> list[str]:
    """Each light's calculation resolution: ``light_resolutions[i]`` or ``render.resolution``."""
    p = scene.techniques.killzone
    default = resolved(scene, "resolution")
    out = []
    for i in range(len(scene.lights)):
        res = p.light_resolutions[i] if i < len(p.light_resolutions) else default
        if res not in ORDER:
            key = f"techniques.killzone.light_resolutions[{i}]" if i < len(p.light_resolutions) else "render.resolution"
            raise InputError(scene.source or "<scene>", key, f"must be one of {', '.join(ORDER)} (render.technique = "
                                                               f"\"killzone\"), got {res!r}")
        out.append(res)
    return out


def render(scene, frame) -> dict:
    """Render the thesis passes of ``scene`` (module docstring); returns the buffers named there."""
    p = scene.techniques.killzone
    cam = frame.camera
    H, W = cam.height, cam.width
    n_steps = resolved(scene, "steps")
    sampling = resolved(scene, "sampling")
    res_of = light_resolutions(scene)
    med = pack_medium(scene)
    packed = frame.lights
    sm = frame.shadow_maps(p.shadow_filter)
    camp = np.asarray(cam.position, dtype=np.float64)
    depth = frame.gbuffer.depth

    out: dict[str, np.ndarray] = {}
    depth_of = {"full": depth}
    buffers: dict[str, np.ndarray] = {}
    for res in ORDER:
        lights = [i for i, r in enumerate(res_of) if r == res]
        if not lights and not (res == "half" and "quarter" in res_of) and res != "full":
            continue
        if res != "full":
            depth_of[res] = downsample_min(depth, res)
            out[f"depth_{res}"] = depth_of[res]
        w, h = low_res_size(W, H, res)
        buf = np.zeros((h, w, 3))
        if lights:
            dirs = cam.ray_directions(w, h)
            t_end = np.minimum(depth_of[res] / (dirs @ cam.forward), scene.render.max_distance)
            beta = offsets(sampling, w, h, scene.render.seed)
            out[f"offsets_{res}"] = beta
            for i in lights:
                a, b = kz_segments(camp, dirs, t_end, packed, i)
                buf += kz_march(camp, dirs, a, b, beta, n_steps, i, packed, med, sm.table, frame.geometry.arrays,
                                p.transmittance)
            out[f"march_{res}"] = buf.copy()
        prev = {"half": "quarter", "full": "half"}.get(res)
        if prev in buffers:
            up = thesis_upsample(buffers[prev], depth_of[prev], depth_of[res], p.upsample_epsilon)
            out["upsample" if res == "full" else f"upsample_{res}"] = up
            buf = buf + up
        buffers[res] = buf

    light = buffers["full"]
    if p.blur:  # the vertical pass writes into the full-resolution sums (this function's own; stored as copies)
        blur_h, light = blur_hv(thesis_blur_pass, light, depth, out=light, radius=p.blur_radius,
                                sigma=p.blur_sigma, depth_factor=p.blur_depth_factor,
                                depth_weight_kind=p.blur_depth_weight, epsilon=p.upsample_epsilon)
        out["blur_h"], out["blur_v"] = blur_h, light
    dirs = cam.ray_directions()
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    trans = (view_transmittance(camp, dirs, t_end, med) if p.transmittance
             else np.ones((H, W)))
    out["inscatter"] = light
    out["transmittance"] = trans
    out["final"] = composite_physical(frame.scene_colour, trans, light)
    return out
