"""Sections ``raycast``, ``shadow_maps`` and ``post``: the frame's stages and each post pass, plus the
explorer notebook's ``preview`` re-render."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import camera_from_settings
from ..geometry import build_geometry, raycast
from ..lights import pack_lights
from ..lights.shadow_cast import build_shadow_maps
from ..notebook import PreviewRenderer
from ..post.blur import blur_hv, thesis_blur_pass
from ..post.composite import composite_physical
from ..post.downsample import downsample_min
from ..post.radial import radial_blur
from ..post.upsample import thesis_upsample, urp_upsample, vl_upsample
from ..render import render
from ..scene import load_scene
from .config import BenchConfig, bench_scene, median_time

__all__ = ["bench_geometry", "bench_post", "post_passes", "SINGLE_POST_PASSES"]

SINGLE_POST_PASSES = ("downsample_min_half", "thesis_upsample", "vl_upsample", "urp_upsample", "bilateral_blur_h",
                      "bilateral_blur_v", "composite")
"""The passes of :func:`post_passes` that are one pass each (not the radial blur, which has a target of its own, nor
the bilateral blur's two passes together): the issue's "every other post pass ≤ 10 ms" is read on these."""


def bench_geometry(cfg: BenchConfig) -> tuple[dict, dict]:
    """Raycast (primary rays/s) and shadow maps (texels/s) of (b), plus the bundled scenes."""
    def measure(scene):
        cam = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
        geo = build_geometry(scene)
        packed = pack_lights(scene)
        rc = median_time(lambda: raycast(scene, cam, geo), cfg.repeats, min_seconds=cfg.min_seconds)
        sm_seconds = median_time(lambda: build_shadow_maps(scene, cam, geo, packed), cfg.repeats,
                                 min_seconds=cfg.min_seconds)
        texels = int(build_shadow_maps(scene, cam, geo, packed).data.size)
        rays = scene.render.width * scene.render.height
        return ({"width": scene.render.width, "height": scene.render.height, "seconds": rc, "rays_per_s": rays / rc},
                {"texels": texels, "seconds": sm_seconds, "texels_per_s": texels / sm_seconds})

    rc, sm = measure(bench_scene(cfg.width, cfg.height, cfg.steps, "four", cfg.shadow_resolution))
    rc_out, sm_out = {"bench_four_lights": rc}, {"bench_four_lights": sm}
    for name in cfg.bundled:
        rc_out[name], sm_out[name] = measure(load_scene(name, ["render.width=320", "render.height=180"]))
    return rc_out, sm_out


def post_passes(h: int, w: int) -> dict:
    """Each post pass at ``w x h`` as a call without arguments, on fixed inputs (``default_rng(0)``; half-resolution
    inputs where the pass takes them): what :func:`bench_post` times and benchmarks/post_ab.py compares.
    ``bilateral_blur_h`` and ``bilateral_blur_v``: the blur's two passes (the thesis's 7 taps) one at a time, each into
    a new array (the vertical one on the horizontal one's output); ``bilateral_blur_hv``: both, two new arrays;
    ``bilateral_blur_hv_into``: both as the Killzone technique calls them, the vertical pass into a buffer the caller
    owns (its pages mapped by the previous call)."""
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 30.0, size=(h, w))
    depth_lo = downsample_min(depth, "half")
    lo = rng.random(depth_lo.shape + (3,))
    full = rng.random((h, w, 3))
    trans = rng.random((h, w))
    spare = np.empty_like(full)
    across = thesis_blur_pass(full, depth, 1)
    return {
        "downsample_min_half": lambda: downsample_min(depth, "half"),
        "thesis_upsample": lambda: thesis_upsample(lo, depth_lo, depth),
        "vl_upsample": lambda: vl_upsample(lo, depth_lo, depth),
        "urp_upsample": lambda: urp_upsample(lo, depth_lo, depth),
        "bilateral_blur_h": lambda: thesis_blur_pass(full, depth, 1),
        "bilateral_blur_v": lambda: thesis_blur_pass(across, depth, 0),
        "bilateral_blur_hv": lambda: blur_hv(thesis_blur_pass, full, depth),
        "bilateral_blur_hv_into": lambda: blur_hv(thesis_blur_pass, full, depth, out=spare),
        "radial_blur_64": lambda: radial_blur(full, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3),
        "composite": lambda: composite_physical(full, trans, full),
    }


def bench_post(cfg: BenchConfig) -> dict:
    """Each post pass at ``cfg.width x cfg.height`` (:func:`post_passes`), and the explorer's preview re-render."""
    h, w = cfg.height, cfg.width
    passes = post_passes(h, w)
    out = {name: {"seconds": median_time(fn, cfg.repeats, min_seconds=cfg.min_seconds), "width": w, "height": h}
           for name, fn in passes.items()}
    pw, ph, steps = cfg.preview
    scene = bench_scene(pw, ph, steps, "one", cfg.shadow_resolution, technique="killzone", resolution="half")
    # A slider move re-renders with the frame (geometry, G-buffer, shadow maps) reused, as the explorer
    # notebook does; the first render (frame included) is timed too.
    first = render(scene).timings
    renderer = PreviewRenderer()
    renderer.render(scene)
    variants = [scene.replace(medium=dataclasses.replace(scene.medium, anisotropy=g)) for g in (0.3, 0.5)]
    count = [0]

    def preview():
        count[0] += 1
        renderer.render(variants[count[0] % 2])

    seconds = median_time(preview, cfg.repeats)
    out["preview"] = {"seconds": seconds, "width": pw, "height": ph, "steps": steps, "technique": "killzone",
                      "resolution": "half", "what": "re-render after a medium change, frame reused",
                      "first_render_stages": dict(first)}
    return out
