"""The ``urp`` technique: Valerio Marty's "Raymarched Volumetric Lighting in Unity URP (Part 1)" (Medium,
SOURCES §2; the article's listing P1), pass by pass.

0. march (low res, ``render.resolution`` off/half/third/quarter): :func:`vlref.march.urp.urp_march`
   on the world position reconstructed from the point-sampled raw full-res depth; the hash buffer is
   ``jitter`` (or injected from ``techniques.urp.jitter_path``); stored R16 UNORM: ``march``;
1. blur X, 2. blur Y (``urp_article_blur_pass``: uv-unit offsets ``k · amount / 1000``, raw-depth
   weight ``exp(-(100 Δz)²)``), each stored R16: ``blur_h``, ``blur_v``;
4. depth downsample: the raw full-res depth point-sampled at each low-res centre, R16: ``depth_low``;
3. nearest-depth upsample over the cross neighbours (0,+1), (0,-1), (+1,0), (-1,0): ``upsample``;
   composite ``scene + F · intensity · colour`` (``final``), no extinction (``transmittance`` = 1).

One directional light: the first directional light of the scene (others are ignored, as URP's
"main light"); a scene with none is an :class:`~vlref.errors.InputError` naming ``render.technique``.
"""

from __future__ import annotations

import numpy as np

from ..camera import linear_to_raw, raw_to_linear
from ..errors import InputError
from ..io.images import read_image
from ..lights.pack import F_DX, F_DZ
from ..march.urp import urp_hash, urp_march
from ..post.blur import urp_article_blur_pass
from ..post.composite import composite_urp, unorm16
from ..post.downsample import downsample_point
from ..post.resolution import low_res_size
from ..post.upsample import urp_upsample
from ..scene.technique_params import resolved
from .main_light import has_main_light, main_light

__all__ = ["render", "main_light", "has_main_light", "load_jitter"]


def load_jitter(path: str, width: int, height: int, file: str = "<scene>") -> np.ndarray:
    """An injected hash buffer (.npy, or single-channel .exr), (height, width) in [0, 1), row 0 on top."""
    key = "techniques.urp.jitter_path"

    try:
        a = read_image(path, channels=1)
    except InputError as exc:
        raise InputError(file, key, exc.reason) from None
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if a.shape != (height, width):
        raise InputError(file, key, f"expected a ({height}, {width}) buffer (the march resolution), got {a.shape}")
    if not np.all((a >= 0.0) & (a < 1.0)):
        raise InputError(file, key, "values must lie in [0, 1)")
    return a


def render(scene, frame) -> dict:
    """Render the URP tutorial's passes of ``scene`` (module docstring)."""
    p = scene.techniques.urp
    li = main_light(scene)
    light = scene.lights[li]
    cam = frame.camera
    H, W = cam.height, cam.width
    resolution = resolved(scene, "resolution")
    n_steps = resolved(scene, "steps")
    if n_steps < 2:
        raise InputError(scene.source or "<scene>", "render.steps", "\"urp\" needs at least 2 steps "
                                                                      "(the loop runs steps - 1 times)")
    w, h = low_res_size(W, H, resolution)
    store = unorm16 if p.r16 else (lambda a: a)

    raw_full = linear_to_raw(np.minimum(frame.gbuffer.depth, cam.far), cam.near, cam.far, p.depth_convention)
    raw_lo = downsample_point(raw_full, resolution, p.uv_origin)
    dirs = cam.ray_directions(w, h)
    eye = raw_to_linear(raw_lo, cam.near, cam.far, p.depth_convention)
    length = np.minimum(eye / (dirs @ cam.forward), p.max_distance)
    rand = (load_jitter(p.jitter_path, w, h, scene.source or "<scene>") if p.jitter_path is not None
            else urp_hash(w, h, p.uv_origin))
    sm = frame.shadow_maps(p.shadow_filter)
    packed = frame.lights
    toward = -np.asarray(packed.floats[li, F_DX:F_DZ + 1], dtype=np.float64)
    fog = store(urp_march(np.asarray(cam.position, dtype=np.float64), dirs, length, rand, n_steps, p.jitter,
                          p.anisotropy, toward, sm.table, frame.geometry.arrays, packed.floats, li))
    blur_h = store(urp_article_blur_pass(fog, raw_full, 1, p.gauss_samples, p.gauss_amount, uv_origin=p.uv_origin))
    blur_v = store(urp_article_blur_pass(blur_h, raw_full, 0, p.gauss_samples, p.gauss_amount, uv_origin=p.uv_origin))
    depth_low = store(raw_lo)
    full = urp_upsample(blur_v, depth_low, raw_full, uv_origin=p.uv_origin)
    colour = np.asarray(light.color, dtype=np.float64)
    inscatter = (full * p.intensity)[..., None] * colour
    return {"jitter": rand, "march": fog, "blur_h": blur_h, "blur_v": blur_v, "depth_low": depth_low,
            "depth_raw": raw_full, "upsample": full, "inscatter": inscatter, "transmittance": np.ones((H, W)),
            "final": composite_urp(frame.scene_colour, full, p.intensity, colour)}
