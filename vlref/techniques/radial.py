"""The ``radial`` technique: GPU Gems 3 ch. 13 (Mitchell, Listing 13-1) and disenone's Unity port,
SOURCES §3.

Passes (buffers at the occlusion target's size ``W_o x H_o``; ``H_o = occlusion_height`` or the frame
height, ``W_o = floor(H_o · aspect)``):

1. ``occlusion``: 1 where the camera ray leaves the scene, 0 on opaque surfaces, and through
   transparent occluders the light they pass: ``gpugems`` the RGB transmittance ``Π (1 - opacity) tint``
   of the transparent surfaces in front of the first opaque one; ``disenone`` its replacement shaders
   over a white background, ``α (1 - α) + (1 - α) occ`` with ``α = 1 - mean transmittance`` (one layer);
2. ``light_image``: ``gpugems`` the occlusion times the light's colour (clamped to [0, 1]: the pre-pass is
   an LDR target, light bright and occluders black) inside an anti-aliased disc (:func:`disc_coverage`) of
   ``light_radius`` pixels around the light's screen position [U: the disc is ours; the light's intensity
   does not enter, or one tap alone would saturate]; ``disenone`` ``radiate`` (peak 0.5, parabolic falloff,
   white);
3. ``radial``: the radial loop, Listing 13-1 (``radial_blur``) or disenone's 32-tap variant
   (``disenone_scatter``), before exposure;
4. ``inscatter`` = radial x exposure (x the fade factor, x visibility), bilinearly upsampled to the
   frame when the target is smaller; ``final`` = scene + inscatter; ``transmittance`` = 1.

Light position: a directional light is the point at infinity ``-direction``; a light behind the camera
gives visibility 0 (no effect); an off-screen light keeps its off-screen uv (taps clamp to the edge).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..camera import camera_from_settings
from ..errors import InputError
from ..geometry import raycast, shadow_transmittance
from ..jit import njit
from ..post.composite import composite_add
from ..post.radial import (disenone_exposure, disenone_scatter, light_screen_uv, occlusion_opaque,
                           occlusion_transparent, radial_blur, radiate)
from ..post.upsample import bilinear_upsample

__all__ = ["render", "notes", "radial_light", "light_target", "light_in_frame", "variant_params", "occlusion_buffer", "disc_coverage",
           "VARIANT_DEFAULTS"]

VARIANT_DEFAULTS = {
    "gpugems": dict(num_samples=100, density=0.84, weight=5.65, decay=1.0, exposure=0.0034, fade=False),
    "disenone": dict(num_samples=32, density=1.0, weight=1.0 / 32.0, decay=1.0, exposure=0.8, fade=True),
}
"""gpugems: F. Sanglard's GLSL port (NOT the book's, which has none); disenone: its C# ``Params``."""
GPUGEMS_DISC_FRACTION = 0.05
DISENONE_RADIUS_PX = 100.0


def disc_coverage(width: int, height: int, uv, radius: float) -> np.ndarray:
    """Pixel coverage (height, width) of a disc of ``radius`` pixels centred at ``uv`` (image uv, v down).

    ``clip(radius + 1/2 - r, 0, 1)``, ``r`` the distance of the pixel centre from the disc centre in pixels:
    the area a straight edge covers of a 1-pixel box, so the rim is anti-aliased (a hard ``r <= radius``
    test gives a staircase rim that the radial loop magnifies by ``1 / (1 - Density)``).
    """
    u, v = (np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height
    r = np.hypot((u[None, :] - uv[0]) * width, (v[:, None] - uv[1]) * height)
    return np.clip(radius + 0.5 - r, 0.0, 1.0)


def variant_params(p) -> dict:
    """The effective loop parameters: each unset (None) field takes its variant's default."""
    out = dict(VARIANT_DEFAULTS[p.variant])
    for k in out:
        if getattr(p, k) is not None:
            out[k] = getattr(p, k)
    return out


def radial_light(scene) -> int:
    """``techniques.radial.light``, or the first directional light, or light 0."""
    p = scene.techniques.radial
    if p.light >= 0:
        if p.light >= len(scene.lights):
            raise InputError(scene.source or "<scene>", "techniques.radial.light",
                             f"no light {p.light} (the scene has {len(scene.lights)})")
        return p.light
    return next((i for i, l in enumerate(scene.lights) if l.type == "directional"), 0)


def light_target(light) -> np.ndarray:
    """The light's homogeneous world position: ``(-direction, 0)`` (at infinity) for a directional light."""
    if light.type == "directional":
        return np.array([*(-np.asarray(light.direction, dtype=np.float64)), 0.0])
    return np.array([*light.position, 1.0])


def light_in_frame(scene) -> bool:
    """The golden suite's rule (:mod:`vlref.techniques`): the radial light projects inside the frame, in front
    of the camera; a blur centred off screen (or behind the camera, where the technique fades to nothing)
    tests only its edge clamping."""
    cam = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
    (u, v), visible = light_screen_uv(cam.view_projection() @ light_target(scene.lights[radial_light(scene)]))
    return bool(visible > 0.0 and 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0)


@njit(cache=True, fastmath=False, parallel=True)
def _transparent_pass(geo, cam, dirs, t_opaque):
    """RGB transmittance of the transparent surfaces in front of each pixel's opaque hit, prange over pixels."""
    h, w = t_opaque.shape
    out = np.ones((h, w, 3))
    for p in prange(h * w):
        r, c = p // w, p % w
        tr, tg, tb = shadow_transmittance(geo, cam[0], cam[1], cam[2], dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2],
                                          t_opaque[r, c])
        out[r, c, 0], out[r, c, 1], out[r, c, 2] = tr, tg, tb
    return out


