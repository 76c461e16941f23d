"""The peak-memory estimate of a render (vlref.memory) against tracemalloc's measured peak."""

import tracemalloc

import pytest

from vlref.errors import InputError
from vlref.memory import MemoryEstimate, check_memory, estimate
from vlref.render import render
from vlref.scene import load_scene

FACTOR = 1.5  # the estimate lies within this factor of the measured peak (module docstring of vlref.memory)


@pytest.mark.parametrize("name, technique, shadow_res", [
    ("pillars", "killzone", 256),     # spot: one face; frame buffers and shadow map of similar size
    ("cage", "physical", 128),        # point: six faces
    ("forest", "urp", 128),           # directional: cascades
])
def test_estimate_is_within_a_factor_of_the_tracemalloc_peak(name, technique, shadow_res):
    base = load_scene(name)
    sets = ["render.width=200", "render.height=112", "render.steps=4", f'render.technique="{technique}"']
    sets += [f"lights.{i}.shadows.resolution={shadow_res}" for i, l in enumerate(base.lights) if l.shadows]
    scene = load_scene(name, sets)
    render(load_scene(name, sets + ["render.width=8", "render.height=8"]))  # compile outside the measurement
    tracemalloc.start()
    try:
        render(scene, stages=True)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    est = estimate(scene)
    allocated = est.frame + est.shadows
    assert peak / FACTOR <= allocated <= peak * FACTOR, (allocated / 1e6, peak / 1e6)


def test_refusal_names_the_largest_part_and_both_figures():
    scene = load_scene("pillars", ["render.width=4000", "render.height=4000"])
    with pytest.raises(InputError) as exc:
        check_memory(scene, available=1e9)
    assert exc.value.path == "render.width" and exc.value.file == scene.source
    assert "needs about 4.1 GB, 1.0 GB available" in exc.value.reason
    small = load_scene("pillars", ["render.width=16", "render.height=9", "lights.0.shadows.resolution=8192"])
    with pytest.raises(InputError) as exc:  # 0.34 GB of map + the process's 0.3 GB
        check_memory(small, available=5e8)
    assert exc.value.path == "lights[0].shadows.resolution"
    assert isinstance(check_memory(small, available=1e12), MemoryEstimate)


def test_refusal_names_the_command_line_when_a_set_value_made_the_largest_part():
    sets = ["render.width=4000", "render.height=4000"]
    with pytest.raises(InputError) as exc:
        check_memory(load_scene("pillars", sets), available=1e9, overrides=sets)
    assert (exc.value.file, exc.value.path) == ("<command line>", "--set render.height=4000")
    sets = ["render.width=16", "lights.0.shadows.resolution=8192"]
    with pytest.raises(InputError) as exc:
        check_memory(load_scene("pillars", sets), available=5e8, overrides=sets)
    assert (exc.value.file, exc.value.path) == ("<command line>", "--set lights.0.shadows.resolution=8192")
    sets = ["lights.0.intensity=5"]  # not what the estimate grows with: the scene file is named
    scene = load_scene("pillars", ["render.width=4000", "render.height=4000"])
    with pytest.raises(InputError) as exc:
        check_memory(scene, available=1e9, overrides=sets)
    assert (exc.value.file, exc.value.path) == (scene.source, "render.width")
