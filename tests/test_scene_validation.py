"""Scene files: every validation rule gives `FILE: key.path: reason`, and overrides reach any field."""

import json

import pytest

from vlref.errors import InputError
from vlref.scene import bundled_scenes, load_scene

MINIMAL = """
[[lights]]
type = "point"
position = [0, 2, 0]
"""


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def error_of(tmp_path, text, overrides=(), name="scene.toml"):
    p = write(tmp_path, text, name)
    with pytest.raises(InputError) as info:
        load_scene(p, overrides)
    return p, str(info.value)


def test_minimal_scene_gets_documented_defaults(tmp_path):
    s = load_scene(write(tmp_path, MINIMAL))
    assert s.render.width == 640 and s.render.height == 360
    assert s.render.technique == "physical"
    assert s.camera.fov == 60.0
    assert s.lights[0].type == "point" and s.lights[0].range == 10.0
    assert s.medium.extinction == s.medium.scattering + s.medium.absorption


def test_json_is_accepted_and_equals_toml(tmp_path):
    data = {"lights": [{"type": "spot", "position": [0, 5, 0], "spot_angle": 40}],
            "medium": {"scattering": 0.1}}
    js = load_scene(write(tmp_path, json.dumps(data), "s.json"))
    toml = load_scene(write(tmp_path, MINIMAL.replace('"point"', '"spot"').replace("[0, 2, 0]", "[0, 5, 0]")
                            + "spot_angle = 40\n[medium]\nscattering = 0.1\n", "s.toml"))
    assert js.lights == toml.lights and js.medium == toml.medium


@pytest.mark.parametrize("text, path, reason", [
    (MINIMAL + "spot_angel = 30\n", "lights[0].spot_angel", "did you mean spot_angle?"),
    ("[render]\nwidht = 3\n" + MINIMAL, "render.widht", "did you mean width?"),
    ("[medium]\nscattering = -0.1\n" + MINIMAL, "medium.scattering", "must be >= 0.0"),
    ("[medium]\nabsorption = -1\n" + MINIMAL, "medium.absorption", "must be >= 0.0"),
    ("[medium]\nanisotropy = 1.0\n" + MINIMAL, "medium.anisotropy", "must be < 1.0"),
    ("[medium]\nanisotropy = -1.0\n" + MINIMAL, "medium.anisotropy", "must be > -1.0"),
    ("[camera]\nfov = 0\n" + MINIMAL, "camera.fov", "must be > 0.0"),
    ("[camera]\nfov = 180\n" + MINIMAL, "camera.fov", "must be < 180.0"),
    ("[camera]\nnear = 5.0\nfar = 1.0\n" + MINIMAL, "camera.far", "must be greater than near"),
    ("[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 0]\n" + MINIMAL, "camera.look_at", "zero-length"),
    (MINIMAL + "direction = [0, 0, 0]\n", "lights[0].direction", "zero-length vector"),
    (MINIMAL + "range = 0\n", "lights[0].range", "must be > 0.0"),
    (MINIMAL + "intensity = \"bright\"\n", "lights[0].intensity", "expected a number, got a string"),
    (MINIMAL + "color = [1, 1]\n", "lights[0].color", "expected a list of 3 numbers"),
    (MINIMAL + "attenuation = \"quadratic\"\n", "lights[0].attenuation", "must be one of"),
    ("[render]\nwidth = 2.5\n" + MINIMAL, "render.width", "expected an integer"),
    ("[render]\nsampling = \"bayer16\"\n" + MINIMAL, "render.sampling", "must be one of"),
    ('[[lights]]\ntype = "spot"\nspot_angle = 180\n', "lights[0].spot_angle", "must be < 180.0"),
    (MINIMAL + '[[objects]]\nshape = "mesh"\npath = "nope.obj"\n', "objects[0].path", "file not found"),
    (MINIMAL + '[[objects]]\nshape = "cube"\n', "objects[0].shape", "must be one of"),
    (MINIMAL + '[[objects]]\nshape = "sphere"\nradius = -1\n', "objects[0].radius", "must be > 0.0"),
    (MINIMAL + '[[objects]]\nshape = "box"\nmaterial = { opacity = 2 }\n', "objects[0].material.opacity",
     "must be <= 1.0"),
    ("[medium.bounds]\nmin = [0, 0, 0]\nmax = [1, 0, 1]\n" + MINIMAL, "medium.bounds.max", "must exceed min"),
    ("[render]\n", "lights", "at least one light"),
    ("[[lights]]\nposition = [0, 1, 0]\n", "lights[0].type", "missing required key"),
    (MINIMAL + "[techniques.slightlymad]\nmie_g = 1.5\n", "techniques.slightlymad.mie_g", "must be < 1.0"),
])
def test_each_rule_names_file_key_and_reason(tmp_path, text, path, reason):
    p, msg = error_of(tmp_path, text)
    assert msg.startswith(f"{p}: {path}: "), msg
    assert reason in msg


