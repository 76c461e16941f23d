"""vlref.post.composite: the composite formulas and the storage rounding."""

import numpy as np
import pytest
from hypothesis import given, settings

from post_cases import image, sizes
from vlref.post.composite import (blend_add_fp16, composite_add, composite_physical, composite_urp, composite_vl,
                                  fp16, sum_and_composite, unorm8, unorm16)


@given(sizes(2, 8))
@settings(max_examples=10)
def test_composites_per_pixel(case):
    seed, H, W = case
    rng = np.random.default_rng(seed)
    scene, L, T, F = image(rng, H, W, 4), image(rng, H, W, 3), rng.random((H, W)), rng.random((H, W))
    vol = np.concatenate([L, T[..., None]], axis=2)
    phys = composite_physical(scene[..., :3], T, L)
    vl4, vl3 = composite_vl(scene, vol), composite_vl(scene[..., :3], vol)
    urp = composite_urp(scene[..., :3], F, 2.5, (1.0, 0.5, 0.25))
    add = composite_add(scene[..., :3], F, 0.8)
    for r in range(H):
        for c in range(W):
            for ch in range(3):
                assert phys[r, c, ch] == scene[r, c, ch] * T[r, c] + L[r, c, ch]
                assert vl4[r, c, ch] == vl3[r, c, ch] == scene[r, c, ch] * T[r, c] + L[r, c, ch]
                assert urp[r, c, ch] == scene[r, c, ch] + (F[r, c] * 2.5) * (1.0, 0.5, 0.25)[ch]
                assert add[r, c, ch] == scene[r, c, ch] + F[r, c] * 0.8
            assert vl4[r, c, 3] == scene[r, c, 3] * T[r, c]
    assert vl3.shape == (H, W, 3)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("n", [0, 1, 2, 4])
def test_the_lights_sum_adds_in_light_order(n, dtype):
    """The sum of the lights' in-scattering: ((L_0 + L_1) + L_2) + ... in the buffers' precision, element by
    element (the same bits as NumPy's sum over the first axis); zeros without lights."""
    rng = np.random.default_rng(n)
    per_light = (rng.random((n, 7, 5, 3)) * 10.0 ** rng.integers(-8, 8, (n, 7, 5, 3))).astype(dtype)
    got, _ = sum_and_composite(per_light, np.zeros((7, 5, 3)), np.ones((7, 5), dtype))
    assert got.dtype == dtype and got.shape == (7, 5, 3)
    want = np.zeros((7, 5, 3), dtype)
    if n:
        want = per_light[0].copy()
        for k in range(1, n):
            want = want + per_light[k]
    assert got.tobytes() == want.tobytes()
    assert got.tobytes() == per_light.sum(axis=0).tobytes()


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("n", [0, 1, 4])
def test_sum_and_composite_has_the_bits_of_the_sum_then_the_composite(n, dtype):
    """The physical technique's one pass: NumPy's sum over the lights (in light order, in the buffers' dtype) and
    ``scene * T + sum`` in float64, bit for bit, over magnitudes 1e-8..1e8; zeros and ``scene * T`` without lights."""
    rng = np.random.default_rng(10 + n)
    per_light = (rng.random((n, 9, 7, 3)) * 10.0 ** rng.integers(-8, 8, (n, 9, 7, 3))).astype(dtype)
    scene, trans = rng.random((9, 7, 3)) * 10.0, rng.random((9, 7)).astype(dtype)
    inscatter, final = sum_and_composite(per_light, scene, trans)
    want = per_light.sum(axis=0) if n else np.zeros((9, 7, 3), dtype)
    assert inscatter.dtype == dtype and final.dtype == np.float64
    assert inscatter.tobytes() == want.tobytes()
    assert final.tobytes() == (scene * trans[:, :, None] + want).tobytes()
    assert final.tobytes() == composite_physical(scene, trans, want).tobytes()
    with pytest.raises(ValueError, match="does not match"):
        sum_and_composite(np.zeros((2, 9, 6, 3), dtype), scene, trans)


def test_composite_physical_promotes_float32_buffers():
    """float32 march buffers over a float64 scene composite in float64, as NumPy promotes them."""
    rng = np.random.default_rng(3)
    scene, L, T = rng.random((4, 6, 3)), rng.random((4, 6, 3)).astype(np.float32), rng.random((4, 6)).astype(np.float32)
    got = composite_physical(scene, T, L)
    assert got.dtype == np.float64
    assert got.tobytes() == (scene * T[:, :, None] + L).tobytes()


def test_fp16_rounding():
    x = np.array([1.0 / 3.0, 2049.0, 1e-8, -70000.0, 70000.0, 65519.0])
    out = fp16(x)
    assert out[0] == float(np.float16(np.float32(1.0 / 3.0)))
    assert out[1] == 2048.0                       # nearest even at spacing 2
    assert out[3] == -65504.0 and out[4] == 65504.0 and out[5] == 65504.0
    assert np.isinf(fp16(np.array([70000.0]), overflow="inf")).all()
    # every result is representable: a second rounding is the identity
    assert (fp16(out) == out).all()


def test_blend_add_fp16_rounds_after_each_blend():
    acc = np.zeros(3)
    for _ in range(3000):
        acc = blend_add_fp16(acc, np.full(3, 1.0))
    assert (acc == 2048.0).all()          # 2048 + 1 rounds back to 2048 in half precision
    assert (blend_add_fp16(np.array([0.1]), np.array([0.2])) == fp16(np.float32(0.1) + np.float32(0.2))).all()


def test_unorm_quantisation():
    x = np.array([-0.5, 0.0, 0.25, 1.0 / 3.0, 1.0, 7.0])
    q16, q8 = unorm16(x), unorm8(x)
    assert q16.tolist() == [0.0, 0.0, 16384 / 65535, 21845 / 65535, 1.0, 1.0]
    assert q8.tolist() == [0.0, 0.0, 64 / 255, 85 / 255, 1.0, 1.0]
    r = np.random.default_rng(1).random(1000)
    assert np.abs(unorm16(r) - r).max() <= 0.5 / 65535 + 1e-17
    assert (unorm16(unorm16(r)) == unorm16(r)).all()


def test_bad_shapes_raise():
    with pytest.raises(ValueError):
        composite_vl(np.zeros((2, 2, 3)), np.zeros((2, 2, 3)))
    with pytest.raises(ValueError):
        composite_physical(np.zeros((2, 2, 3)), np.zeros((3, 2)), np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match="inscatter"):
        composite_physical(np.zeros((2, 2, 3)), np.zeros((2, 2)), np.zeros((2, 3, 3)))
