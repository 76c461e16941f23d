"""Every technique renders every applicable bundled scene at a small size without NaN/Inf."""

import numpy as np
import pytest

from vlref.render import prepare_frame
from vlref.scene.bundled import bundled_scenes
from vlref.scene.load import load_scene
from vlref.techniques import killzone, radial, slightlymad, urp

MODULES = {"killzone": killzone, "slightlymad": slightlymad, "urp": urp, "radial": radial}


def _small(name):
    base = load_scene(name)
    sets = ["render.width=48", "render.height=27", "render.steps=6"]
    sets += [f"lights.{i}.shadows.resolution=64" for i, l in enumerate(base.lights) if l.shadows is not None]
    return load_scene(name, sets)


@pytest.mark.parametrize("name", sorted(bundled_scenes()))
def test_bundled_scene_renders_finite(name):
    scene = _small(name)
    frame = prepare_frame(scene)
    for technique, module in MODULES.items():
        if technique == "urp" and not any(l.type == "directional" for l in scene.lights):
            continue
        out = module.render(scene, frame)
        assert out["inscatter"].shape == (27, 48, 3) and out["final"].shape == (27, 48, 3)
        assert out["transmittance"].shape == (27, 48)
        for key in ("inscatter", "transmittance", "final"):
            assert np.all(np.isfinite(out[key])), (technique, key)
        assert np.all(out["inscatter"] >= 0.0), technique
        assert np.all((out["transmittance"] >= 0.0) & (out["transmittance"] <= 1.0)), technique
