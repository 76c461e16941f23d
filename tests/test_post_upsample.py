"""vlref.post.upsample against per-pixel loop references, plus the upsample invariants."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings

from post_cases import depth_image, image, raw_depth, sizes
from vlref.post.downsample import downsample_min
from vlref.post.upsample import bilinear_upsample, nearest_upsample, thesis_upsample, urp_upsample, vl_upsample


def ddelta(a, b):
    return 0.0 if a == b else abs(a - b)


def foot(i, n_lo, n_hi):
    """(i0, i1, t) of full-res texel i: p = (i + 1/2) n_lo / n_hi - 1/2, clamp addressing."""
    p = Fraction(2 * i + 1, 2 * n_hi) * n_lo - Fraction(1, 2)
    k = math.floor(p)
    return min(max(k, 0), n_lo - 1), min(max(k + 1, 0), n_lo - 1), float(p - k)


def lerp(a, b, t):
    return a + t * (b - a)


def case_data(case, channels=3, sky=True):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    f = int(rng.integers(1, 5))
    f = min(f, H, W)
    zh = depth_image(rng, H, W, sky)
    zl = downsample_min(zh, f)
    if rng.random() < 0.3:
        zl = depth_image(rng, H // f, W // f, sky)   # depth not derived from the full-res one
    return rng, zh, zl, image(rng, H // f, W // f, channels)


@given(sizes(4, 12))
@settings(max_examples=20)
def test_bilinear_and_nearest_match_reference(case):
    rng, zh, zl, lo = case_data(case)
    H, W = zh.shape
    h, w = lo.shape[:2]
    bil, near = bilinear_upsample(lo, (H, W)), nearest_upsample(lo, (H, W), "top")
    for r in range(H):
        r0, r1, ty = foot(r, h, H)
        rn = min(math.floor(Fraction(2 * r + 1, 2 * H) * h), h - 1)
        for c in range(W):
            c0, c1, tx = foot(c, w, W)
            ref = lerp(lerp(lo[r0, c0], lo[r0, c1], tx), lerp(lo[r1, c0], lo[r1, c1], tx), ty)
            assert (bil[r, c] == ref).all()
            assert (near[r, c] == lo[rn, min(math.floor(Fraction(2 * c + 1, 2 * W) * w), w - 1)]).all()


@given(sizes(4, 12))
@settings(max_examples=20)
def test_thesis_upsample_matches_reference(case):
    rng, zh, zl, lo = case_data(case)
    H, W = zh.shape
    h, w = lo.shape[:2]
    out = thesis_upsample(lo, zl, zh)
    for r in range(H):
        r0, r1, ty = foot(r, h, H)
        for c in range(W):
            c0, c1, tx = foot(c, w, W)
            texels = [(r0, c0, (1 - tx) * (1 - ty)), (r0, c1, tx * (1 - ty)), (r1, c0, (1 - tx) * ty),
                      (r1, c1, tx * ty)]
            ws = [b / (ddelta(zh[r, c], zl[rr, cc]) + 1e-3) for rr, cc, b in texels]
            if sum(ws) == 0:
                ws = [b for _, _, b in texels]
            ref = sum(wk * lo[rr, cc] for wk, (rr, cc, _) in zip(ws, texels)) / sum(ws)
            np.testing.assert_allclose(out[r, c], ref, rtol=1e-14, atol=0)
    assert np.isfinite(out).all()


def test_thesis_half_res_weights_on_flat_depth():
    # flat depth: w_k = b_k / eps, so the result is the bilinear 9/16, 3/16, 3/16, 1/16 blend
    lo = np.array([[0.0, 16.0], [32.0, 64.0]])
    out = thesis_upsample(lo, np.ones((2, 2)), np.ones((4, 4)))
    assert out[1, 1] == pytest.approx((9 * 0 + 3 * 16 + 3 * 32 + 1 * 64) / 16, rel=1e-15)
    assert out[2, 2] == pytest.approx((1 * 0 + 3 * 16 + 3 * 32 + 9 * 64) / 16, rel=1e-15)


def vl_reference(lo, zl, zh, uv_origin):
    """Loops in uv rows (row index grows with v), tie order 00, 10, 01, 11 with strict <."""
    flip = (lambda a: a[::-1]) if uv_origin == "bottom" else (lambda a: a)
    lo, zl, zh = flip(lo), flip(zl), flip(zh)
    H, W = zh.shape
    h, w = lo.shape[:2]
    out = np.empty((H, W) + lo.shape[2:])
    for r in range(H):
        r0, r1, ty = foot(r, h, H)
        for c in range(W):
            c0, c1, tx = foot(c, w, W)
            cand = [(r0, c0), (r0, c1), (r1, c0), (r1, c1)]            # 00, 10, 01, 11
            d = [ddelta(zh[r, c], zl[t]) for t in cand]
            if ((d[0] + d[1]) + d[2]) + d[3] < 1.5:
                out[r, c] = lerp(lerp(lo[r0, c0], lo[r0, c1], tx), lerp(lo[r1, c0], lo[r1, c1], tx), ty)
            else:
                best = 0
                for k in (1, 2, 3):
                    if d[k] < d[best]:
                        best = k
                out[r, c] = lo[cand[best]]
    return flip(out)


@given(sizes(4, 12))
@settings(max_examples=20)
def test_vl_upsample_matches_reference(case):
    rng, zh, zl, lo = case_data(case, channels=4)
    for origin in ("bottom", "top"):
        assert (vl_upsample(lo, zl, zh, uv_origin=origin) == vl_reference(lo, zl, zh, origin)).all()


def test_vl_upsample_tie_order_depends_on_v_orientation():
    # hi depth 0 everywhere; the four low-res texels all at |dz| = 1 -> ties -> texel 00 wins,
    # i.e. the footprint's lower-left texel in Unity's v-up uv, the upper-left with uv_origin="top"
    lo = np.arange(4.0).reshape(2, 2)
    zl = np.ones((2, 2))
    zh = np.zeros((4, 4))
    bottom, top = vl_upsample(lo, zl, zh, uv_origin="bottom"), vl_upsample(lo, zl, zh, uv_origin="top")
    assert bottom[1, 1] == lo[1, 0] and top[1, 1] == lo[0, 0]


def urp_reference(fog, zl, zh):
    """uv_origin bottom: loops in uv rows, candidates (0,+1), (0,-1), (+1,0), (-1,0), first min wins."""
    fog, zl, zh = fog[::-1], zl[::-1], zh[::-1]
    H, W = zh.shape
    h, w = fog.shape
    out = np.empty((H, W))
    for r in range(H):
        k = min(math.floor(Fraction(2 * r + 1, 2 * H) * h), h - 1)
        for c in range(W):
            j = min(math.floor(Fraction(2 * c + 1, 2 * W) * w), w - 1)
            best, best_d = None, None
            for du, dv in ((0, 1), (0, -1), (1, 0), (-1, 0)):
                t = (min(max(k + dv, 0), h - 1), min(max(j + du, 0), w - 1))
                d = ddelta(zh[r, c], zl[t])
                if best is None or d < best_d:
                    best, best_d = t, d
            out[r, c] = fog[best]
    return out[::-1]


@given(sizes(4, 12))
@settings(max_examples=20)
def test_urp_upsample_matches_reference(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    f = int(rng.integers(1, 5))
    f = min(f, H, W)
    zh = raw_depth(rng, H, W)
    zl, fog = raw_depth(rng, H // f, W // f), image(rng, H // f, W // f)
    assert (urp_upsample(fog, zl, zh) == urp_reference(fog, zl, zh)).all()


def test_urp_flat_depth_shifts_one_texel_up():
    fog = np.arange(12.0).reshape(4, 3)
    out = urp_upsample(fog, np.full((4, 3), 0.5), np.full((8, 6), 0.5))
    rows = np.clip(np.arange(8) // 2 - 1, 0, 3)          # +v = up = one low-res row toward the top
    assert (out == fog[rows][:, np.arange(6) // 2]).all()
    down = urp_upsample(fog, np.full((4, 3), 0.5), np.full((8, 6), 0.5), uv_origin="top")
    assert (down == fog[np.clip(np.arange(8) // 2 + 1, 0, 3)][:, np.arange(6) // 2]).all()


@given(sizes(4, 12))
@settings(max_examples=15)
def test_constant_image_stays_constant(case):
    rng, zh, zl, lo = case_data(case, channels=4)
    value = float(rng.random() * 7)
    const = np.full(lo.shape, value)
    H, W = zh.shape
    assert (bilinear_upsample(const, (H, W)) == value).all()
    assert (nearest_upsample(const, (H, W)) == value).all()
    assert (vl_upsample(const, zl, zh) == value).all()
    np.testing.assert_allclose(thesis_upsample(const, zl, zh), value, rtol=1e-15, atol=0)
    assert (urp_upsample(const[..., 0], zl, zh) == value).all()


def test_no_bleeding_across_a_depth_edge():
    # left low-res column near (1 m, value 0), right far (value 1, sky or 60 m): full-res pixels on the
    # near side never take the far value (thesis: weight b/(dz + eps) -> 0 for sky; VL: nearest-depth)
    for far in (np.inf, 60.0):
        zl = np.array([[1.0, far]] * 3)
        lo = np.array([[0.0, 1.0]] * 3)
        zh = np.ones((6, 4))
        zh[:, 2:] = far
        vl = vl_upsample(lo, zl, zh)
        assert (vl[:, :2] == 0.0).all() and (vl[:, 2:] == 1.0).all()
        th = thesis_upsample(lo, zl, zh)
        if np.isinf(far):
            assert (th[:, :2] == 0.0).all() and (th[:, 2:] == 1.0).all()
        else:   # bounded leak: (1/4 / 59) / (3/4 / 1e-3)
            assert (th[:, :2] < 1e-5).all() and (th[:, 2:] > 1 - 1e-5).all()
