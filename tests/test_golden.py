"""The golden suite: `pytest --update-goldens` rebuilds data/golden deliberately; without the flag the
whole suite is verified. Tampering, stale goldens and changed renders must fail (exit 1), bad input exit 2."""

import json
import shutil

import numpy as np
import pytest

from vlref.io.exr import write_exr
from vlref.io.images import read_image
from pathlib import Path

from vlref.cli import main
from vlref.oracle.golden import MANIFEST, load_suite, suite_entries
from vlref.scene import bundled_scenes, load_scene
from vlref.techniques.radial import light_in_frame

ONE = "pillars/physical"
GOLDEN_DIR = Path(__file__).resolve().parents[1] / "data" / "golden"  # the checkout's goldens, installed or not
DIR = ["--dir", str(GOLDEN_DIR)]


def test_golden_suite(request):
    if request.config.getoption("--update-goldens"):
        assert main(["golden", "build", "-q", *DIR]) == 0
    assert main(["golden", "verify", "-q", *DIR]) == 0
    size = sum(p.stat().st_size for p in GOLDEN_DIR.rglob("*") if p.is_file())
    assert size < 20e6


@pytest.fixture
def golden_copy(tmp_path):
    dst = tmp_path / "golden"
    shutil.copytree(GOLDEN_DIR, dst)
    return dst


def _record(golden_dir, name):
    manifest = json.loads((golden_dir / MANIFEST).read_text())
    return manifest, next(e for e in manifest["entries"] if e["name"] == name)


def test_tampered_file_fails_on_checksum(golden_copy, capsys):
    _, record = _record(golden_copy, ONE)
    path = golden_copy / record["files"]["final"]["path"]
    data = bytearray(path.read_bytes())
    data[-1] ^= 0x01
    path.write_bytes(bytes(data))
    assert main(["golden", "verify", "--dir", str(golden_copy), "--only", ONE]) == 1
    assert "checksum" in capsys.readouterr().out


def test_changed_render_fails_even_with_a_matching_checksum(golden_copy, capsys):
    """A golden edited consistently (manifest checksum updated) still fails: the re-render differs."""
    import hashlib

    manifest, record = _record(golden_copy, ONE)
    path = golden_copy / record["files"]["inscatter"]["path"]
    img = read_image(path)
    write_exr(path, img * np.float32(1.001))  # 0.1 %: 10x the float32 preset's relative tolerance
    record["files"]["inscatter"]["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (golden_copy / MANIFEST).write_text(json.dumps(manifest))
    assert main(["golden", "verify", "--dir", str(golden_copy), "--only", ONE]) == 1
    out = capsys.readouterr().out
    assert "inscatter: differs beyond preset float32" in out and "checksum" not in out


def test_stale_suite_and_scene_fail(golden_copy, tmp_path, capsys):
    suite = tmp_path / "suite.toml"
    from vlref.oracle.golden import SUITE_FILE
    suite.write_text(SUITE_FILE.read_text().replace("steps = 8", "steps = 9"))
    assert main(["golden", "verify", "--dir", str(golden_copy), "--suite", str(suite), "--only", ONE]) == 1
    assert "suite settings changed" in capsys.readouterr().out
    manifest, record = _record(golden_copy, ONE)
    record["scene_hash"] = "0" * 64
    (golden_copy / MANIFEST).write_text(json.dumps(manifest))
    assert main(["golden", "verify", "--dir", str(golden_copy), "--only", ONE]) == 1
    assert "scene changed" in capsys.readouterr().out


def test_bad_input_exits_2(tmp_path):
    assert main(["golden", "verify", "--dir", str(tmp_path)]) == 2  # no manifest
    (tmp_path / MANIFEST).write_text("{not json")
    assert main(["golden", "verify", "--dir", str(tmp_path)]) == 2
    assert main(["golden", "frobnicate"]) == 2


def test_build_only_one_entry_then_verify(tmp_path):
    assert main(["golden", "build", "-q", "--dir", str(tmp_path), "--only", ONE]) == 0
    manifest = json.loads((tmp_path / MANIFEST).read_text())
    assert [e["name"] for e in manifest["entries"]] == [ONE]
    assert main(["golden", "verify", "-q", "--dir", str(tmp_path), "--only", ONE]) == 0
    assert main(["golden", "verify", "-q", "--dir", str(tmp_path)]) == 1  # the other entries are missing


def test_applicability_rules():
    suite = load_suite()
    entries = {(e.scene, e.technique) for e in suite_entries(suite)}
    for name, path in bundled_scenes().items():
        scene = load_scene(path, [f"render.width={suite.width}", f"render.height={suite.height}"])
        if scene.animation is not None:  # animated scenes: physical and froxel at frames 0 and 3
            assert {t for s, t in entries if s == name} == {"physical", "froxel"}
            assert {e.name for e in suite_entries(suite) if e.scene == name} == {
                f"{name}@{f}/{t}" for f in (0, 3) for t in ("physical", "froxel")}
            continue
        for t in ("physical", "killzone", "slightlymad", "froxel"):
            assert (name, t) in entries
        has_sun = any(l.type == "directional" for l in scene.lights)
        assert ((name, "urp") in entries) == has_sun
        assert ((name, "radial") in entries) == light_in_frame(scene)
    # an independent check of the radial rule: the light's NDC lies inside [-1, 1]^2 in front of the camera
    from vlref.camera import camera_from_settings
    scene = load_scene("behind_camera")
    cam = camera_from_settings(scene.camera, 64, 36)
    view = cam.view_matrix() @ np.array([*scene.lights[0].position, 1.0])
    assert view[2] < 0 and not light_in_frame(scene)
    scene = load_scene("radial_sun")
    cam_ndc = camera_from_settings(scene.camera, 64, 36).world_to_ndc(
        np.asarray(scene.camera.position) - 1e6 * np.asarray(scene.lights[0].direction))
    assert np.all(np.abs(cam_ndc[:2]) <= 1) and light_in_frame(scene)