def occlusion_buffer(scene, frame, width: int, height: int, variant: str) -> np.ndarray:
    """The occlusion pre-pass (module docstring, pass 1), (height, width, 3)."""
    cam = frame.camera
    g = frame.gbuffer if (width, height) == (cam.width, cam.height) else raycast(scene, cam.with_size(width, height),
                                                                                  frame.geometry)
    dirs = cam.ray_directions(width, height)
    t_opaque = np.where(np.isfinite(g.distance), g.distance, 1e30)
    trans = _transparent_pass(frame.geometry.arrays, np.asarray(cam.position, dtype=np.float64), dirs, t_opaque)
    sky = occlusion_opaque(g.object_id)
    if variant == "gpugems":
        return sky[..., None] * trans
    return occlusion_transparent(sky, 1.0 - trans.mean(axis=2), mode="disenone")


def render(scene, frame) -> dict:
    """Render the radial technique of ``scene`` (module docstring)."""
    p = scene.techniques.radial
    v = variant_params(p)
    cam = frame.camera
    H, W = cam.height, cam.width
    ho = p.occlusion_height or H
    wo = max(1, int(math.floor(ho * cam.aspect))) if p.occlusion_height else W
    li = radial_light(scene)
    light = scene.lights[li]
    target = light_target(light)
    uv, visibility = light_screen_uv(cam.view_projection() @ target)
    occ = occlusion_buffer(scene, frame, wo, ho, p.variant)

    to_light = target[:3] if light.type == "directional" else target[:3] - cam.position
    cos_a = float(to_light @ cam.forward) / float(np.linalg.norm(to_light))
    angle = math.degrees(math.acos(min(1.0, max(-1.0, cos_a))))
    exposure = disenone_exposure(v["exposure"], angle, cam.fov / 2.0) if v["fade"] else v["exposure"]
    if p.variant == "gpugems":
        radius = p.light_radius if p.light_radius is not None else GPUGEMS_DISC_FRACTION * ho
        colour = np.minimum(np.asarray(light.color, dtype=np.float64), 1.0)
        image = occ * disc_coverage(wo, ho, uv, radius)[..., None] * colour
        rad = radial_blur(image, uv, v["num_samples"], v["density"], v["weight"], v["decay"], 1.0)
    else:
        radius = p.light_radius if p.light_radius is not None else DISENONE_RADIUS_PX
        image = radiate(occ, uv, radius)
        rad = disenone_scatter(image, uv, v["density"], v["weight"], v["decay"], v["num_samples"],
                               v["num_samples"] - 1)
    light_lo = rad * (exposure * visibility)
    inscatter = light_lo if (wo, ho) == (W, H) else bilinear_upsample(light_lo, (H, W))
    return {"occlusion": occ, "light_image": image, "radial": rad, "inscatter": inscatter,
            "transmittance": np.ones((H, W)), "final": composite_add(frame.scene_colour, inscatter)}


def notes(scene, out) -> list[str]:
    """What ``vlref render`` tells the user: without a medium, a hard horizon is faithful."""
    if scene.lights[radial_light(scene)].type == "directional":
        return []
    return ["radial: no medium, so nothing dims the far scene: the hard horizon against the sky is the scene's "
            "own, faithful to GPU Gems 3 ch. 13 (a screen-space blur around the light; docs/TECHNIQUES.md, "
            "Faithful artifacts)"]
