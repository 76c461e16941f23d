"""The BVH against brute force on random triangle soups, its structure, and its build time."""

import math
import time

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from vlref.geometry.bvh import SAH_DEPTH, _sort_by_key, build_bvh, bvh_closest, bvh_transmittance
from vlref.geometry.primitives import hit_triangle


def soup(seed, n, clustered):
    """n random triangles; ``clustered``: copies of at most 3 triangles (equal centroids, equal hits)."""
    rng = np.random.default_rng(seed)
    c = rng.uniform(-5, 5, size=(n, 3))
    tri = c[:, None, :] + rng.normal(scale=rng.uniform(0.05, 2.0), size=(n, 3, 3))
    if clustered:
        tri = tri[rng.integers(0, min(3, n), size=n)]
    return tri


def pack(tri, bvh):
    t = tri[bvh.order]
    return t[:, 0].copy(), (t[:, 1] - t[:, 0]).copy(), (t[:, 2] - t[:, 0]).copy()


def rays(seed, m):
    rng = np.random.default_rng(seed + 1)
    o = rng.uniform(-8, 8, size=(m, 3))
    d = rng.uniform(-4, 4, size=(m, 3)) - o
    d[::7, 1] = 0.0  # exact zero direction components
    d[::11, 0] = 0.0
    return o, d


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 300), clustered=st.booleans(),
       tmax=st.sampled_from([math.inf, 6.0]))
def test_closest_matches_brute_force(seed, n, clustered, tmax):
    tri = soup(seed, n, clustered)
    bvh = build_bvh(tri[:, 0], tri[:, 1], tri[:, 2], max_leaf=2)
    v0, e1, e2 = pack(tri, bvh)
    opaque = np.random.default_rng(seed).random(n) < 0.7
    o, d = rays(seed, 60)
    for k in range(len(o)):
        for opaque_only in (False, True):
            t, i = bvh_closest(bvh.node_min, bvh.node_max, bvh.node_first, bvh.node_count, v0, e1, e2, opaque,
                               opaque_only, (*o[k], *d[k]), 0.0, tmax)
            brute = [hit_triangle(v0, e1, e2, j, *o[k], *d[k], 0.0, tmax) if opaque[j] or not opaque_only
                     else math.inf for j in range(n)]
            assert t == min(brute)
            assert (i == -1) if t == math.inf else (brute[i] == t)


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 200), clustered=st.booleans())
def test_transmittance_matches_brute_force(seed, n, clustered):
    tri = soup(seed, n, clustered)
    bvh = build_bvh(tri[:, 0], tri[:, 1], tri[:, 2])
    v0, e1, e2 = pack(tri, bvh)
    rng = np.random.default_rng(seed)
    n_obj = 4
    opacity = np.where(rng.random(n_obj) < 0.3, 1.0, rng.uniform(0, 0.9, n_obj))
    tint = rng.uniform(0.2, 1.0, size=(n_obj, 3))
    tri_obj = rng.integers(0, n_obj, size=n)
    if clustered:  # coincident copies belong to one object, as in a mesh with duplicated faces
        tri_obj = (np.abs(v0[:, 0] * 1e6).astype(np.int64)) % n_obj
    o, d = rays(seed, 40)
    for k in range(len(o)):
        got = bvh_transmittance(bvh.node_min, bvh.node_max, bvh.node_first, bvh.node_count, v0, e1, e2, tri_obj,
                                opacity, tint, (*o[k], *d[k]), 1e-9, 1.0)
        crossings = {(tri_obj[j], hit_triangle(v0, e1, e2, j, *o[k], *d[k], 1e-9, 1.0)) for j in range(n)}
        expect = np.ones(3)
        for obj, t in crossings:  # one crossing per (object, t): coincident triangles count once
            if t < math.inf:
                expect = expect * ((1 - opacity[obj]) * tint[obj] if opacity[obj] < 1 else 0.0)
        assert np.allclose(got, expect, rtol=1e-12, atol=0.0)


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 500), clustered=st.booleans(),
       max_leaf=st.integers(1, 8))
def test_structure(seed, n, clustered, max_leaf):
    tri = soup(seed, n, clustered)
    bvh = build_bvh(tri[:, 0], tri[:, 1], tri[:, 2], max_leaf=max_leaf)
    assert np.array_equal(np.sort(bvh.order), np.arange(n))
    leaves = bvh.node_count > 0
    assert bvh.node_count.sum() == n and np.all(bvh.node_count <= 4 * max_leaf)
    starts = np.sort(bvh.node_first[leaves])
    assert np.array_equal(np.cumsum(np.r_[0, bvh.node_count[leaves][np.argsort(bvh.node_first[leaves])]])[:-1],
                          starts)  # leaves tile the triangle range
    t = tri[bvh.order]
    for k in np.flatnonzero(leaves):
        s, c = bvh.node_first[k], bvh.node_count[k]
        assert np.all(t[s:s + c].min(axis=(0, 1)) >= bvh.node_min[k])
        assert np.all(t[s:s + c].max(axis=(0, 1)) <= bvh.node_max[k])
    for k in np.flatnonzero(~leaves):
        for child in (bvh.node_first[k], bvh.node_first[k] + 1):
            assert np.all(bvh.node_min[child] >= bvh.node_min[k] - 1e-12)
            assert np.all(bvh.node_max[child] <= bvh.node_max[k] + 1e-12)
    assert bvh.depth <= SAH_DEPTH + math.log2(n) + 2


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 200), s=st.integers(0, 5), distinct=st.integers(1, 6))
def test_median_fallback_sort_is_numpys_stable_argsort(seed, n, s, distinct):
    """The median split's in-place sort of ``idx[s:e]`` by key: ties keep their order, as NumPy's stable sort."""
    rng = np.random.default_rng(seed)
    key = rng.integers(0, distinct, size=n + s + 3).astype(np.float64)
    idx = rng.permutation(n + s + 3)
    want = idx.copy()
    want[s:s + n] = idx[s:s + n][np.argsort(key[idx[s:s + n]], kind="stable")]
    _sort_by_key(idx, s, s + n, key)
    assert np.array_equal(idx, want)


def test_empty_input():
    bvh = build_bvh(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    z = np.zeros((0, 3))
    assert bvh_closest(bvh.node_min, bvh.node_max, bvh.node_first, bvh.node_count, z, z, z,
                       np.zeros(0, bool), False, (0.0, 0.0, 0.0, 0.0, 0.0, 1.0), 0.0, math.inf) == (math.inf, -1)


def test_build_100k_triangles_is_fast():
    tri = soup(5, 100_000, False) * 10
    build_bvh(tri[:10, 0], tri[:10, 1], tri[:10, 2])  # JIT warm-up
    start = time.perf_counter()
    bvh = build_bvh(tri[:, 0], tri[:, 1], tri[:, 2])
    assert time.perf_counter() - start < 10.0
    assert bvh.node_count.sum() == 100_000
