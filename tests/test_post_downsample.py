"""vlref.post.downsample against plain per-texel loops."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings

from post_cases import depth_image, raw_depth, sizes
from vlref.camera import linear_to_raw, raw_to_linear
from vlref.post.downsample import (downsample_chessboard, downsample_max, downsample_min, downsample_point,
                                   downsample_vl)


def covering(n_hi, n_lo, j):
    """Full-res texels whose area overlaps low-res texel j."""
    lo, hi = Fraction(j, n_lo), Fraction(j + 1, n_lo)
    return [i for i in range(n_hi) if Fraction(i, n_hi) < hi and Fraction(i + 1, n_hi) > lo]


@given(sizes(4, 14))
@settings(max_examples=25)
def test_min_max_match_loop_reference(case):
    seed, H, W = case
    z = depth_image(np.random.default_rng(seed), H, W)
    for res, f in (("half", 2), ("third", 3), ("quarter", 4)):
        mn, mx = downsample_min(z, res), downsample_max(z, res)
        assert mn.shape == (H // f, W // f)
        for k in range(H // f):
            for j in range(W // f):
                block = [z[r, c] for r in covering(H, H // f, k) for c in covering(W, W // f, j)]
                assert mn[k, j] == min(block) and mx[k, j] == max(block)
                # never deeper than any source pixel it stands for
                assert all(mn[k, j] <= b for b in block)


def test_min_on_divisible_size_is_block_min():
    z = depth_image(np.random.default_rng(3), 8, 12)
    assert (downsample_min(z, 4) == z.reshape(2, 4, 3, 4).min(axis=(1, 3))).all()


def chessboard_reference(raw, uv_origin):
    H, W = raw.shape
    h, w = H // 2, W // 2
    out = np.empty((h, w))
    for r in range(h):
        k = h - 1 - r if uv_origin == "bottom" else r            # uv row of this output row
        for j in range(w):
            cols = [math.floor(Fraction(2 * j + 1, 2 * w) * W - Fraction(1, 2))]
            rows = [math.floor(Fraction(2 * k + 1, 2 * h) * H - Fraction(1, 2))]
            cols.append(cols[0] + 1)
            rows.append(rows[0] + 1)
            vals = []
            for kk in rows:
                rr = min(max(kk, 0), H - 1)
                rr = H - 1 - rr if uv_origin == "bottom" else rr
                vals += [raw[rr, min(max(c, 0), W - 1)] for c in cols]
            out[r, j] = min(vals) if (j % 2) + (k % 2) == 1 else max(vals)
    return out


@given(sizes(2, 13))
@settings(max_examples=30)
def test_chessboard_matches_loop_reference(case):
    seed, H, W = case
    raw = raw_depth(np.random.default_rng(seed), H, W)
    for origin in ("bottom", "top"):
        assert (downsample_chessboard(raw, origin) == chessboard_reference(raw, origin)).all()


def test_chessboard_parity_and_quarter_chain():
    raw = raw_depth(np.random.default_rng(7), 16, 12)
    half = downsample_chessboard(raw, "top")
    blocks = raw.reshape(8, 2, 6, 2)
    q = (np.arange(8)[:, None] % 2) + (np.arange(6)[None, :] % 2)
    assert (half == np.where(q == 1, blocks.min(axis=(1, 3)), blocks.max(axis=(1, 3)))).all()
    assert (downsample_vl(raw, "quarter") == downsample_chessboard(downsample_chessboard(raw))).all()
    assert downsample_vl(raw, "quarter").shape == (4, 3)
    assert (downsample_vl(raw, "full") == raw).all()


@pytest.mark.parametrize("convention", ["d3d", "reversed"])
def test_raw_min_max_meaning_follows_the_depth_convention(convention):
    # the raw array is used as given: with standard Z the q == 1 texels keep the nearest surface,
    # with reversed Z (1 = near) the farthest, as on the GPU
    z = depth_image(np.random.default_rng(11), 8, 8, sky=False)
    raw = linear_to_raw(z, 0.3, 100.0, convention)
    back = raw_to_linear(downsample_chessboard(raw, "top"), 0.3, 100.0, convention)
    blocks = z.reshape(4, 2, 4, 2)
    near, far = blocks.min(axis=(1, 3)), blocks.max(axis=(1, 3))
    q1 = ((np.arange(4)[:, None] % 2) + (np.arange(4)[None, :] % 2)) == 1
    expect = np.where(q1, near, far) if convention == "d3d" else np.where(q1, far, near)
    np.testing.assert_allclose(back, expect, rtol=1e-9)


@given(sizes(4, 14))
@settings(max_examples=25)
def test_point_matches_d3d_edge_rule(case):
    seed, H, W = case
    raw = raw_depth(np.random.default_rng(seed), H, W)
    for f in (1, 2, 3, 4):
        h, w = H // f, W // f
        out = downsample_point(raw, f)           # uv_origin bottom: the row rule counts from the bottom
        for r in range(h):
            k = h - 1 - r
            rk = min(math.floor(Fraction(2 * k + 1, 2 * h) * H), H - 1)
            for j in range(w):
                cj = min(math.floor(Fraction(2 * j + 1, 2 * w) * W), W - 1)
                assert out[r, j] == raw[H - 1 - rk, cj]


def test_point_half_res_texels():
    raw = np.arange(8 * 8, dtype=float).reshape(8, 8)
    assert (downsample_point(raw, "half", "top") == raw[1::2, 1::2]).all()
    assert (downsample_point(raw, "half", "bottom") == raw[0::2, 1::2]).all()
    assert (downsample_point(raw, "quarter", "top") == raw[2::4, 2::4]).all()


def test_bad_shapes_raise():
    with pytest.raises(ValueError):
        downsample_min(np.zeros((4, 4, 2)), 2)
    with pytest.raises(ValueError):
        downsample_vl(np.zeros((4, 4)), "third")
