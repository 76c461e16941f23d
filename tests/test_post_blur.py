"""vlref.post.blur against per-pixel loop references, plus the blur invariants."""

import math

import numpy as np
import pytest
from hypothesis import given, settings

from post_cases import depth_image, image, raw_depth, sizes
from vlref.post.blur import (URP_GAUSS_WEIGHTS, _bilateral_lines, _gaussian_weight, _gaussian_weights, _weight_code, bilateral_pass, blur_hv,
                             gaussian_weights, thesis_blur_pass, urp_article_blur_pass, urp_repo_blur_pass, vl_blur_pass)

RTOL = 1e-12   # numpy's exp and math.exp may differ by an ulp; everything else is the same arithmetic


def ddelta(a, b):
    return 0.0 if a == b else abs(a - b)


def int_offset_reference(v, z, axis, g, weight_of_dz, keep_alpha=False):
    """Centre first, then k = -K..-1, 1..K; clamp addressing; value and depth at the same texel."""
    H, W = z.shape
    K = len(g) - 1
    out = np.empty_like(v)
    for r in range(H):
        for c in range(W):
            w0 = g[0] * weight_of_dz(0.0)
            acc, wsum = w0 * v[r, c], w0
            for k in list(range(-K, 0)) + list(range(1, K + 1)):
                rr, cc = (min(max(r + k, 0), H - 1), c) if axis == 0 else (r, min(max(c + k, 0), W - 1))
                w = g[abs(k)] * weight_of_dz(ddelta(z[r, c], z[rr, cc]))
                acc = acc + w * v[rr, cc]
                wsum = wsum + w
            out[r, c] = acc / wsum
            if keep_alpha:
                out[r, c, -1] = v[r, c, -1]
    return out


def test_vl_gaussian_weights_match_appendix_b():
    table = {7: [0.085488, 0.083547, 0.077986, 0.069529, 0.059206, 0.048153, 0.037406, 0.027754],
             5: [0.119683, 0.114416, 0.099967, 0.079826, 0.058256, 0.038855],
             6: [0.099736, 0.096667, 0.088016, 0.075284, 0.060493, 0.045662, 0.032379]}
    for k, ref in table.items():
        np.testing.assert_allclose(gaussian_weights(k, k / 1.5), ref, atol=6e-7)


