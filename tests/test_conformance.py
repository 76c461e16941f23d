"""The conformance suite for ports (data/conformance/*.toml) reaches every parameter a technique reads.

In the spirit of Khronos' CTS: small scenes that together set every field of the scene schema
(:mod:`vlref.scene.model`) and of each technique's parameter table (the registry's ``Technique.params``,
:mod:`vlref.scene.technique_params`) away from its default somewhere, and every choice of the laws
(:data:`EVERY_CHOICE`). A port of technique T runs each suite scene with ``render.technique = T`` and
refuses, with a reason, what lies outside its scope (ports/wgpu: ``kz_check.run_suite``).

The fields a technique reads are derived, not listed: every leaf field of the schema, minus the other
techniques' tables, minus :data:`NOT_READ` -- and each entry of :data:`NOT_READ` is itself checked: changing
that field leaves every buffer of the technique bit-identical on a suite scene.
"""

import dataclasses
import typing
from pathlib import Path

import numpy as np
import pytest

from vlref.camera import camera_from_settings
from vlref.render import render
from vlref.scene import load_scene
from vlref.scene.model import SHAPES, Scene
from vlref.techniques import TECHNIQUES

SUITE = Path(__file__).resolve().parents[1] / "data" / "conformance"

EVERY_CHOICE = ("lights.type", "lights.attenuation", "lights.cone", "lights.shadows.filter", "objects.shape")
"""Laws whose every value must appear in the suite (not only one value other than the default)."""

NOT_READ = {
    "*": {"description": "shown by `vlref scenes` only",
          "render.technique": "selects the technique (the port sets its own)",
          "render.exposure": "PNG previews only", "render.auto_exposure": "PNG previews only",
          "objects.name": "a label", "animation": "sequences (`vlref render --frames`); the suite is single frames",
          # 2 MiB VolumetricLights asset, not shipped; vlref's own noise is the default and is in the suite
          "medium.noise.path": "external asset (NoiseVolume.bytes, 2 MiB)",
          "techniques.slightlymad.noise_path": "external asset (NoiseVolume.bytes, 2 MiB)",
          "techniques.urp.jitter_path": "an injected buffer tied to one march size (tests/test_techniques_urp*)"},
    "physical": {"render.frame": "no temporal term", "render.resolution": "always full resolution"},
    "killzone": {"render.frame": "no temporal term", "render.precision": "float64 only",
                 "render.seed": "no hash sampling (bayer patterns only)"},
    "slightlymad": {"render.frame": "no temporal term", "render.precision": "float64 only",
                    "render.sampling": "VL's dither (techniques.slightlymad.dither)"},
    "urp": {"render.frame": "no temporal term", "render.precision": "float64 only",
            "render.sampling": "its own jitter", "render.seed": "its own hash"},
    "radial": {"render.frame": "no temporal term", "render.precision": "float64 only",
               "render.sampling": "no march", "render.seed": "no march", "render.steps": "num_samples",
               "render.resolution": "occlusion_height"},
    "froxel": {"render.precision": "float64 only", "render.sampling": "its Halton jitter",
               "render.seed": "no hash", "render.steps": "slices", "render.resolution": "the grid size"},
}
"""Fields a technique does not read, with the reason; ``"*"`` for all of them. A path covers its subtree.
``test_not_read_fields_do_not_change_the_render`` checks the technique-specific entries."""


def _dataclass_of(tp):
    """The dataclass inside ``tp`` (``X``, ``Optional[X]``, ``tuple[X, ...]``), else None."""
    if dataclasses.is_dataclass(tp):
        return tp
    inner = [a for a in typing.get_args(tp) if dataclasses.is_dataclass(a)]
    return inner[0] if inner else None


def _default(f):
    if f.default is not dataclasses.MISSING:
        return f.default
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else dataclasses.MISSING


