"""The medium: density factors, noise, bounds, optical depth (closed forms vs quadrature)."""

import math
from decimal import Decimal, localcontext
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import quad

from vlref.medium import (FOG_SERIES_BELOW, M_ST, density, fog_mean_factor, load_noise_volume, noise_lattice,
                          noise_value, optical_depth, pack_medium)
from vlref.scene.model import Bounds, HeightFog, Light, Medium, Noise, RenderSettings, Scene

NOISE_FILE = Path("/work/shared/data/volumetriclights/NoiseVolume.bytes")


def _scene(**medium):
    return Scene(medium=Medium(scattering=0.2, absorption=0.05, **medium), lights=(Light(type="point"),),
                 render=RenderSettings(time=2.0, seed=7))


def _tau_quad(m, o, d, t0, t1):
    f = lambda t: float(m.params[M_ST]) * density(m.params, m.noise, *(np.asarray(o) + t * np.asarray(d)))  # noqa
    return quad(f, t0, t1, limit=500, epsabs=1e-13, epsrel=1e-11)[0]


@pytest.mark.parametrize("d", [(0.0, 0.6, 0.8), (0.0, -0.6, 0.8), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)])
def test_height_fog_optical_depth_closed_form(d):
    m = pack_medium(_scene(height_fog=HeightFog(base=0.5, falloff=0.4)))
    o = (0.2, 1.0, -1.0)
    got = optical_depth(m.params, m.noise, *o, *d, 0.5, 9.0, 1)
    assert got == pytest.approx(_tau_quad(m, o, d, 0.5, 9.0), rel=1e-10)


def _exact_fog_mean(ea, eb) -> Decimal:
    """The mean of e^e over a segment where e runs linearly from ea to eb (floats), in 50 digits."""
    with localcontext() as ctx:
        ctx.prec = 50
        a, b = Decimal(float(ea)), Decimal(float(eb))
        return a.exp() if a == b else (max(a, b).exp() - min(a, b).exp()) / abs(a - b)


@pytest.mark.parametrize("dtype, bound", [(np.float64, 4e-15), (np.float32, 1e-6)])
def test_fog_mean_factor_against_the_exact_mean(dtype, bound):
    """The series below the cut and the difference above it, each to a few ulp of the exact mean, for factors
    that are the correctly rounded e^{e_a}, e^{e_b} (δ from 1e-12 to 60, both sides of the cut)."""
    rng = np.random.default_rng(5)
    gaps = np.concatenate([np.geomspace(1e-12, 60.0, 600), rng.uniform(0.0, 2.0, 600), [FOG_SERIES_BELOW[0],
                           FOG_SERIES_BELOW[1]]])
    worst = 0.0
    for gap, ea in zip(gaps, rng.uniform(-30.0, 30.0, gaps.size)):
        ea = dtype(ea)
        eb = dtype(ea + dtype(gap))
        for a, b in ((ea, eb), (eb, ea)):
            got = fog_mean_factor(dtype(math.exp(a)), dtype(math.exp(b)), abs(a - b))
            assert dtype(got) == got  # computed in the factors' precision
            exact = _exact_fog_mean(a, b)
            worst = max(worst, float(abs(Decimal(float(got)) - exact) / exact))
    assert worst <= bound


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_fog_mean_factor_is_continuous_at_its_cut(dtype):
    """Just below and just above δ_c (series, then difference) the means agree to the difference's rounding."""
    cut = FOG_SERIES_BELOW[0] if dtype == np.float64 else FOG_SERIES_BELOW[1]
    tol = 1e-15 if dtype == np.float64 else 1e-6
    for ea in (-3.0, 0.0, 2.5):
        below, above = np.nextafter(dtype(cut), dtype(0)), dtype(cut)
        means = [fog_mean_factor(dtype(math.exp(ea)), dtype(math.exp(ea - float(gap))), gap) for gap in (below, above)]
        assert means[0] == pytest.approx(means[1], rel=tol)


def test_fog_mean_factor_below_the_cut_does_not_cancel():
    """A factor off by a relative ε (the march's running product) moves the mean by about ε, not ε/δ: below the
    cut the mean is the top factor times the series, so the bottom factor's error does not enter at all."""
    top, gap = math.exp(1.0), 1e-9
    exact = fog_mean_factor(top, math.exp(1.0 - gap), gap)
    for eps in (1e-14, -1e-14):
        assert fog_mean_factor(top, math.exp(1.0 - gap) * (1.0 + eps), gap) == exact
        assert fog_mean_factor(top * (1.0 + eps), math.exp(1.0 - gap), gap) == pytest.approx(exact, rel=2e-14)


@given(st.floats(-60.0, 60.0), st.floats(-60.0, 60.0))
def test_fog_mean_factor_lies_between_the_end_factors(ea, eb):
    fa, fb = math.exp(ea), math.exp(eb)
    mean = fog_mean_factor(fa, fb, abs(ea - eb))
    assert min(fa, fb) * (1 - 1e-15) <= mean <= max(fa, fb) * (1 + 1e-15)


