"""Compositing the volumetric light over the scene, and the storage formats the sources round to.

Colours are linear HDR, ``(H, W, 3)`` (or ``(H, W, 4)`` where stated); per-pixel scalars ``(H, W)``.

Storage rounding (SOURCES §6.9) -- apply after the pass that writes the buffer:

* :func:`fp16` -- an ARGBHalf target (VL's light buffers): each value is first rounded to fp32 (the
  shader's ALU result), then to IEEE half with round-to-nearest-even. Values beyond the half range
  (65504) become ``+-65504`` with ``overflow="clamp"`` (the default, keeping buffers finite) or
  ``+-inf`` with ``overflow="inf"``; which one a GPU's blender does is [U].
* :func:`blend_add_fp16` -- one additive blend (``Blend One One``) into an fp16 target:
  ``fp16(fp32(dst) + fp32(src))``.
* :func:`unorm16` -- an R16 UNORM target (the URP tutorial's fog and low-res depth):
  ``rint(clip(x, 0, 1) * 65535) / 65535``.
* :func:`unorm8` -- an 8-bit UNORM target: ``rint(clip(x, 0, 1) * 255) / 255``.

``rint`` rounds half to even; D3D allows either neighbour at an exact half [K].
"""

from __future__ import annotations

import numpy as np
from numba import prange

from vlref.jit import njit
from vlref.post.resolution import check_choice

FP16_MAX = 65504.0


def _per_pixel(a, like: np.ndarray) -> np.ndarray:
    """An (H, W) factor broadcast over the channel axis of ``like``."""
    return _check_per_pixel(np.asarray(a, dtype=np.float64), like)[..., None]


def _check_per_pixel(a: np.ndarray, like: np.ndarray) -> np.ndarray:
    """``a``, after checking that it is (H, W) of the image ``like``."""
    if a.shape != like.shape[:2]:
        raise ValueError(f"factor: per-pixel factor {a.shape} does not match image {like.shape[:2]}")
    return a


def composite_physical(scene, transmittance, inscatter) -> np.ndarray:
    """``final = scene * T + L`` (the physical profile and the thesis): ``T`` (H, W), ``scene``, ``L`` (H, W, 3);
    float64, the same bits as NumPy's ``scene * T[..., None] + L``, rows in parallel (a frame's compositing
    ran on one core: BENCHMARKS.md "The rest of a frame on every core")."""
    scene = np.ascontiguousarray(scene, dtype=np.float64)
    # float32 stays float32: promoted per element, as NumPy does
    trans, light = _check_per_pixel(_floats(transmittance), scene), _floats(inscatter)
    if light.shape != scene.shape:
        raise ValueError(f"inscatter: shape {light.shape} does not match image {scene.shape}")
    out = np.empty(scene.shape)
    _composite(scene, trans, light, out)
    return out


def _floats(a) -> np.ndarray:
    """``a`` as a contiguous float32 or float64 array (other types as float64)."""
    a = np.ascontiguousarray(a)
    return a if a.dtype in (np.float32, np.float64) else a.astype(np.float64)


@njit(cache=True, fastmath=False, parallel=True)
def _composite(scene, trans, light, out):
    h, w, c = out.shape
    for i in prange(h):
        for j in range(w):
            for k in range(c):
                out[i, j, k] = scene[i, j, k] * trans[i, j] + light[i, j, k]


def sum_and_composite(per_light: np.ndarray, scene, transmittance) -> tuple[np.ndarray, np.ndarray]:
    """``(inscatter, final)``: the lights' sum ``Σ_k per_light[k]`` of ``per_light`` (n, H, W, 3), in light order
    (``((L_0 + L_1) + L_2) + …``) in the buffers' dtype (the same bits as NumPy's ``per_light.sum(axis=0)``; zeros
    without lights), and :func:`composite_physical` of ``scene``, ``transmittance`` and that sum (the same bits), in
    one parallel pass over the rows (one kernel to load in a fresh process, the sum read back from registers)."""
    per_light = np.ascontiguousarray(per_light)
    scene = np.ascontiguousarray(scene, dtype=np.float64)
    if per_light.shape[0] == 0:
        inscatter = np.zeros(per_light.shape[1:], dtype=per_light.dtype)
        return inscatter, composite_physical(scene, transmittance, inscatter)
    if per_light.shape[1:] != scene.shape:
        raise ValueError(f"inscatter: shape {per_light.shape[1:]} does not match image {scene.shape}")
    trans = _check_per_pixel(_floats(transmittance), scene)
    inscatter = np.empty(scene.shape, dtype=per_light.dtype)
    final = np.empty(scene.shape)
    _sum_composite(per_light, scene, trans, inscatter, final)
    return inscatter, final


