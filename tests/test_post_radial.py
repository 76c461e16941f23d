"""vlref.post.radial: Listing 13-1 against its closed form, the disenone port, occlusion helpers."""

import math

import numba
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from post_cases import image, sizes
from vlref.post.radial import (ADDRESS_MODES, RADIAL_TILE, bilinear_sample, disenone_exposure, disenone_scatter,
                               light_screen_uv, occlusion_opaque, occlusion_transparent, radial_blur, radiate)


def tex(img, u, v, address="clamp"):
    """Plain bilinear fetch at one uv."""
    H, W = img.shape[:2]
    x, y = u * W - 0.5, v * H - 0.5
    x0, y0 = math.floor(x), math.floor(y)
    tx, ty = x - x0, y - y0

    def at(r, c):
        if address == "clamp":
            return img[min(max(r, 0), H - 1), min(max(c, 0), W - 1)]
        if address == "repeat":
            return img[r % H, c % W]
        return img[r, c] if 0 <= r < H and 0 <= c < W else 0.0 * img[0, 0]

    top = at(y0, x0) + tx * (at(y0, x0 + 1) - at(y0, x0))
    bot = at(y0 + 1, x0) + tx * (at(y0 + 1, x0 + 1) - at(y0 + 1, x0))
    return top + ty * (bot - top)


@given(sizes(3, 9), st.sampled_from(["clamp", "repeat", "border"]))
@settings(max_examples=20)
def test_bilinear_sample_matches_reference(case, address):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    img = image(rng, H, W, 3)
    u, v = rng.uniform(-0.5, 1.5, 30), rng.uniform(-0.5, 1.5, 30)
    out = bilinear_sample(img, u, v, address)
    for k in range(30):
        assert (out[k] == tex(img, u[k], v[k], address)).all()


light_uvs = st.tuples(st.floats(-0.6, 1.6), st.floats(-0.6, 1.6))


@given(sizes(4, 9), light_uvs, st.integers(1, 12), st.floats(0.0, 1.5), st.floats(0.0, 3.0), st.floats(0.5, 1.0))
@settings(max_examples=30)
def test_radial_loop_matches_closed_form(case, light, n, density, weight, decay):
    seed, H, W = case
    img = image(np.random.default_rng(seed), H, W)
    exposure = 0.7
    out = radial_blur(img, light, n, density, weight, decay, exposure)
    for r in range(H):
        for c in range(W):
            u, v = (c + 0.5) / W, (r + 0.5) / H
            du, dv = (u - light[0]) * density / n, (v - light[1]) * density / n
            C = tex(img, u, v) + weight * sum(decay ** (i - 1) * tex(img, u - i * du, v - i * dv)
                                              for i in range(1, n + 1))
            assert out[r, c] == pytest.approx(C * exposure, rel=1e-9, abs=1e-12)


def listing_13_1(img, light, divisor, iterations, density, weight, tap_scale, decay, address):
    """The shader loop pixel by pixel in Python floats: ``u -= delta`` by repeated subtraction, ``acc += tex * w``."""
    H, W = img.shape[:2]
    out = np.zeros(img.shape)
    scale = 1.0 / divisor * density
    for r in range(H):
        for c in range(W):
            u, v = (c + 0.5) / W, (r + 0.5) / H
            du, dv = (u - light[0]) * scale, (v - light[1]) * scale
            acc = 0.0 + tex(img, u, v, address) * 1.0
            dec = 1.0
            for _ in range(iterations):
                u, v = u - du, v - dv
                acc = acc + tex(img, u, v, address) * (dec * tap_scale * weight)
                dec = dec * decay
            out[r, c] = acc
    return out


@pytest.mark.parametrize("address", ["clamp", "repeat", "border"])
@pytest.mark.parametrize("light", [(0.3, 0.6), (-0.7, 1.9), (2.5, -1.2)])
def test_radial_same_bits_as_the_pixel_loop(address, light):
    # the kernel runs taps outer, pixels inner over a row: per pixel the same operations in the same order
    rng = np.random.default_rng(11)
    for img in (image(rng, 7, 9, 3), image(rng, 6, 5)):
        got = disenone_scatter(img, light, 0.9, 0.6, 0.97, num_samples=12, iterations=11, address=address)
        assert np.array_equal(got, listing_13_1(img, light, 12, 11, 0.9, 0.6, 0.03125, 0.97, address))
        got = radial_blur(img, light, 10, 0.8, 0.5, 0.95, 0.37, address, visibility=0.5)
        assert np.array_equal(got, (listing_13_1(img, light, 10, 10, 0.8, 0.5, 1.0, 0.95, address) * 0.37) * 0.5)


@pytest.mark.parametrize("address", ["clamp", "border"])
@pytest.mark.parametrize("light", [(1e25, 0.5), (0.4, -3e21), (-1e300, 1e300)])
def test_a_light_beyond_two_to_the_63_texels_clamps_its_taps_on_its_own_side(address, light):
    # the taps toward a light that far off screen leave the image on the light's side: clamped to that edge (or its
    # border); an integer conversion of floor(x) overflows there (the other edge was read)
    img = image(np.random.default_rng(13), 6, 9, 3)
    got = radial_blur(img, light, 8, 0.9, 0.5, 0.95, 0.37, address)
    assert np.array_equal(got, listing_13_1(img, light, 8, 8, 0.9, 0.5, 1.0, 0.95, address) * 0.37)


