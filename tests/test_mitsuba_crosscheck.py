"""Cross-check of the quadrature reference with Mitsuba 3 (volpath, single scattering) on a point light in a box of
medium, converted by :func:`vlref.reference.mitsuba.mitsuba_scene` (its docstring lists the matched conventions).
Mitsuba's pixels average over the pixel area (box filter), so vlref's reference is rendered at 4x4 sub-pixel rays
and box-averaged.
"""

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is optional (pip install mitsuba) for this cross-check")

from vlref.reference.mitsuba import mitsuba_scene  # noqa: E402
from vlref.reference.quadrature import render_reference  # noqa: E402
from vlref.scene.model import Bounds, CameraSettings, Light, Medium, RenderSettings, Scene  # noqa: E402

W, H, SUB = 16, 12, 4
SIGMA_T, ALBEDO, G, I = 0.25, 0.8, 0.5, 20.0


def _scene(w, h, g=G):
    return Scene(render=RenderSettings(width=w, height=h, max_distance=40.0),
                 camera=CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
                 medium=Medium(scattering=ALBEDO * SIGMA_T, absorption=(1 - ALBEDO) * SIGMA_T, anisotropy=g,
                               bounds=Bounds(min=(-4.0, -2.0, -4.0), max=(4.0, 4.0, 4.0))),
                 lights=(Light(type="point", position=(0.0, 2.0, 0.0), intensity=I, range=100.0),))


def _mitsuba_runs(runs=8, spp=128):
    mi.set_variant("scalar_rgb")
    description = mitsuba_scene(_scene(W, H))
    description["sensor"] = {
        "type": "perspective", "fov": 50.0, "fov_axis": "y",
        "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1, -10], target=[0, 1, 0], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp}}
    scene = mi.load_dict(description)
    return np.stack([np.array(mi.render(scene, seed=s))[..., 0] for s in range(runs)])


def _vlref(w, h, g=G):
    return render_reference(_scene(w, h, g), rel_tol=1e-5)


def test_reference_matches_mitsuba_within_monte_carlo_noise():
    runs = _mitsuba_runs()
    mean = runs.mean(axis=0)
    stderr = runs.std(axis=0, ddof=1) / np.sqrt(runs.shape[0])
    ref = _vlref(W * SUB, H * SUB)
    ours = ref.inscatter[..., 0].reshape(H, SUB, W, SUB).mean(axis=(1, 3))
    # the scene is symmetric in x, so Mitsuba's horizontal image orientation does not matter here
    z = np.abs(mean - ours) / np.maximum(stderr, 1e-12)
    assert np.mean(z < 4.0) > 0.97, np.max(z)
    assert np.all(z < 6.0), np.max(z)
    total_se = np.sqrt(np.sum(stderr ** 2))
    assert abs(mean.sum() - ours.sum()) < 4.0 * total_se
    # the phase sign is pinned: vlref with g flipped is far outside Mitsuba's noise
    flipped = _vlref(W * SUB, H * SUB, -G).inscatter[..., 0].reshape(H, SUB, W, SUB).mean(axis=(1, 3))
    assert abs(mean.sum() - flipped.sum()) > 8.0 * total_se
