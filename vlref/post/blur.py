"""Separable depth-aware ("bilateral") Gaussian blur: one function per pass and per source.

Each ``*_pass(values, depth, axis, ...)`` blurs along ``axis`` (1 = horizontal, 0 = vertical) and
returns its buffer; a source's blur is its horizontal pass followed by its vertical pass on the
result (:func:`blur_hv`). ``values`` is ``(H, W)`` or ``(H, W, C)``; every pass computes

    out = sum_k G_k W_k v_k / sum_k G_k W_k,

accumulated in the source's tap order (listed per pass) in float64. Taps beyond the image use
clamp addressing (the sources' RT wrap modes are [U], research §1.9/§7).

Depth weight ``W_k`` of a tap with depth difference ``dz = |z_k - z_0|`` (:func:`depth_delta`, with
``inf - inf = 0`` so sky matches sky): ``"gaussian"`` ``exp(-(dz * c) * (dz * c))`` (VL, URP) or
``"inverse"`` ``1 / (dz + eps)`` (the thesis's "in the same way as the bilateral up-sampling").
"""

from __future__ import annotations

import math

import numpy as np

from vlref.errors import InputError
from vlref.post.resolution import ARGUMENTS, check_choice, check_positive, nearest_index, point_texel, uv_rows

VL_KERNEL_RADIUS = {"full": 7, "half": 5, "quarter": 6}
"""``FULL/HALF/QUARTER_RES_BLUR_KERNEL_SIZE`` of VL's ``BilateralBlur.shader``."""

URP_GAUSS_WEIGHTS = (0.14446445, 0.13543542, 0.11153505, 0.08055309, 0.05087564, 0.02798160, 0.01332457,
                     0.00545096)
"""``gauss_filter_weights[0..7]`` of the URP tutorial (research §2.5)."""

DEPTH_WEIGHTS = ("gaussian", "inverse")


def depth_delta(a, b) -> np.ndarray:
    """``|a - b|`` with equal values (``inf`` and ``inf`` included) giving exactly 0."""
    with np.errstate(invalid="ignore"):
        return np.where(a == b, 0.0, np.abs(np.subtract(a, b, dtype=np.float64)))


def depth_weight(dz, kind: str = "gaussian", factor: float = 1.0, epsilon: float = 1e-3) -> np.ndarray:
    """``exp(-(dz*factor)^2)`` (``"gaussian"``) or ``1/(dz + epsilon)`` (``"inverse"``, ``epsilon > 0``).

    0 for ``dz = inf``; ``factor = 0`` gives 1 everywhere (no depth term).
    """
    check_choice("depth_weight", kind, DEPTH_WEIGHTS)
    if kind == "gaussian":
        if factor == 0.0:                       # no depth term (and no inf * 0 for sky)
            return np.ones(np.shape(dz))
        s = dz * factor
        return np.exp(-(s * s))
    check_positive("epsilon", epsilon)
    return 1.0 / (dz + epsilon)


def gaussian_weights(radius: int, sigma: float) -> np.ndarray:
    """``G(i) = exp(-i^2 / (2 sigma^2)) / sqrt(2 pi sigma^2)``, ``i = 0..radius`` (VL ``GaussianWeight``)."""
    if radius < 0 or not sigma > 0:
        raise InputError(ARGUMENTS, "blur", f"need radius >= 0 and sigma > 0, got {radius}, {sigma}")
    i = np.arange(radius + 1, dtype=np.float64)
    return (1.0 / math.sqrt(2.0 * math.pi * sigma * sigma)) * np.exp(-(i * i) / (2.0 * sigma * sigma))


def _weighted_mean(terms) -> np.ndarray:
    """``sum w v / sum w`` over ``terms = [(w (H,W), v (H,W[,C])), ...]``, summed left to right."""
    acc = wsum = 0.0
    for w, v in terms:
        acc = acc + (w[..., None] if v.ndim == 3 else w) * v
        wsum = wsum + w
    return acc / (wsum[..., None] if np.ndim(acc) == 3 else wsum)


def _values(values) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64)
    if v.ndim not in (2, 3):
        raise InputError(ARGUMENTS, "values", f"expected (H, W) or (H, W, C), got shape {v.shape}")
    return v


def _shift(a: np.ndarray, axis: int, k: int) -> np.ndarray:
    """``a`` read at integer offset ``k`` along ``axis`` with clamp addressing."""
    n = a.shape[axis]
    return a.take(np.clip(np.arange(n) + k, 0, n - 1), axis=axis)


