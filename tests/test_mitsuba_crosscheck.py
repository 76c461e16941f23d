"""Cross-check of the quadrature reference with Mitsuba 3 (volpath, single scattering).

Matched conventions (docs/PHYSICS.md): Mitsuba's point-light ``intensity`` is radiant intensity
(W/sr) like vlref's ``color × intensity``; Mitsuba's ``hg`` with ``g > 0`` scatters forward, the same
physics as vlref's ``cos θ = dot(d, l)`` convention (its vectors point the other way, so the formula
has the opposite sign on its own cosine); the medium is a box (``cube`` with a ``null`` BSDF and a
``homogeneous`` interior) matching ``medium.bounds``; ``albedo = σs/σt``. ``volpath`` with
``max_depth = 2`` counts the camera vertex and one scattering vertex with next-event estimation:
exactly single scattering. Mitsuba's pixels average over the pixel area (box filter), so vlref's
reference is rendered at 4x4 sub-pixel rays and box-averaged.
"""

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is optional (pip install mitsuba) for this cross-check")

from vlref.reference.quadrature import render_reference  # noqa: E402
from vlref.scene.model import Bounds, CameraSettings, Light, Medium, RenderSettings, Scene  # noqa: E402

W, H, SUB = 16, 12, 4
SIGMA_T, ALBEDO, G, I = 0.25, 0.8, 0.5, 20.0


def _mitsuba_runs(runs=8, spp=128):
    mi.set_variant("scalar_rgb")
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 50.0, "fov_axis": "y",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1, -10], target=[0, 1, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"},
                            "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "light": {"type": "point", "position": [0.0, 2.0, 0.0], "intensity": {"type": "rgb", "value": [I, I, I]}},
        "box": {"type": "cube", "to_world": mi.ScalarTransform4f().translate([0, 1, 0]).scale([4, 3, 4]),
                "bsdf": {"type": "null"},
                "interior": {"type": "homogeneous", "albedo": {"type": "rgb", "value": [ALBEDO] * 3},
                             "sigma_t": SIGMA_T, "phase": {"type": "hg", "g": G}}},
    })
    return np.stack([np.array(mi.render(scene, seed=s))[..., 0] for s in range(runs)])


def _vlref(w, h, g=G):
    scene = Scene(render=RenderSettings(width=w, height=h, max_distance=40.0),
                  camera=CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
                  medium=Medium(scattering=ALBEDO * SIGMA_T, absorption=(1 - ALBEDO) * SIGMA_T, anisotropy=g,
                                bounds=Bounds(min=(-4.0, -2.0, -4.0), max=(4.0, 4.0, 4.0))),
                  lights=(Light(type="point", position=(0.0, 2.0, 0.0), intensity=I, range=100.0),))
    return render_reference(scene, rel_tol=1e-5)


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