@given(sizes(4, 10))
@settings(max_examples=20)
def test_thesis_pass_matches_reference(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    v, z = image(rng, H, W, 3), depth_image(rng, H, W)
    g = gaussian_weights(3, 1.5)
    for axis in (0, 1):
        ref = int_offset_reference(v, z, axis, g, lambda d: math.exp(-(d * 1.0) * (d * 1.0)))
        np.testing.assert_allclose(thesis_blur_pass(v, z, axis), ref, rtol=RTOL, atol=0)
        ref = int_offset_reference(v, z, axis, g, lambda d: 1.0 / (d + 1e-3))
        np.testing.assert_allclose(thesis_blur_pass(v, z, axis, depth_weight_kind="inverse"), ref, rtol=RTOL, atol=0)


@given(sizes(4, 10))
@settings(max_examples=20)
def test_vl_pass_matches_reference_and_keeps_alpha(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    v, z = image(rng, H, W, 4), depth_image(rng, H, W)
    for res, K in (("full", 7), ("half", 5), ("quarter", 6)):
        g = [math.exp(-(i * i) / (2 * (K / 1.5) ** 2)) / math.sqrt(2 * math.pi * (K / 1.5) ** 2) for i in range(K + 1)]
        for axis in (0, 1):
            out = vl_blur_pass(v, z, axis, res)
            ref = int_offset_reference(v, z, axis, g, lambda d: math.exp(-(d * 0.5) * (d * 0.5)), keep_alpha=True)
            np.testing.assert_allclose(out, ref, rtol=RTOL, atol=0)
            assert (out[..., 3] == v[..., 3]).all()


WEIGHT_KINDS = [("gaussian", 0.7, lambda d: math.exp(-(d * 0.7) * (d * 0.7))),
                ("gaussian", 0.0, lambda d: 1.0),
                ("inverse", 1.0, lambda d: 1.0 / (d + 1e-3))]


@pytest.mark.parametrize("shape", [(1, 1, 1), (2, 9, 4), (9, 2, 3), (5, 6, 2), (13, 11, 3), (3, 530, 3)])
def test_bilateral_pass_same_bits_as_the_pixel_loop(shape):
    # each depth weight is computed once per pair of texels and serves both of their taps (|a - b| == |b - a|),
    # sums vectorised over stretches of a line (3 x 530: three stretches, the last one short): still the pixel loop's
    # bits, for every radius (wider than the image too), weight kind, sky and flat depth, clamped edge, and channel
    # count (RGB is written by a loop of its own)
    H, W, C = shape
    rng = np.random.default_rng(31 * H + W)
    v, z = image(rng, H, W, C), depth_image(rng, H, W)
    for K in (1, 3, 7):
        g = gaussian_weights(K, K / 1.5)
        for kind, factor, weight in WEIGHT_KINDS:
            for axis in (0, 1):
                got = bilateral_pass(v, z, axis, g, factor, kind, 1e-3)
                assert np.array_equal(got, int_offset_reference(v, z, axis, g, weight)), (K, kind, factor, axis)


def test_bilateral_pass_independent_of_the_blocks():
    # the vertical pass recomputes the depth weights of the K rows above each block: any blocking, same bits
    rng = np.random.default_rng(8)
    v, z = image(rng, 17, 6, 2), depth_image(rng, 17, 6)
    g = gaussian_weights(3, 2.0)
    runs = []
    for blocks in (1, 2, 5, 17, 40):
        out = np.empty_like(v)
        _bilateral_lines(v, z, 0, g, _weight_code("gaussian", 1.0, 1.0), 1.0, 1.0, blocks, out)
        runs.append(out)
    assert all(np.array_equal(runs[0], r) for r in runs[1:])


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 63, 64, 1000])
def test_gaussian_weights_same_bits_as_one_by_one(n):
    # the vector loop takes glibc's main path for exp arguments in [-708, 0] and 0 below -746; the lanes between
    # (subnormal weights) and NaN are redone one by one, skipping words of 8 unmarked lanes: every lane has
    # _gaussian_weight's bits, whichever lanes of a word are marked, the last word short or not
    rng = np.random.default_rng(n)
    bands = np.array([[0.0, 22.0], [22.0, 26.6], [26.6, 27.3], [27.3, 40.0]])   # |dz f|: x above/below -512, ...
    for factor in (1.0, -0.7, 3e-3):
        lo, hi = bands[rng.integers(0, 4, n)].T
        tap = rng.uniform(0.0, 50.0, n) / abs(factor)
        at = tap + rng.uniform(lo, hi) / abs(factor) * rng.choice([-1.0, 1.0], n)
        same = rng.random(n) < 0.1
        at[same] = tap[same]                                  # equal depths (dz = 0), then sky against a depth
        at[rng.random(n) < 0.05], tap[rng.random(n) < 0.05] = np.inf, np.nan
        flags = np.full(n // 8 + 1, 2**64 - 1, np.uint64)   # a previous line's marks do not count
        out = np.empty(n)
        _gaussian_weights(tap, at, factor, flags, out)
        ref = np.array([_gaussian_weight(ddelta(a, b), factor) for a, b in zip(tap, at)])
        assert np.array_equal(np.isnan(out), np.isnan(tap)) and np.array_equal(np.isnan(ref), np.isnan(tap))
        ok = ~np.isnan(tap)
        assert np.array_equal(out[ok].view(np.int64), ref[ok].view(np.int64)), factor
        if n >= 64:   # every kind of lane occurred
            assert (out[ok] == 0).any() and (out[ok] == 1).any() and ((out[ok] > 0) & (out[ok] < 2.0**-1022)).any()


def urp_reference(fog, zf, axis, taps_lo, taps_hi, centre_hi, n):
    """fog (h, w) in uv rows (row 0 = v smallest); depth rows/cols picked by the given index functions."""
    h, w = fog.shape
    H, W = zf.shape
    out = np.empty((h, w))
    for r in range(h):
        for c in range(w):
            j = c if axis == 1 else r
            cross = (min(math.floor((2 * r + 1) * H / (2 * h)), H - 1) if axis == 1
                     else min(math.floor((2 * c + 1) * W / (2 * w)), W - 1))

            def z_at(i):
                return zf[cross, i] if axis == 1 else zf[i, cross]

            z0 = z_at(centre_hi(j))
            acc = wsum = 0.0
            for k in range(-n, n + 1):
                jl = taps_lo(j, k)
                f = fog[r, jl] if axis == 1 else fog[jl, c]
                d = ddelta(z_at(taps_hi(j, k)), z0) * 100.0
                wk = math.exp(-d * d) * URP_GAUSS_WEIGHTS[abs(k)]
                acc += wk * f
                wsum += wk
            out[r, c] = acc / wsum
    return out


def nearest(u, n):
    x = round(u * n * 256) / 256          # D3D 8-bit sub-texel snap, then floor and clamp
    return min(max(math.floor(x), 0), n - 1)


@given(sizes(4, 12))
@settings(max_examples=20)
def test_urp_article_pass_matches_reference(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    f = int(rng.integers(1, 4))
    h, w = H // f, W // f
    fog, zf = image(rng, h, w), raw_depth(rng, H, W)
    n, amount = int(rng.integers(0, 8)), float(rng.choice([0.0, 3.0, 25.0, 120.0]))
    for axis in (0, 1):
        nl = w if axis == 1 else h
        nh = W if axis == 1 else H

        def u(j):
            return (j + 0.5) / nl

        ref = urp_reference(fog[::-1], zf[::-1], axis,
                            lambda j, k: nearest(u(j) + (k * amount) / 1000.0, nl),
                            lambda j, k: nearest(u(j) + (k * amount) / 1000.0, nh),
                            lambda j: nearest(u(j), nh), n)[::-1]
        out = urp_article_blur_pass(fog, zf, axis, n, amount)
        np.testing.assert_allclose(out, ref, rtol=RTOL, atol=0)


@given(sizes(4, 12))
@settings(max_examples=20)
def test_urp_repo_pass_matches_reference(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    f = int(rng.integers(1, 4))
    h, w = H // f, W // f
    fog, zf = image(rng, h, w), raw_depth(rng, H, W)
    for axis in (0, 1):
        nl = w if axis == 1 else h
        nh = W if axis == 1 else H

        def c(j):
            return min(math.floor((2 * j + 1) * nh / (2 * nl)), nh - 1)

        ref = urp_reference(fog[::-1], zf[::-1], axis, lambda j, k: min(max(j + k, 0), nl - 1),
                            lambda j, k: min(max(c(j) + k, 0), nh - 1), c, 5)[::-1]
        np.testing.assert_allclose(urp_repo_blur_pass(fog, zf, axis), ref, rtol=RTOL, atol=0)


def all_passes(rng, H, W):
    """(name, pass over axis) for every blur, on data shaped for it."""
    z, zr = depth_image(rng, H, W), raw_depth(rng, H, W)
    return [("thesis", lambda v, a: thesis_blur_pass(v, z, a), 3),
            ("thesis-inverse", lambda v, a: thesis_blur_pass(v, z, a, depth_weight_kind="inverse"), 3),
            ("vl", lambda v, a: vl_blur_pass(v, z, a, "half"), 4),
            ("urp-article", lambda v, a: urp_article_blur_pass(v, zr, a, 7, 40.0), None),
            ("urp-repo", lambda v, a: urp_repo_blur_pass(v, zr, a), None)]


@given(sizes(4, 12))
@settings(max_examples=15)
def test_constant_image_stays_constant(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    value = float(rng.random() * 10)
    for name, fn, c in all_passes(rng, H, W):
        v = np.full((H, W) if c is None else (H, W, c), value)
        for axis in (0, 1):
            np.testing.assert_allclose(fn(v, axis), value, rtol=4e-16 * 16, atol=0, err_msg=name)


@given(sizes(4, 12))
@settings(max_examples=15)
def test_blur_is_a_convex_combination(case):
    # normalised weights: every output lies within the min/max of the taps (here: of the whole line)
    seed, H, W = case
    rng = np.random.default_rng(seed)
    for name, fn, c in all_passes(rng, H, W):
        v = image(rng, H, W, c)
        for axis in (0, 1):
            out = fn(v, axis)
            lo, hi = v.min(axis=axis, keepdims=True), v.max(axis=axis, keepdims=True)
            if c == 4 and name == "vl":
                out, lo, hi = out[..., :3], lo[..., :3], hi[..., :3]
            assert (out >= lo * (1 - 1e-15)).all() and (out <= hi * (1 + 1e-15)).all(), name


def test_flat_depth_gives_normalised_gaussian_convolution():
    rng = np.random.default_rng(5)
    v = image(rng, 9, 11)
    g = gaussian_weights(3, 1.5)
    out = thesis_blur_pass(v, np.full((9, 11), 2.0), 1)
    pad = np.pad(v, ((0, 0), (3, 3)), mode="edge")
    ref = sum(g[abs(k)] * pad[:, 3 + k:3 + k + 11] for k in range(-3, 4)) / (g[0] + 2 * g[1:].sum())
    np.testing.assert_allclose(out, ref, rtol=1e-14)


@pytest.mark.parametrize("far", [60.0, np.inf])
def test_no_bleeding_across_a_depth_edge(far):
    # left half near (depth 1, value 0), right half far (value 1): above the threshold the Gaussian
    # depth weight underflows to exactly 0, so neither side leaks into the other
    H, W = 6, 10
    z = np.ones((H, W))
    z[:, 5:] = far
    v = np.zeros((H, W, 4))
    v[:, 5:] = 1.0
    zr = np.full((H, W), 0.2)
    zr[:, 5:] = 1.0 if np.isinf(far) else 0.7
    for out in (thesis_blur_pass(v[..., 0], z, 1), vl_blur_pass(v, z, 1, "full")[..., 0],
                urp_repo_blur_pass(v[..., 0], zr, 1), urp_article_blur_pass(v[..., 0], zr, 1, 7, 100.0)):
        assert (out[:, :5] == 0.0).all() and (out[:, 5:] == 1.0).all()
    # the inverse weight never reaches 0: the leak is bounded by (sum G / G0) * eps / dz
    out = thesis_blur_pass(v[..., 0], z, 1, depth_weight_kind="inverse")
    g = gaussian_weights(3, 1.5)
    bound = 2 * g[1:].sum() / g[0] * 1e-3 / (far - 1.0)
    assert (out[:, :5] <= bound).all() and (out[:, 5:] >= 1.0 - bound).all()


def test_blur_hv_runs_horizontal_then_vertical():
    rng = np.random.default_rng(2)
    v, z = image(rng, 7, 8, 3), depth_image(rng, 7, 8)
    h, hv = blur_hv(thesis_blur_pass, v, z)
    assert (h == thesis_blur_pass(v, z, 1)).all()
    assert (hv == thesis_blur_pass(h, z, 0)).all()


def test_blur_hv_into_its_own_input_gives_the_same_buffers():
    # the vertical pass may write into the values themselves (read by the horizontal pass before): the same bits as
    # two new arrays, hv in the caller's memory; an out= that overlaps what a pass reads, or of another shape, is
    # refused before anything is written
    rng = np.random.default_rng(12)
    v, z = image(rng, 19, 23, 3), depth_image(rng, 19, 23)
    h, hv = blur_hv(thesis_blur_pass, v, z)
    own = v.copy()
    h2, hv2 = blur_hv(thesis_blur_pass, own, z, out=own)
    assert np.array_equal(h, h2) and np.array_equal(hv, hv2) and np.shares_memory(hv2, own)
    for bad in (v, v[:, :-1].copy(), v.astype(np.float32), np.asfortranarray(v)):
        kept = bad.copy()
        with pytest.raises(ValueError, match="out"):
            thesis_blur_pass(v, z, 1, out=bad)
        assert np.array_equal(bad, kept)


def test_sky_depth_and_zero_factor_stay_finite():
    rng = np.random.default_rng(9)
    v, z = image(rng, 6, 7, 3), depth_image(rng, 6, 7)
    z[:, :3] = np.inf
    for out in (thesis_blur_pass(v, z, 1, depth_factor=0.0), thesis_blur_pass(v, z, 0),
                thesis_blur_pass(v, z, 1, depth_weight_kind="inverse")):
        assert np.isfinite(out).all()
    np.testing.assert_allclose(thesis_blur_pass(v, z, 1, depth_factor=0.0),
                               thesis_blur_pass(v, np.ones_like(z), 1), rtol=1e-15)


def test_bad_arguments_raise():
    z = np.ones((4, 4))
    with pytest.raises(ValueError):
        vl_blur_pass(np.ones((4, 4, 3)), z, 1)
    with pytest.raises(ValueError):
        urp_article_blur_pass(np.ones((2, 2)), z, 1, 8, 1.0)
    with pytest.raises(ValueError):
        thesis_blur_pass(np.ones((4, 4)), z, 2)
    with pytest.raises(ValueError):
        thesis_blur_pass(np.ones((4, 5)), z, 1)
    with pytest.raises(ValueError):
        thesis_blur_pass(np.ones((4, 4)), z, 1, depth_weight_kind="inverse", epsilon=0.0)
