"""Deliberately wrong "ports" for tests/test_planted_bugs.py: vlref's own passes, one planted mistake each.

Each case names a scene (bundled, with ``--set`` overrides chosen so that the mistake is visible), the
tolerance preset a GPU port of that configuration would be held to, and a function ``port(scene)`` that
returns the port's ``final`` image. ``correct_port`` is the faithful port: the same passes run with
``render.precision = "float32"`` where the technique has it, and the light buffer stored as fp16
(ARGBHalf), as a GPU port would -- it must pass where every planted port must fail.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from vlref.post.blur import depth_delta
from vlref.post.resolution import bilinear_footprint
from vlref.render import prepare_frame
from vlref.techniques import TECHNIQUES


@dataclass(frozen=True)
class Case:
    name: str
    scene: str
    overrides: tuple[str, ...]
    preset: str
    port: Callable


def _run(scene, frame=None) -> dict:
    frame = prepare_frame(scene) if frame is None else frame
    return TECHNIQUES[scene.render.technique].render(scene, frame)


def correct_port(scene) -> np.ndarray:
    """The faithful float32 port: float32 march where supported, light buffer rounded through fp16."""
    if scene.render.technique == "physical":
        scene = scene.replace(render=dataclasses.replace(scene.render, precision="float32"))
    frame = prepare_frame(scene)
    out = _run(scene, frame)
    light = out["inscatter"].astype(np.float16).astype(np.float64)
    return (frame.scene_colour * out["transmittance"][..., None] + light).astype(np.float32)


def hg_sign_flipped(scene) -> np.ndarray:
    """``p_HG(-cos θ, g)``: the port takes the view direction toward the camera; ``= p_HG(cos θ, -g)``."""
    medium = dataclasses.replace(scene.medium, anisotropy=-scene.medium.anisotropy)
    return _run(scene.replace(medium=medium))["final"]


def beer_lambert_left_out(scene) -> np.ndarray:
    """No extinction: neither the march's running transmittance nor the view transmittance of the surface."""
    p = dataclasses.replace(scene.techniques.killzone, transmittance=False)
    return _run(scene.replace(techniques=dataclasses.replace(scene.techniques, killzone=p)))["final"]


def bayer_off_by_one(scene, monkeypatch) -> np.ndarray:
    """The Bayer texture indexed at ``x + 1``: every pixel takes its right neighbour's offset."""
    import vlref.techniques.killzone as kz

    original = kz.offsets
    monkeypatch.setattr(kz, "offsets", lambda *a, **k: np.roll(original(*a, **k), -1, axis=1))
    return _run(scene)["final"]


def _transposed_upsample(lo, depth_lo, depth_hi, epsilon=1e-3):
    """The thesis upsample with its bilinear weights transposed: 3/16 to the wrong neighbours
    (``t_x`` and ``t_y`` swapped), each still divided by ``|Δz| + ε`` and normalised."""
    lo, zl, zh = np.asarray(lo, float), np.asarray(depth_lo, float), np.asarray(depth_hi, float)
    r0, r1, ty = bilinear_footprint(lo.shape[0], zh.shape[0])
    c0, c1, tx = bilinear_footprint(lo.shape[1], zh.shape[1])
    tx, ty = np.broadcast_to(tx[None, :], zh.shape), np.broadcast_to(ty[:, None], zh.shape)
    taps = ((r0, c0, (1 - ty) * (1 - tx)), (r0, c1, ty * (1 - tx)), (r1, c0, (1 - ty) * tx), (r1, c1, tx * ty))
    w = [b / (depth_delta(zh, zl[rows][:, cols]) + epsilon) for rows, cols, b in taps]
    dead = sum(w) == 0.0  # every tap infinitely far in depth: bilinear weights alone, as the original
    w = [np.where(dead, b, wk) for (_, _, b), wk in zip(taps, w)]
    acc = sum(wk[..., None] * lo[rows][:, cols] for (rows, cols, _), wk in zip(taps, w))
    return acc / sum(w)[..., None]


def upsample_transposed(scene, monkeypatch) -> np.ndarray:
    import vlref.techniques.killzone as kz

    monkeypatch.setattr(kz, "thesis_upsample", _transposed_upsample)
    return _run(scene)["final"]


def depth_half_pixel(scene) -> np.ndarray:
    """The depth buffer read half a texel to the right with bilinear filtering (a ``+0.5/W`` uv error)."""
    frame = prepare_frame(scene)
    g = frame.gbuffer
    shifted = np.concatenate([g.depth[:, 1:], g.depth[:, -1:]], axis=1)
    depth = np.where(np.isfinite(g.depth) & np.isfinite(shifted), 0.5 * (g.depth + shifted),
                     np.minimum(g.depth, shifted))
    distance = frame.camera.eye_depth_to_distance(depth)
    frame.gbuffer = dataclasses.replace(g, depth=depth, distance=distance)
    return _run(scene, frame)["final"]


def shadow_bias_x10(scene) -> np.ndarray:
    """Every shadow map rendered with ten times the scene's constant bias."""
    lights = tuple(dataclasses.replace(l, shadows=dataclasses.replace(l.shadows, bias=10 * l.shadows.bias))
                   if l.shadows is not None else l for l in scene.lights)
    return _run(scene.replace(lights=lights))["final"]


def cone_half_for_full(scene) -> np.ndarray:
    """``spot_angle`` (Unity's FULL angle) used as the half angle: a cone twice as wide (map fov too)."""
    lights = tuple(dataclasses.replace(l, spot_angle=min(2 * l.spot_angle, 170.0)) if l.type == "spot" else l
                   for l in scene.lights)
    return _run(scene.replace(lights=lights))["final"]


SIZE = ("render.width=64", "render.height=36", "lights.0.shadows.resolution=256")
CASES = (
    Case("hg_sign", "radial_sun", SIZE + ('render.technique="physical"', "render.steps=16", "medium.anisotropy=0.6"),
         "gpu-full", hg_sign_flipped),
    Case("beer_lambert", "valley", SIZE + ('render.technique="killzone"', "render.steps=16"), "gpu-half",
         beer_lambert_left_out),
    Case("bayer_off_by_one", "pillars", SIZE + ('render.technique="killzone"', "render.steps=8"), "gpu-half",
         bayer_off_by_one),
    Case("upsample_transposed", "pillars", SIZE + ('render.technique="killzone"', "render.steps=16"), "gpu-half",
         upsample_transposed),
    Case("depth_half_pixel", "pillars", SIZE + ('render.technique="physical"', "render.steps=16"), "gpu-full",
         depth_half_pixel),
    Case("shadow_bias_x10", "cage", SIZE + ('render.technique="physical"', "render.steps=16"), "gpu-full",
         shadow_bias_x10),
    Case("cone_angle_convention", "pillars", SIZE + ('render.technique="physical"', "render.steps=16"), "gpu-full",
         cone_half_for_full),
)
