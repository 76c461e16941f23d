"""Every registered technique renders every bundled scene it can light at a small size without NaN/Inf, and
keeps the stage-buffer contract of :mod:`vlref.techniques`: ``final = scene · T + L`` bit for bit."""

import numpy as np
import pytest

from vlref.render import prepare_frame
from vlref.scene.bundled import bundled_scenes
from vlref.scene.load import load_scene
from vlref.techniques import FRAME_BUFFERS, TECHNIQUES
from vlref.techniques.urp import has_main_light


def _small(name):
    base = load_scene(name)
    sets = ["render.width=48", "render.height=27", "render.steps=6"]
    sets += [f"lights.{i}.shadows.resolution=64" for i, l in enumerate(base.lights) if l.shadows is not None]
    return load_scene(name, sets)


@pytest.mark.parametrize("name", sorted(bundled_scenes()))
def test_bundled_scene_renders_finite(name):
    scene = _small(name)
    frame = prepare_frame(scene)
    for technique, entry in TECHNIQUES.items():
        if technique == "urp" and not has_main_light(scene):  # urp marches the main light only
            continue
        out = entry.render(scene, frame)
        assert out["inscatter"].shape == (27, 48, 3) and out["final"].shape == (27, 48, 3)
        assert out["transmittance"].shape == (27, 48)
        for key in FRAME_BUFFERS:
            assert np.all(np.isfinite(out[key])), (technique, key)
        # one composite per technique, and each (BlitAdd, URP's, the additive radial one) is scene · T + L
        composite = frame.scene_colour * out["transmittance"][..., None] + out["inscatter"]
        assert np.array_equal(out["final"], composite), technique
        assert np.all(out["inscatter"] >= 0.0), technique
        assert np.all((out["transmittance"] >= 0.0) & (out["transmittance"] <= 1.0)), technique