def _leaves(cls, prefix=""):
    """``{path: (field, choices)}`` of every leaf field under dataclass ``cls``; object shapes as
    ``objects.<field>`` (fields every shape has) and ``objects.<shape>.<field>``."""
    out = {}
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if f.metadata.get("internal"):
            continue
        path = f"{prefix}{f.name}"
        if "union" in f.metadata:
            tag, classes = f.metadata["union"]
            common = set.intersection(*({g.name for g in dataclasses.fields(c)} for c in classes.values()))
            for shape, c in classes.items():
                for p, leaf in _leaves(c).items():
                    top = p.split(".")[0]
                    out[f"{path}.{p}" if top in common else f"{path}.{shape}.{p}"] = leaf
            out[f"{path}.{tag}"] = (None, tuple(classes))
            continue
        inner = _dataclass_of(hints[f.name])
        if inner is not None:
            out.update(_leaves(inner, path + "."))
        else:
            out[path] = (f, f.metadata.get("choices"))
    return out


def _values(obj, prefix="", out=None):
    """``[(path, value, default)]`` of every leaf set in a built scene (same paths as :func:`_leaves`)."""
    out = [] if out is None else out
    for f in dataclasses.fields(obj):
        if f.metadata.get("internal"):
            continue
        v, path = getattr(obj, f.name), f"{prefix}{f.name}"
        if isinstance(v, tuple) and v and dataclasses.is_dataclass(v[0]):
            for item in v:
                if "union" in f.metadata:
                    tag = f.metadata["union"][0]
                    out.append((f"{path}.{tag}", getattr(item, tag), None))
                    common = {g.name for g in dataclasses.fields(dataclasses.replace(item))} & {"material", "name"}
                    for p, val, d in _values(item, ""):
                        top = p.split(".")[0]
                        out.append((f"{path}.{p}" if top in common or top == tag else f"{path}.{item.shape}.{p}",
                                    val, d))
                else:
                    _values(item, path + ".", out)
        elif dataclasses.is_dataclass(v):
            _values(v, path + ".", out)
        else:
            out.append((path, v, _default(f)))
    return out


def _excluded(path: str, technique: str) -> bool:
    skip = {**NOT_READ["*"], **NOT_READ[technique]}
    return any(path == p or path.startswith(p + ".") for p in skip)


def read_fields(technique: str) -> dict:
    """The leaf fields technique ``technique`` reads (module docstring): ``{path: choices}``."""
    own = f"techniques.{technique}."
    return {p: choices for p, (_, choices) in _leaves(Scene).items()
            if (not p.startswith("techniques.") or p.startswith(own)) and not _excluded(p, technique)}


def uncovered(technique: str, scenes) -> list[str]:
    """Fields ``technique`` reads with no non-default value in ``scenes`` (and laws with a choice never used)."""
    seen: dict[str, set] = {}
    for scene in scenes:
        for path, value, default in _values(scene):
            if path.startswith("techniques.") and not path.startswith(f"techniques.{technique}."):
                continue
            if path in EVERY_CHOICE or default is dataclasses.MISSING or default is None or value != default:
                seen.setdefault(path, set()).add(value if not isinstance(value, (list, dict)) else repr(value))
    missing = []
    for path, choices in read_fields(technique).items():
        if path not in seen:
            missing.append(path)
        elif path in EVERY_CHOICE and choices and set(choices) - seen[path]:
            missing.append(f"{path} = {sorted(set(choices) - seen[path])}")
    return missing


def _eye_forward(scene):
    cam = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
    return np.asarray(cam.position, float), np.asarray(cam.forward, float)


def _in_volume(light, x) -> bool:
    """``x`` inside a point/spot light's volume (ball of radius ``range``, cone of full angle ``spot_angle``)."""
    w = np.asarray(x, float) - np.asarray(light.position, float)
    if light.type == "directional" or np.linalg.norm(w) >= light.range:
        return light.type == "directional"
    if light.type == "point":
        return True
    axis = np.asarray(light.direction, float) / np.linalg.norm(light.direction)
    return w @ axis >= np.cos(np.radians(light.spot_angle) / 2) * np.linalg.norm(w)


def _behind_camera(scene) -> bool:
    eye, fwd = _eye_forward(scene)
    return any(li.type != "directional" and (np.asarray(li.position) - eye) @ fwd < 0 for li in scene.lights)


def _camera_inside(scene) -> bool:
    return any(li.type != "directional" and _in_volume(li, _eye_forward(scene)[0]) for li in scene.lights)


def _max_distance_inside(scene) -> bool:
    eye, fwd = _eye_forward(scene)
    end = eye + scene.render.max_distance * fwd
    return any(li.type != "directional" and _in_volume(li, end) for li in scene.lights)


