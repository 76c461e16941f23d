"""The Numba kernels of vlref.post: same bits for any thread count, any input layout, exact weight shortcuts."""

import math

import numba
import numpy as np
import pytest

from post_cases import depth_image, image, raw_depth
from vlref.post.blur import (_GAUSSIAN, _depth_weight, thesis_blur_pass, urp_article_blur_pass, urp_repo_blur_pass,
                             vl_blur_pass)
from vlref.post.downsample import downsample_min
from vlref.post.upsample import bilinear_upsample, thesis_upsample, urp_upsample, vl_upsample


def passes(H, W):
    """Every kernel-backed pass as a function of (values (H, W, 3), linear depth, raw depth); low-res inputs are cut
    from the same arrays."""
    return {
        "thesis_blur": lambda v, z, zr: thesis_blur_pass(v, z, 0),
        "thesis_blur_inverse": lambda v, z, zr: thesis_blur_pass(v, z, 1, depth_weight_kind="inverse"),
        "vl_blur": lambda v, z, zr: vl_blur_pass(np.concatenate([v, v[..., :1]], axis=2), z, 0, "full"),
        "urp_article": lambda v, z, zr: urp_article_blur_pass(v[::2, ::2, 0], zr, 0, 7, 40.0),
        "urp_repo": lambda v, z, zr: urp_repo_blur_pass(v[::2, ::2, 0], zr, 1),
        "bilinear": lambda v, z, zr: bilinear_upsample(v[::2, ::2], z.shape),
        "thesis_up": lambda v, z, zr: thesis_upsample(v[:H // 2, :W // 2], downsample_min(z, 2), z),
        "vl_up": lambda v, z, zr: vl_upsample(v[:H // 2, :W // 2], downsample_min(z, 2), z),
        "urp_up": lambda v, z, zr: urp_upsample(v[:H // 2, :W // 2, 0], zr[:H // 2, :W // 2], zr),
    }


@pytest.mark.parametrize("H, W", [(24, 32), (17, 9)])
def test_same_bits_for_any_thread_count_and_layout(H, W):
    rng = np.random.default_rng(H * W)
    v, z, zr = image(rng, H, W, 3), depth_image(rng, H, W), raw_depth(rng, H, W)
    before = numba.get_num_threads()
    try:
        for name, fn in passes(H, W).items():
            numba.set_num_threads(1)
            one = fn(v, z, zr)
            numba.set_num_threads(before)
            many = fn(v, z, zr)
            view = fn(np.asfortranarray(v), np.asfortranarray(z), np.asfortranarray(zr))   # not C-contiguous
            assert one.tobytes() == many.tobytes() == view.tobytes(), name
            assert np.isfinite(one).all(), name
    finally:
        numba.set_num_threads(before)


def test_gaussian_weight_shortcuts_are_exp_bits():
    # exp(-q) is skipped at q = 0 (exactly 1) and above q = 746 (exp underflows to exactly 0 below
    # -1075 ln 2 = -745.13); around both ends the kernel must return math.exp's bits
    for q in np.concatenate([[0.0, 1e-300, 5e-324], np.linspace(700.0, 760.0, 241), [1e4, np.inf]]):
        dz = math.sqrt(q)
        assert _depth_weight(dz, _GAUSSIAN, 1.0, 1e-3) == math.exp(-(dz * dz)), q
    assert math.exp(-746.0) == 0.0 and math.exp(-745.0) > 0.0