def bilateral_pass(values, depth, axis: int, gauss, depth_factor: float = 1.0, depth_weight_kind: str = "gaussian",
                   epsilon: float = 1e-3, keep_alpha: bool = False) -> np.ndarray:
    """One pass with taps at integer texel offsets ``k = -K..K`` (``K = len(gauss) - 1``), value and
    depth read at the same texel of the same resolution (thesis §4.2.6; VL §1.9).

    Tap order (VL ``BilateralBlur``): the centre, then ``k = -K..-1``, then ``k = 1..K``; tap ``k``
    weighs ``gauss[|k|] * W(dz_k)``, the centre ``gauss[0] * W(0)`` (1 for ``"gaussian"``). ``keep_alpha``: the last
    channel is the centre texel's, not blurred (VL's alpha carries the transmittance).
    """
    check_choice("axis", axis, (0, 1))
    v = _values(values)
    z = np.asarray(depth, dtype=np.float64)
    if z.shape != v.shape[:2]:
        raise InputError(ARGUMENTS, "depth", f"depth shape {z.shape} does not match values {v.shape[:2]}")
    g = np.asarray(gauss, dtype=np.float64)
    radius = len(g) - 1
    centre_w = np.full(z.shape, g[0]) * depth_weight(np.zeros(z.shape), depth_weight_kind, depth_factor, epsilon)
    terms = [(centre_w, v)]
    for k in list(range(-radius, 0)) + list(range(1, radius + 1)):
        w = g[abs(k)] * depth_weight(depth_delta(z, _shift(z, axis, k)), depth_weight_kind, depth_factor, epsilon)
        terms.append((w, _shift(v, axis, k)))
    out = _weighted_mean(terms)
    if keep_alpha:
        if v.ndim != 3:
            raise InputError(ARGUMENTS, "values", "keep_alpha needs an (H, W, C) buffer")
        out[..., -1] = v[..., -1]
    return out


def thesis_blur_pass(values, depth, axis: int, radius: int = 3, sigma: float = 1.5, depth_factor: float = 1.0,
                     depth_weight_kind: str = "gaussian", epsilon: float = 1e-3) -> np.ndarray:
    """The thesis's 7-tap pass (source pixel and 3 each side) on linear eye depth (§4.2.6).

    The thesis gives neither sigma nor the depth factor [U]: the defaults are
    ``vlref.scene.technique_params.KillzoneParams`` (sigma 1.5 texels, ``exp(-(1.0 dz)^2)`` with
    ``dz`` in metres); ``depth_weight_kind="inverse"`` is the literal reading "weights divided by the
    depth difference", with ``epsilon`` metres added against ``dz = 0``.
    """
    return bilateral_pass(values, depth, axis, gaussian_weights(radius, sigma), depth_factor, depth_weight_kind,
                          epsilon)


def vl_blur_pass(values, depth, axis: int, resolution: str = "half", deviation: float = 1.5,
                 depth_factor: float = 0.5, kernel_radius: int | None = None) -> np.ndarray:
    """VolumetricLights' pass on an RGBA buffer ``(H, W, 4)`` (research §1.9).

    Radius ``K`` = 7 / 5 / 6 for full / half / quarter (``kernel_radius`` overrides it), Gaussian
    ``sigma = K / deviation`` (``GAUSS_BLUR_DEVIATION 1.5``), depth weight
    ``exp(-(0.5 |dz|)^2)`` (``BLUR_DEPTH_FACTOR 0.5``) on **linear eye depth** of the same level;
    alpha is the centre texel's alpha.
    """
    check_choice("resolution", resolution, tuple(VL_KERNEL_RADIUS))
    v = _values(values)
    if v.ndim != 3 or v.shape[2] != 4:
        raise InputError(ARGUMENTS, "values", f"VL blurs an (H, W, 4) RGBA buffer, got shape {v.shape}")
    k = VL_KERNEL_RADIUS[resolution] if kernel_radius is None else kernel_radius
    return bilateral_pass(v, depth, axis, gaussian_weights(k, k / deviation), depth_factor, keep_alpha=True)


def _urp_gauss(taps: int, weights) -> np.ndarray:
    g = np.asarray(weights, dtype=np.float64)
    if not 0 <= taps <= len(g) - 1:
        raise InputError(ARGUMENTS, "samples", f"taps each side must be in 0..{len(g) - 1}, got {taps}")
    return g