def test_radial_density_one_ends_on_the_light():
    # with Density = 1 the n-th tap sits on the light: a delta-like image at the light's texel
    # reaches every pixel with weight Decay^(n-1) * Weight
    H = W = 8
    img = np.zeros((H, W))
    img[2, 5] = 1.0
    light = ((5 + 0.5) / W, (2 + 0.5) / H)
    out = radial_blur(img, light, 4, 1.0, 1.0, 0.5, 1.0)
    assert out[6, 1] == pytest.approx(0.5 ** 3, rel=1e-12)
    assert out[2, 5] == pytest.approx(1.0 + (1 + 0.5 + 0.25 + 0.125), rel=1e-12)


def test_off_screen_and_behind_camera():
    img = image(np.random.default_rng(4), 6, 7)
    off = radial_blur(img, (3.0, -2.0), 16, 1.0, 0.5, 0.95, 1.0)
    assert np.isfinite(off).all() and (off > 0).all()
    (u, v), vis = light_screen_uv((0.2, 0.1, 0.5, -1.0))
    assert vis == 0.0 and (u, v) == (0.5, 0.5)
    assert (radial_blur(img, (u, v), 16, 1.0, 0.5, 0.95, 1.0, visibility=vis) == 0.0).all()
    (u, v), vis = light_screen_uv((0.5, 0.5, 0.2, 1.0))
    assert vis == 1.0 and (u, v) == (0.75, 0.25)
    (u, v), vis = light_screen_uv((4.0, 0.0, 0.2, 1.0))   # right of the screen: uv outside [0, 1]
    assert vis == 1.0 and u == 2.5
    with pytest.raises(ValueError):
        radial_blur(img, (np.nan, 0.5), 16, 1.0, 0.5, 0.95, 1.0)


def test_radial_same_bits_as_the_pixel_loop_across_column_bands():
    # wider than RADIAL_TILE: the columns are cut into bands of equal width (here 2 of 150), tiles taken on demand
    # (RGB has a path of its own, the channels of a texel read together)
    for channels in (2, 3):
        img = image(np.random.default_rng(12), 3, RADIAL_TILE + 44, channels)
        for address in ADDRESS_MODES:
            got = radial_blur(img, (0.7, -0.4), 6, 0.9, 0.5, 0.95, 0.37, address)
            assert np.array_equal(got, listing_13_1(img, (0.7, -0.4), 6, 6, 0.9, 0.5, 1.0, 0.95, address) * 0.37)


def test_same_bits_for_any_thread_count():
    img = image(np.random.default_rng(8), 9, 11, 3)
    runs = []
    for n in (1, numba.config.NUMBA_NUM_THREADS):
        numba.set_num_threads(n)
        runs.append(radial_blur(img, (0.2, 1.3), 40, 0.9, 0.3, 0.97, 0.5))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert (runs[0] == runs[1]).all()


@given(sizes(4, 9), light_uvs, st.floats(0.0, 2.0), st.floats(0.0, 1.0), st.floats(0.8, 1.0))
@settings(max_examples=20)
def test_disenone_scatter_closed_form(case, light, density, weight, decay):
    seed, H, W = case
    img = image(np.random.default_rng(seed), H, W, 3)
    out = disenone_scatter(img, light, density, weight, decay)
    for r in range(H):
        for c in range(W):
            u, v = (c + 0.5) / W, (r + 0.5) / H
            du, dv = (u - light[0]) * density / 32, (v - light[1]) * density / 32
            ref = tex(img, u, v) + sum(decay ** (i - 1) * 0.03125 * weight * tex(img, u - i * du, v - i * dv)
                                       for i in range(1, 32))
            np.testing.assert_allclose(out[r, c], ref, rtol=1e-9, atol=1e-12)


def test_radiate_disc():
    H, W = 40, 64
    occ = np.ones((H, W, 3))
    light = ((20 + 0.5) / W, (10 + 0.5) / H)
    out = radiate(occ, light, radius_px=12.0)
    assert (out[10, 20] == 0.5).all()                       # peak 0.5 at the light
    assert (out[10, 20 + 12] == 0.0).all() and (out[10 + 12, 20] == 0.0).all()
    assert out[10, 26, 0] == pytest.approx(0.5 * (144 - 36) / 144)   # pixels, not uv: round disc
    assert out[16, 20, 0] == pytest.approx(out[10, 26, 0])
    assert (radiate(occ[..., 0] * 0.0, light) == 0.0).all()       # masked by occluders


def test_disenone_exposure():
    assert disenone_exposure(0.8, 10.0, 30.0) == 0.8
    assert disenone_exposure(0.8, 45.0, 30.0) == pytest.approx(0.8 * 0.5)
    assert disenone_exposure(0.8, 60.0, 30.0) == 0.0
    assert disenone_exposure(0.8, 50.0, 20.0) == pytest.approx(0.8 * -0.5)   # the source's negative range


def test_occlusion_helpers():
    oid = np.array([[-1, 0], [3, -1]])
    occ = occlusion_opaque(oid)
    assert occ.tolist() == [[1.0, 0.0], [0.0, 1.0]]
    a = np.array([[0.5, 0.0], [0.25, 0.8]])
    dis = occlusion_transparent(np.ones((2, 2)), a, mode="disenone")
    np.testing.assert_allclose(dis[..., 0], 1 - a * a, rtol=1e-15)             # 1 - alpha^2 over white
    tint = np.array([1.0, 0.5, 0.0])
    filt = occlusion_transparent(occ, a, tint)
    np.testing.assert_allclose(filt, occ[..., None] * (1 - a)[..., None] * tint, rtol=1e-15)
    with pytest.raises(ValueError):
        occlusion_transparent(occ, a, mode="multiply")
