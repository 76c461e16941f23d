"""Henyey-Greenstein phase function: normalisation, mean cosine, isotropy, forward peak, sign convention."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from vlref.phase import INV_4PI, hg, hg_array

G = st.floats(min_value=-0.95, max_value=0.95, allow_nan=False)


def _sphere_moment(g, power):
    """2π ∫_{-1}^{1} μ^power p(μ; g) dμ by adaptive quadrature (the azimuth integrates to 2π)."""
    value, _ = integrate.quad(lambda mu: mu ** power * hg(mu, g), -1.0, 1.0, epsabs=1e-14, epsrel=1e-12,
                              limit=400, points=[1.0 - 1e-3] if g > 0.5 else None)
    return 2.0 * math.pi * value


@given(G)
@settings(max_examples=25)
def test_hg_integrates_to_one_over_the_sphere(g):
    assert abs(_sphere_moment(g, 0) - 1.0) < 1e-9


@given(G)
@settings(max_examples=25)
def test_hg_mean_cosine_is_g(g):
    assert abs(_sphere_moment(g, 1) - g) < 1e-9


def test_hg_normalised_and_mean_cosine_for_strong_anisotropy():
    """Composite Gauss-Legendre (independent of QUADPACK) on μ pieces graded toward the peak, g = ±0.99."""
    x, w = np.polynomial.legendre.leggauss(40)
    edges = np.concatenate([[-1.0], 1.0 - np.geomspace(1.0, 1e-6, 40), [1.0]])
    for g in (-0.99, 0.99):
        e = edges if g > 0 else -edges[::-1]
        a, b = e[:-1, None], e[1:, None]
        mu = 0.5 * (b - a) * x + 0.5 * (a + b)
        wt = 0.5 * (b - a) * w
        p = hg_array(mu, g)
        assert abs(2.0 * math.pi * np.sum(wt * p) - 1.0) < 1e-10
        assert abs(2.0 * math.pi * np.sum(wt * mu * p) - g) < 1e-10


@given(st.floats(min_value=-1.0, max_value=1.0))
def test_isotropic_is_one_over_four_pi(mu):
    assert hg(mu, 0.0) == INV_4PI
    assert abs(INV_4PI - 0.0795774715459) < 1e-12


@given(st.floats(min_value=0.01, max_value=0.95), st.floats(min_value=-1.0, max_value=0.999))
def test_forward_peak_points_at_the_light(g, mu):
    """cos θ = dot(d, l) with l toward the light: looking into the light (μ = 1) is the maximum for g > 0."""
    d = np.array([0.0, 0.0, 1.0])
    light_dir_from_sample = np.array([math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    toward_light = float(np.dot(d, light_dir_from_sample))
    assert hg(1.0, g) > hg(toward_light, g)
    assert hg(toward_light, g) > hg(-1.0, g) or toward_light == -1.0
    assert hg(1.0, g) == hg(-1.0, -g)


@given(G, st.floats(min_value=-1.0, max_value=1.0))
def test_njit_and_numpy_agree(g, mu):
    assert abs(hg(mu, g) - float(hg_array(mu, g))) <= 1e-14 * hg(mu, g)