def _urp_axes(fog, depth_full, axis: int, uv_origin: str):
    check_choice("axis", axis, (0, 1))
    f = _values(fog)
    z = np.asarray(depth_full, dtype=np.float64)
    if z.ndim != 2 or z.shape[0] < f.shape[0] or z.shape[1] < f.shape[1]:
        raise InputError(ARGUMENTS, "depth", f"full-res depth {z.shape} cannot feed low-res fog {f.shape[:2]}")
    return uv_rows(f, uv_origin), uv_rows(z, uv_origin)


def _urp_pass(f, z, axis, offsets_lo, offsets_hi, centre_hi, g, falloff):
    """Shared URP accumulation: taps ``k = -n..n`` read fog at ``offsets_lo[k]`` and depth at ``offsets_hi[k]``."""
    other = 1 - axis
    cross = nearest_index(z.shape[other], f.shape[other])   # full-res texel under each low-res line
    z = z.take(cross, axis=other)                             # (h, W) or (H, w): one line per low-res line
    z0 = z.take(centre_hi, axis=axis)
    terms = []
    for k in sorted(offsets_lo):
        zk = z.take(offsets_hi[k], axis=axis)
        w = depth_weight(depth_delta(zk, z0), "gaussian", falloff) * g[abs(k)]
        terms.append((w, f.take(offsets_lo[k], axis=axis)))
    return _weighted_mean(terms)


def urp_article_blur_pass(fog, depth_full, axis: int, samples: int, amount: float, falloff: float = 100.0,
                          weights=URP_GAUSS_WEIGHTS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP article's pass (P1, research §2.5) on the low-res fog ``(h, w)``.

    Tap ``k = -samples..samples`` sits at uv ``u_k = u + (k * amount) / 1000`` along the axis --
    **uv units**, so the blur width depends on resolution and aspect. The fog is point-sampled at
    ``u_k`` on the low-res buffer, the **raw** full-res depth at ``u`` and ``u_k`` (the other axis
    at the low-res texel's nearest full-res texel); weight
    ``exp(-(100 |z_k - z_0|)^2) * weights[|k|]`` (``BLUR_DEPTH_FALLOFF 100``); summed in order
    ``k = -n..n``. ``samples`` above 7 would index past the source's array: rejected.
    ``amount = 0`` puts every tap on the centre texel (the result is the centre value up to
    rounding). ``uv_origin`` fixes which texel an exact edge rounds to on the vertical axis.
    """
    g = _urp_gauss(samples, weights)
    f, z = _urp_axes(fog, depth_full, axis, uv_origin)
    n_lo, n_hi = f.shape[axis], z.shape[axis]
    u = (np.arange(n_lo) + 0.5) / n_lo
    uk = {k: u + (k * amount) / 1000.0 for k in range(-samples, samples + 1)}
    lo = {k: point_texel(uk[k], n_lo) for k in uk}
    hi = {k: point_texel(uk[k], n_hi) for k in uk}
    out = _urp_pass(f, z, axis, lo, hi, point_texel(u, n_hi), g, falloff)
    return uv_rows(out, uv_origin)


def urp_repo_blur_pass(fog, depth_full, axis: int, taps: int = 5, falloff: float = 100.0,
                       weights=URP_GAUSS_WEIGHTS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP repository's pass (R, research §2.5): fixed ``n = 5``, integer texel offsets.

    The fog tap ``k`` is low-res texel ``j + k``; its depth is the raw full-res depth at the
    *full-res* texel ``c(j) + k``, ``c(j)`` the texel under the low-res centre -- the source's offset
    mismatch whenever ``f > 1``. Weights and order as :func:`urp_article_blur_pass`.
    """
    g = _urp_gauss(taps, weights)
    f, z = _urp_axes(fog, depth_full, axis, uv_origin)
    n_lo, n_hi = f.shape[axis], z.shape[axis]
    j = np.arange(n_lo)
    c = nearest_index(n_hi, n_lo)
    lo = {k: np.clip(j + k, 0, n_lo - 1) for k in range(-taps, taps + 1)}
    hi = {k: np.clip(c + k, 0, n_hi - 1) for k in range(-taps, taps + 1)}
    out = _urp_pass(f, z, axis, lo, hi, c, g, falloff)
    return uv_rows(out, uv_origin)


def blur_hv(pass_fn, values, depth, **params) -> tuple[np.ndarray, np.ndarray]:
    """``(h, hv)``: ``pass_fn`` along axis 1, then along axis 0 on its output (both buffers returned)."""
    h = pass_fn(values, depth, 1, **params)
    return h, pass_fn(h, depth, 0, **params)