@njit(cache=True, fastmath=False, parallel=True)
def _sum_composite(per_light, scene, trans, inscatter, final):
    n, h, w, c = per_light.shape
    for i in prange(h):
        for j in range(w):
            for k in range(c):
                acc = per_light[0, i, j, k]  # in the buffers' dtype, lights in order
                for m in range(1, n):
                    acc += per_light[m, i, j, k]
                inscatter[i, j, k] = acc
                final[i, j, k] = scene[i, j, k] * trans[i, j] + acc  # as _composite, reading the stored sum


def composite_vl(scene, volume) -> np.ndarray:
    """VolumetricLights' ``BlitAdd`` (SOURCES §1.11): ``rgb = scene_rgb * V_a + V_rgb``, ``a = scene_a * V_a``.

    ``volume`` is the full-res RGBA light buffer ``(H, W, 4)``; its alpha is the transmittance of
    the last directional light drawn (1 without one). ``scene`` is ``(H, W, 3)`` or ``(H, W, 4)``;
    the result has the same channels.
    """
    scene = np.asarray(scene, dtype=np.float64)
    volume = np.asarray(volume, dtype=np.float64)
    if volume.ndim != 3 or volume.shape[2] != 4 or scene.ndim != 3 or scene.shape[2] not in (3, 4):
        raise ValueError(f"volume: need scene (H, W, 3|4) and volume (H, W, 4), got "
                                              f"{scene.shape} and {volume.shape}")
    va = volume[..., 3:4]
    out = scene.copy()
    out[..., :3] = scene[..., :3] * va + volume[..., :3]
    if scene.shape[2] == 4:
        out[..., 3:4] = scene[..., 3:4] * va
    return out


def composite_urp(scene, fog, intensity: float = 1.0, colour=(1.0, 1.0, 1.0)) -> np.ndarray:
    """The URP tutorial's composite (SOURCES §2.7): ``scene + (F * intensity) * colour``.

    ``fog`` is the upsampled scalar fog ``F`` (H, W); ``colour`` is ``_SunMoonColor`` = the light's
    colour *without* its intensity; no extinction is applied to the scene.
    """
    scene = np.asarray(scene, dtype=np.float64)
    return scene + (_per_pixel(fog, scene) * intensity) * np.asarray(colour, dtype=np.float64)


def composite_add(scene, light, exposure: float = 1.0) -> np.ndarray:
    """``scene + light * exposure``: the radial techniques' composite (GPU Gems 3 ch. 13, disenone).

    ``light`` is (H, W, 3) or (H, W) (broadcast over the colour channels).
    """
    scene = np.asarray(scene, dtype=np.float64)
    light = np.asarray(light, dtype=np.float64)
    if light.ndim == 2:
        light = _per_pixel(light, scene)
    return scene + light * exposure


def fp16(x, overflow: str = "clamp") -> np.ndarray:
    """Round to fp32, then to IEEE half (nearest even); returned as float64 holding the half values."""
    check_choice("overflow", overflow, ("clamp", "inf"))
    x32 = np.asarray(x, dtype=np.float32)
    if overflow == "clamp":
        x32 = np.clip(x32, np.float32(-FP16_MAX), np.float32(FP16_MAX))
    with np.errstate(over="ignore"):
        return x32.astype(np.float16).astype(np.float64)


def blend_add_fp16(dst, src, overflow: str = "clamp") -> np.ndarray:
    """One additive blend into an fp16 target: ``fp16(fp32(dst) + fp32(src))``."""
    return fp16(np.asarray(dst, dtype=np.float32) + np.asarray(src, dtype=np.float32), overflow)


def _unorm(x, levels: int) -> np.ndarray:
    return np.rint(np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0) * levels) / levels


def unorm16(x) -> np.ndarray:
    """R16 UNORM storage: clamp to [0, 1], quantise to ``k / 65535``."""
    return _unorm(x, 65535)


def unorm8(x) -> np.ndarray:
    """8-bit UNORM storage: clamp to [0, 1], quantise to ``k / 255``."""
    return _unorm(x, 255)