SITUATIONS = {
    "an odd frame size": lambda s: s.render.width % 2 == 1 or s.render.height % 2 == 1,
    "a width not a multiple of 8": lambda s: s.render.width % 8 != 0,
    "sigma_s = 0": lambda s: s.medium.scattering == 0.0,
    "g near +1 (> 0.9)": lambda s: s.medium.anisotropy > 0.9,
    "g near -1 (< -0.85)": lambda s: s.medium.anisotropy < -0.85,
    "a point or spot light behind the camera": _behind_camera,
    "the camera inside a light volume": _camera_inside,
    "render.max_distance ending inside a light volume": _max_distance_inside,
    "light colour x intensity beyond fp16 (65504)": lambda s: any(max(li.color) * li.intensity > 65504.0
                                                                  for li in s.lights),
    "a directional light with more than one cascade": lambda s: any(
        li.type == "directional" and li.shadows is not None and li.shadows.cascades > 1 for li in s.lights),
}
"""Situations a port must meet that no single field value expresses; each holds in some killzone scene."""


def missing_situations(scenes) -> list[str]:
    return [name for name, holds in SITUATIONS.items()
            if not any(holds(s) for s in scenes if s.render.technique == "killzone")]


def suite_scenes(exclude=()):
    return [load_scene(str(p)) for p in sorted(SUITE.glob("*.toml")) if p.stem not in exclude]


@pytest.fixture(scope="module")
def suite():
    return suite_scenes()


def test_the_schema_walk_sees_every_law_and_shape():
    leaves = _leaves(Scene)
    assert set(leaves["objects.shape"][1]) == set(SHAPES)
    for path in EVERY_CHOICE:
        assert leaves[path][1], path
    assert {"techniques.killzone.blur_sigma", "lights.shadows.strength", "lights.shadows.slope_bias",
            "objects.material.albedo", "objects.box.rotation", "medium.noise.scale"} <= set(leaves)


@pytest.mark.parametrize("technique", list(TECHNIQUES))
def test_every_field_the_technique_reads_has_a_non_default_value_in_the_suite(technique, suite):
    assert uncovered(technique, suite) == []


def test_every_situation_is_reached_by_a_killzone_scene(suite):
    assert missing_situations(suite) == []


KILLZONE_SCENES = ["laws", "inside_volume", "bright_behind", "no_scattering", "back_scatter", "directional_fog",
                   "killzone_params", "killzone_unblurred"]


def test_the_killzone_scenes_are_the_suite_s_killzone_scenes(suite):
    assert sorted(Path(s.source).stem for s in suite if s.render.technique == "killzone") == sorted(KILLZONE_SCENES)


@pytest.mark.parametrize("removed", KILLZONE_SCENES)
def test_the_coverage_check_fails_when_a_killzone_scene_is_removed(removed):
    """Every killzone scene of the suite reaches something no other scene does: without it the check fails."""
    scenes = suite_scenes(exclude=(removed,))
    assert uncovered("killzone", scenes) + missing_situations(scenes) != []


def _changed(scene, path: str):
    """``scene`` with the field at ``path`` (render.* only) set to another valid value."""
    section, name = path.split(".")
    old = getattr(getattr(scene, section), name)
    new = {"frame": 5, "precision": "float32", "seed": 11, "sampling": "bayer2", "steps": 7,
           "resolution": "quarter"}[name]
    assert new != old
    return scene.replace(**{section: dataclasses.replace(getattr(scene, section), **{name: new})})


PROBES = {"physical": "physical", "killzone": "laws", "slightlymad": "slightlymad_source", "urp": "urp",
          "radial": "radial_gpugems", "froxel": "froxel"}


@pytest.mark.parametrize("technique,path", [(t, p) for t, d in NOT_READ.items() if t != "*" for p in d])
def test_not_read_fields_do_not_change_the_render(technique, path):
    scene = load_scene(str(SUITE / f"{PROBES[technique]}.toml"),
                       ["render.width=24", "render.height=14", f'render.technique="{technique}"'])
    a = render(scene).buffers
    b = render(_changed(scene, path)).buffers
    for name in a:
        if isinstance(a[name], np.ndarray):
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"{technique} reads {path}: buffer {name}")
