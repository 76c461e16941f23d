"""The technique registry (:mod:`vlref.techniques`) is the one list of techniques: every entry is complete
(render function, parameter class, golden applicability rule, memory figure), and the scene model, the
command line, the golden suite and the stored goldens name exactly the registered techniques."""

import dataclasses
import json
from pathlib import Path

import pytest

from vlref.cli.commands import command
from vlref.oracle.golden import load_suite, suite_entries
from vlref.scene import bundled_scenes, load_scene
from vlref.scene.model import TECHNIQUES as SCENE_TECHNIQUES
from vlref.scene.model import RenderSettings
from vlref.scene.technique_params import TechniqueParams
from vlref.techniques import RESOLVED_DEFAULTS, TECHNIQUES, resolved

GOLDEN_MANIFEST = Path(__file__).resolve().parents[1] / "data" / "golden" / "manifest.json"


@pytest.mark.parametrize("name", list(TECHNIQUES))
def test_every_entry_has_a_render_function_its_parameter_table_and_a_golden_rule(name):
    entry = TECHNIQUES[name]
    assert entry.name == name
    assert callable(entry.render)
    # the parameter class is the [techniques.NAME] table the scene model reads
    assert dataclasses.is_dataclass(entry.params)
    assert type(TechniqueParams().of(name)) is entry.params
    # the golden rule: a callable answering a plain bool for every bundled scene
    assert callable(entry.applies), f"{name} has no golden applicability rule"
    for path in bundled_scenes().values():
        assert type(entry.applies(load_scene(path))) is bool, name
    assert isinstance(entry.bytes_per_pixel, int) and entry.bytes_per_pixel > 0
    assert entry.notes is None or callable(entry.notes)


def test_every_registered_technique_has_golden_entries():
    """A technique whose rule applies to no bundled scene would never be checked by the goldens."""
    assert {e.technique for e in suite_entries(load_suite())} == set(TECHNIQUES)


def test_the_scene_model_the_cli_the_golden_suite_and_the_goldens_name_the_registered_techniques():
    names = tuple(TECHNIQUES)
    assert names == SCENE_TECHNIQUES
    technique_field = {f.name: f for f in dataclasses.fields(RenderSettings)}["technique"]
    assert tuple(technique_field.metadata["choices"]) == names
    assert load_suite().techniques == names
    stored = json.loads(GOLDEN_MANIFEST.read_text())
    assert tuple(stored["suite"]["techniques"]) == names
    assert {e["technique"] for e in stored["entries"]} == set(names)
    render = command("render").parser()
    technique_help = next(a.help for a in render._actions if "--technique" in a.option_strings)
    assert f"({', '.join(names)})" in technique_help


def test_resolved_takes_the_scene_setting_then_the_technique_default_then_the_common_default():
    scene = load_scene("pillars", ['render.technique="killzone"'])
    assert scene.render.steps is None and scene.render.resolution is None
    assert resolved(scene, "steps") == scene.techniques.killzone.steps == 32
    assert resolved(scene, "sampling") == "bayer4"
    assert resolved(scene, "resolution") == "half"
    scene = load_scene("pillars", ['render.technique="killzone"', "render.steps=7", 'render.resolution="quarter"'])
    assert resolved(scene, "steps") == 7 and resolved(scene, "resolution") == "quarter"
    scene = load_scene("pillars", ['render.technique="physical"'])  # physical has no resolution of its own
    assert not hasattr(scene.techniques.physical, "resolution")
    assert resolved(scene, "resolution") == RESOLVED_DEFAULTS["resolution"] == "full"
    assert resolved(scene, "sampling") == "bayer8"