def test_height_fog_along_a_level_ray_is_homogeneous_at_that_height():
    m = pack_medium(_scene(height_fog=HeightFog(base=0.5, falloff=0.4)))
    got = optical_depth(m.params, m.noise, 0.2, 1.0, -1.0, 1.0, 0.0, 0.0, 0.5, 9.0, 1)
    assert got == pytest.approx(0.25 * 8.5 * math.exp(-0.5 * 0.4), rel=1e-12)


def test_homogeneous_and_bounded_optical_depth():
    m = pack_medium(_scene())
    assert optical_depth(m.params, m.noise, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 5.0, 1) == pytest.approx(0.25 * 4)
    b = pack_medium(_scene(bounds=Bounds(min=(-1.0, -1.0, 2.0), max=(1.0, 1.0, 3.5))))
    assert optical_depth(b.params, b.noise, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0, 1) == pytest.approx(0.25 * 1.5)
    assert optical_depth(b.params, b.noise, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0, 1) == 0.0
    assert density(b.params, b.noise, 0.0, 0.0, 1.9) == 0.0 and density(b.params, b.noise, 0.0, 0.0, 2.1) == 1.0


def test_noise_is_periodic_bounded_and_trilinear():
    lat = noise_lattice(8, 3)
    assert np.array_equal(lat, noise_lattice(8, 3)) and not np.array_equal(lat, noise_lattice(8, 4))
    rng = np.random.default_rng(0)
    for p in rng.uniform(-20, 20, size=(50, 3)):
        v = noise_value(lat, *p)
        assert 0.0 <= v < 1.0
        assert v == pytest.approx(noise_value(lat, p[0] + 8, p[1] - 16, p[2] + 24), abs=1e-12)
    assert noise_value(lat, 2.5, 3.5, 4.5) == lat[2, 3, 4]  # values at cell centres
    mid = noise_value(lat, 3.0, 3.5, 4.5)
    assert mid == pytest.approx(0.5 * (lat[2, 3, 4] + lat[3, 3, 4]))


def test_noise_density_factor_and_motion():
    s = _scene(noise=Noise(scale=0.5, intensity=3.0, offset=0.2, velocity=(1.0, 0.0, 0.5), period=8))
    m = pack_medium(s)
    lat = noise_lattice(8, 7)
    x = np.array([0.3, 1.1, -2.0])
    shifted = x - np.array([1.0, 0.0, 0.5]) * 2.0
    n = noise_value(lat, *(0.5 * shifted))
    assert density(m.params, m.noise, *x) == pytest.approx(min(max(max(n - 0.2, 0) * 3.0, 0.0), 1.0))
    tau = optical_depth(m.params, m.noise, *x, 0.0, 0.6, 0.8, 0.0, 6.0, 4000)
    assert tau == pytest.approx(_tau_quad(m, x, (0.0, 0.6, 0.8), 0.0, 6.0), rel=1e-4)


def test_float32_medium_is_float32_and_close():
    m64 = pack_medium(_scene(height_fog=HeightFog(base=0.0, falloff=0.3)))
    m32 = m64.astype(np.float32)
    f = np.float32
    t32 = optical_depth(m32.params, m32.noise, f(0), f(1), f(0), f(0), f(0.6), f(0.8), f(0), f(10), 1)
    t64 = optical_depth(m64.params, m64.noise, 0.0, 1.0, 0.0, 0.0, 0.6, 0.8, 0.0, 10.0, 1)
    assert t32 == pytest.approx(t64, rel=1e-6)
    assert np.float32(t32) == t32


def test_extreme_fog_stays_finite():
    m = pack_medium(_scene(height_fog=HeightFog(base=0.0, falloff=50.0)))
    tau = optical_depth(m.params, m.noise, 0.0, -1e4, 0.0, 0.0, -1.0, 0.0, 0.0, 10.0, 1)
    assert math.isfinite(tau) and math.exp(-tau) == 0.0


def test_volumetric_lights_noise_volume():
    if not NOISE_FILE.is_file():
        pytest.fail(f"shared test data missing: {NOISE_FILE}")
    lat = load_noise_volume(str(NOISE_FILE))
    raw = NOISE_FILE.read_bytes()
    assert lat.shape == (128, 128, 128)
    for w, h, d in [(0, 0, 0), (5, 17, 99), (127, 3, 64)]:
        assert lat[w, h, d] == raw[128 + w + 128 * h + 16384 * d] / 255.0


def test_bad_noise_volume_is_an_input_error(tmp_path):
    from vlref.errors import InputError
    bad = tmp_path / "n.bytes"
    bad.write_bytes(b"DDS " + bytes(200))
    with pytest.raises(InputError, match="medium.noise.path"):
        load_noise_volume(str(bad))
