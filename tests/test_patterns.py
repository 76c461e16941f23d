"""Bayer matrices and offset patterns."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vlref.march.patterns import bayer_matrix, offsets


@pytest.mark.parametrize("n", [1, 2, 4, 8, 16])
def test_bayer_is_a_permutation(n):
    b = bayer_matrix(n)
    assert b.shape == (n, n)
    assert np.array_equal(np.sort(b.ravel()), np.arange(n * n))


@pytest.mark.parametrize("n", [2, 4, 8, 16])
def test_bayer_recursive_structure(n):
    """B_{2m} = [[4B_m, 4B_m+2], [4B_m+3, 4B_m+1]] (the standard construction, row 0 on top)."""
    b, m = bayer_matrix(n), bayer_matrix(n // 2)
    assert np.array_equal(b[: n // 2, : n // 2], 4 * m)
    assert np.array_equal(b[: n // 2, n // 2:], 4 * m + 2)
    assert np.array_equal(b[n // 2:, : n // 2], 4 * m + 3)
    assert np.array_equal(b[n // 2:, n // 2:], 4 * m + 1)


def test_bayer4_literal():
    assert bayer_matrix(4).tolist() == [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]]


@pytest.mark.parametrize("n", [2, 4, 8])
def test_bayer_interleaved_form(n):
    """The equivalent interleaved form B_{2m}[2i+a, 2j+b] = m² B_2[a, b] + B_m[i, j]: every aligned 2x2 block
    holds the four quarters of the range in the B_2 order (the dither is spread at every scale)."""
    b, m = bayer_matrix(n), n // 2
    b2, bm = bayer_matrix(2), bayer_matrix(m)
    for i in range(m):
        for j in range(m):
            assert np.array_equal(b[2 * i:2 * i + 2, 2 * j:2 * j + 2], m * m * b2 + bm[i, j])


@pytest.mark.parametrize("n", [0, 3, 6, -2])
def test_bayer_rejects_non_powers_of_two(n):
    with pytest.raises(ValueError):
        bayer_matrix(n)


@given(st.sampled_from(["bayer2", "bayer4", "bayer8"]), st.integers(1, 40), st.integers(1, 40))
def test_bayer_offsets_index_by_pixel(pattern, w, h):
    n = int(pattern[5:])
    off = offsets(pattern, w, h)
    b = bayer_matrix(n)
    ys, xs = np.mgrid[0:h, 0:w]
    assert off.shape == (h, w)
    assert np.array_equal(off, b[ys % n, xs % n] / (n * n))
    assert off.min() >= 0.0 and off.max() < 1.0


@given(st.integers(1, 30), st.integers(1, 30), st.integers(0, 2**31))
def test_hash_offsets_in_unit_interval_and_seeded(w, h, seed):
    a = offsets("hash", w, h, seed)
    assert a.shape == (h, w) and np.all(a >= 0.0) and np.all(a < 1.0)
    assert np.array_equal(a, offsets("hash", w, h, seed))


def test_hash_offsets_look_uniform():
    a = offsets("hash", 128, 128, 7).ravel()
    hist, _ = np.histogram(a, bins=16, range=(0.0, 1.0))
    # chi-square with 15 dof: 99.9% quantile ≈ 37.7
    expected = a.size / 16
    assert np.sum((hist - expected) ** 2 / expected) < 37.7
    assert not np.array_equal(a, offsets("hash", 128, 128, 8).ravel())


def test_none_is_zero():
    assert not offsets("none", 5, 3).any()
