"""The closed forms of vlref.reference.closed_forms against independent numerics and their own limits."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vlref.phase import hg_array
from vlref.reference.closed_forms import (closest_approach, directional_homogeneous, point_light_extinction,
                                          point_light_no_extinction)

pos = st.floats(min_value=0.01, max_value=5.0)


def _gauss(f, a, b, pieces=400, order=20):
    """Composite Gauss-Legendre of a vectorised f on [a, b] (independent of QUADPACK)."""
    x, w = np.polynomial.legendre.leggauss(order)
    e = np.linspace(a, b, pieces + 1)
    lo, hi = e[:-1, None], e[1:, None]
    t = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
    return float(np.sum(0.5 * (hi - lo) * w * f(t)))


def test_closest_approach():
    tc, h = closest_approach([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [[3.0, 4.0, 7.0], [0.0, 0.0, -2.0]])
    assert np.allclose(tc, [7.0, -2.0]) and np.allclose(h, [5.0, 0.0])


@given(pos, st.floats(min_value=-10, max_value=10), st.floats(min_value=0.05, max_value=5.0),
       st.floats(min_value=0.0, max_value=10.0), st.floats(min_value=0.0, max_value=10.0))
@settings(max_examples=30)
def test_point_no_extinction_matches_quadrature(sigma_s, tc, h, t0, length):
    t1 = t0 + length
    exact = point_light_no_extinction(sigma_s, 3.0, tc, h, t0, t1)
    numeric = _gauss(lambda t: sigma_s * 3.0 / (4 * math.pi) / (h * h + (t - tc) ** 2), t0, t1)
    assert abs(exact - numeric) <= 1e-10 * max(abs(numeric), 1e-300)


def test_point_no_extinction_small_h_limit_is_continuous():
    # light behind the segment: the limit 1/a - 1/b is approached smoothly as h -> 0
    hs = np.array([0.0, 1e-300, 1e-12, 1e-6])
    v = point_light_no_extinction(0.1, 2.0, -1.0, hs, 0.5, 4.0)
    limit = 0.1 * 2.0 / (4 * math.pi) * (1 / 1.5 - 1 / 5.0)
    assert np.all(np.isfinite(v)) and np.allclose(v, limit, rtol=1e-11, atol=0)
    assert np.isinf(point_light_no_extinction(0.1, 2.0, 1.0, 0.0, 0.5, 4.0))


def test_point_no_extinction_far_light_keeps_relative_accuracy():
    # atan(b/h) - atan(a/h) cancels catastrophically here; the atan2 form does not
    v = point_light_no_extinction(1.0, 1.0, 0.0, 1e7, 0.0, 1.0)
    assert abs(v / (1.0 / (4 * math.pi) / 1e14) - 1.0) < 1e-12


@given(pos, st.floats(min_value=0.0, max_value=3.0), st.floats(min_value=-0.9, max_value=0.9),
       st.floats(min_value=-1.0, max_value=1.0), st.floats(min_value=0.0, max_value=5.0),
       st.floats(min_value=0.01, max_value=20.0), st.floats(min_value=0.0, max_value=5.0),
       st.floats(min_value=-0.5, max_value=2.0))
@settings(max_examples=30)
def test_directional_matches_quadrature(sigma_s, sigma_t, g, mu, t0, length, leg0, rate):
    t1 = t0 + length
    exact = directional_homogeneous(sigma_s, sigma_t, g, mu, 2.5, t0, t1, leg0, rate)
    f = lambda t: sigma_s * hg_array(mu, g) * 2.5 * np.exp(-sigma_t * (t + leg0 + rate * t))  # noqa: E731
    numeric = _gauss(f, t0, t1)
    assert abs(exact - numeric) <= 1e-11 * abs(numeric) + 1e-300


def test_directional_textbook_form_and_zero_extinction_limit():
    p = hg_array(0.3, 0.5)
    assert np.isclose(directional_homogeneous(0.2, 0.5, 0.5, 0.3, 4.0, 0.0, 7.0),
                      0.2 * p * 4.0 * (1 - math.exp(-0.5 * 7.0)) / 0.5, rtol=1e-14)
    v = directional_homogeneous(0.2, np.array([0.0, 1e-15, 1e-9]), 0.5, 0.3, 4.0, 1.0, 8.0)
    assert np.allclose(v, 0.2 * p * 4.0 * 7.0, rtol=1e-8, atol=0)


@given(pos, st.floats(min_value=-10, max_value=10), st.floats(min_value=0.05, max_value=5.0),
       st.floats(min_value=0.0, max_value=5.0), st.floats(min_value=0.01, max_value=10.0))
@settings(max_examples=15)
def test_point_extinction_reduces_to_no_extinction(sigma_s, tc, h, t0, length):
    a = point_light_extinction(sigma_s, 0.0, 0.0, 3.0, tc, h, t0, t0 + length)
    b = point_light_no_extinction(sigma_s, 3.0, tc, h, t0, t0 + length)
    assert abs(a - b) <= 1e-10 * b


@given(st.floats(min_value=0.01, max_value=2.0), st.floats(min_value=-0.9, max_value=0.9),
       st.floats(min_value=-5, max_value=10), st.floats(min_value=0.05, max_value=3.0))
@settings(max_examples=15)
def test_point_extinction_matches_composite_gauss(sigma_t, g, tc, h):
    t0, t1 = 0.0, 12.0

    def f(t):
        r = np.sqrt(h * h + (t - tc) ** 2)
        return 0.3 * 2.0 * hg_array((tc - t) / r, g) * np.exp(-sigma_t * (t + r)) / r ** 2

    # grade the composite rule around the peak at tc: pieces of width ~h/20 near it
    edges = np.unique(np.clip(np.concatenate([np.linspace(t0, t1, 200), tc + h * np.linspace(-40, 40, 1601)]),
                              t0, t1))
    x, w = np.polynomial.legendre.leggauss(20)
    lo, hi = edges[:-1, None], edges[1:, None]
    numeric = float(np.sum(0.5 * (hi - lo) * w * f(0.5 * (hi - lo) * x + 0.5 * (hi + lo))))
    exact = point_light_extinction(0.3, sigma_t, g, 2.0, tc, h, t0, t1)
    assert abs(exact - numeric) <= 1e-10 * numeric


def test_closed_forms_are_vectorised():
    tc = np.linspace(-2, 5, 6).reshape(2, 3)
    assert point_light_no_extinction(0.1, 1.0, tc, 0.5, 0.0, 4.0).shape == (2, 3)
    assert point_light_extinction(0.1, 0.2, 0.3, 1.0, tc, 0.5, 0.0, 4.0).shape == (2, 3)
    assert directional_homogeneous(0.1, 0.2, 0.3, np.zeros((4, 1)), 1.0, 0.0, np.ones(5)).shape == (4, 5)