def test_invalid_toml_names_the_file(tmp_path):
    p, msg = error_of(tmp_path, "[render\nwidth = 3")
    assert msg.startswith(f"{p}: ") and "invalid TOML" in msg


def test_overrides_reach_any_field(tmp_path):
    s = load_scene(write(tmp_path, MINIMAL), ["render.width=320", "lights.0.intensity=20",
                                               'render.technique="killzone"', "medium.height_fog.falloff=0.5",
                                               "camera.position=[1, 2, 3]", "render.sampling=bayer4"])
    assert s.render.width == 320 and s.lights[0].intensity == 20.0 and s.render.technique == "killzone"
    assert s.medium.height_fog.falloff == 0.5 and s.camera.position == (1.0, 2.0, 3.0)
    assert s.render.sampling == "bayer4"


@pytest.mark.parametrize("override, path", [
    ("lights.3.range=2", "lights[3]"),
    ("render.width", "--set render.width"),
    ("render.width=-3", "--set render.width=-3"),
])
def test_bad_overrides_are_reported(tmp_path, override, path):
    _, msg = error_of(tmp_path, MINIMAL, [override])
    assert f": {path}" in msg


def test_paths_are_relative_to_the_scene_file(tmp_path):
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    s = load_scene(write(sub, MINIMAL + '[[objects]]\nshape = "mesh"\npath = "m.obj"\n'))
    assert s.objects[0].path == str((sub / "m.obj").resolve())


def test_every_bundled_scene_loads_and_describes_itself():
    scenes = bundled_scenes()
    assert len(scenes) >= 10
    for name, path in scenes.items():
        s = load_scene(name)
        assert s.description, name
        assert s.lights, name


def test_unknown_bundled_name_lists_the_bundled_scenes():
    with pytest.raises(InputError, match="pillars"):
        load_scene("no_such_scene")


def test_urp_scattering_is_a_deprecated_alias_of_minus_anisotropy(tmp_path):
    p = write(tmp_path, MINIMAL + "[techniques.urp]\nscattering = -0.5\n")
    with pytest.warns(DeprecationWarning, match=r"techniques\.urp\.scattering is deprecated: use "
                                                r"techniques\.urp\.anisotropy = 0\.5"):
        old = load_scene(p)
    assert old.techniques.urp.anisotropy == 0.5
    assert old == load_scene(write(tmp_path, MINIMAL + "[techniques.urp]\nanisotropy = 0.5\n", "new.toml")).replace(
        source=old.source)
    with pytest.warns(DeprecationWarning):
        assert load_scene(write(tmp_path, MINIMAL), ["techniques.urp.scattering=0.25"]).techniques.urp.anisotropy \
            == -0.25


@pytest.mark.parametrize("text, reason", [("scattering = 0.1\nanisotropy = 0.1", "give techniques.urp.anisotropy only"),
                                          ('scattering = "x"', "expected a number, got a string")])
def test_urp_scattering_alias_errors(tmp_path, text, reason):
    p, msg = error_of(tmp_path, MINIMAL + "[techniques.urp]\n" + text + "\n")
    assert msg.startswith(f"{p}: techniques.urp.scattering: ") and reason in msg
