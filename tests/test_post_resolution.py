"""vlref.post.resolution: sizes and texel maps against exact rational references."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, strategies as st

from vlref.post.resolution import (block_ranges, bilinear_footprint, gather_footprint, low_res_size, nearest_index,
                                   point_texel, resolution_factor, uv_row_map, uv_rows)

ns = st.integers(1, 40)


def test_low_res_size_is_floor():
    assert low_res_size(641, 361, "half") == (320, 180)
    assert low_res_size(640, 360, "third") == (213, 120)
    assert low_res_size(643, 362, "quarter") == (160, 90)
    assert low_res_size(5, 4, "full") == (5, 4)
    assert resolution_factor(3) == 3


@pytest.mark.parametrize("args", [(3, 8, "quarter"), (8, 8, "eighth"), (8, 8, 0), (8, 8, True)])
def test_bad_resolution_raises(args):
    with pytest.raises(ValueError):
        low_res_size(*args)


@given(ns, ns)
def test_nearest_index_is_floor_of_uv(n_src, n_dst):
    ref = [min(math.floor(Fraction(2 * i + 1, 2 * n_dst) * n_src), n_src - 1) for i in range(n_dst)]
    assert nearest_index(n_src, n_dst).tolist() == ref


def test_nearest_index_source_texels():
    # SOURCES §2.3: half -> 2j+1, third -> 3j+1, quarter -> 4j+2; full-res i reads low-res floor(i/f)
    assert nearest_index(16, 8).tolist() == [2 * j + 1 for j in range(8)]
    assert nearest_index(24, 8).tolist() == [3 * j + 1 for j in range(8)]
    assert nearest_index(32, 8).tolist() == [4 * j + 2 for j in range(8)]
    assert nearest_index(8, 16).tolist() == [i // 2 for i in range(16)]


@given(ns, ns)
def test_point_texel_at_centres_matches_exact_rule(n_src, n_dst):
    u = (np.arange(n_dst) + 0.5) / n_dst     # float uv, possibly a rounding error below an edge
    assert point_texel(u, n_src).tolist() == nearest_index(n_src, n_dst).tolist()


@given(ns, ns)
def test_block_ranges_cover_overlapping_texels(n_lo, extra):
    n_hi = n_lo + extra
    start, stop = block_ranges(n_hi, n_lo)
    for j in range(n_lo):
        lo, hi = Fraction(j, n_lo), Fraction(j + 1, n_lo)
        ref = [i for i in range(n_hi) if Fraction(i, n_hi) < hi and Fraction(i + 1, n_hi) > lo]
        assert list(range(start[j], stop[j])) == ref
    if n_hi % n_lo == 0:
        f = n_hi // n_lo
        assert start.tolist() == [f * j for j in range(n_lo)] and (stop - start == f).all()


@given(ns, ns)
def test_gather_footprint(n_lo, extra):
    n_hi = n_lo + extra
    i0, i1 = gather_footprint(n_hi, n_lo)
    for j in range(n_lo):
        ref = math.floor(Fraction(2 * j + 1, 2 * n_lo) * n_hi - Fraction(1, 2))
        assert i0[j] == min(max(ref, 0), n_hi - 1) and i1[j] == min(max(ref + 1, 0), n_hi - 1)
    assert gather_footprint(2 * n_lo, n_lo)[0].tolist() == [2 * j for j in range(n_lo)]


@given(ns, ns)
def test_bilinear_footprint(n_lo, n_hi):
    i0, i1, t = bilinear_footprint(n_lo, n_hi)
    for i in range(n_hi):
        p = Fraction(2 * i + 1, 2 * n_hi) * n_lo - Fraction(1, 2)
        k = math.floor(p)
        assert (i0[i], i1[i]) == (min(max(k, 0), n_lo - 1), min(max(k + 1, 0), n_lo - 1))
        assert t[i] == float(p - k)


def test_half_res_bilinear_weights_are_9_3_3_1_sixteenths():
    _, _, t = bilinear_footprint(6, 12)
    assert set(t.tolist()) == {0.25, 0.75}
    w = sorted({(1 - a) * (1 - b) for a in (0.25, 0.75) for b in (0.25, 0.75)} | {a * b for a in (0.25, 0.75)
                                                                                   for b in (0.25, 0.75)})
    assert w == [1 / 16, 3 / 16, 9 / 16]


def test_uv_rows_flips_only_for_bottom_origin():
    a = np.arange(12).reshape(4, 3)
    assert (uv_rows(a, "top") == a).all()
    assert (uv_rows(a, "bottom") == a[::-1]).all()
    assert (uv_rows(uv_rows(a, "bottom"), "bottom") == a).all()
    with pytest.raises(ValueError):
        uv_rows(a, "left")


@given(ns, ns, st.integers(1, 4))
def test_uv_row_map_reads_flipped_arrays_in_place(n_src, n_dst, taps):
    # a map built in uv rows, applied to top-first arrays, equals flipping both arrays around it
    rng = np.random.default_rng(n_src * 100 + n_dst)
    index = rng.integers(0, n_src, size=(n_dst, taps))
    src = rng.random(n_src)
    for origin in ("top", "bottom"):
        mapped = uv_row_map(index, n_src, origin)
        assert mapped.shape == index.shape and mapped.min() >= 0 and mapped.max() < n_src
        np.testing.assert_array_equal(src[mapped], uv_rows(uv_rows(src, origin)[index], origin))
    np.testing.assert_array_equal(uv_row_map(index, n_src, "top"), index)
