"""The `vlref` command end to end: outputs, exit codes, and nothing written on bad input."""

import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest

from vlref import __version__
from vlref.cli import main
from vlref.cli import render as render_cli
from vlref.io.exr import read_exr
from vlref.io.images import read_image
from vlref.io.png import png_text
from vlref.io.tonemap import srgb8
from vlref.reference import render_reference
from vlref.scene.load import load_scene

SMALL = ["--set", "render.width=48", "--set", "render.height=27", "--set", "render.steps=8"]


def test_version(capsys):
    assert main(["--version"]) == 0
    assert __version__ in capsys.readouterr().out


def test_scenes_lists_every_bundled_scene_with_a_description(capsys):
    assert main(["scenes"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) >= 10
    assert all(len(line.split(None, 1)) == 2 for line in lines)


def test_render_default_scene_writes_final_png_and_depth(tmp_path):
    out = tmp_path / "out"
    assert main(["render", "-o", str(out), "-q", *SMALL]) == 0
    for name in ("final.exr", "final.png", "depth.exr", "inscatter.exr", "transmittance.exr"):
        assert (out / name).is_file(), name
    channels, meta = read_exr(out / "final.exr")
    assert set(channels) == {"R", "G", "B"}
    assert meta["vlref_version"] == __version__ and len(meta["scene_hash"]) == 64
    final = read_image(out / "final.exr")
    assert final.shape == (27, 48, 3) and np.isfinite(final).all() and final.max() > 0
    depth = read_image(out / "depth.exr")[..., 0]
    assert depth.shape == (27, 48) and (depth > 0).all()


def test_render_is_deterministic(tmp_path):
    for d in ("a", "b"):
        assert main(["render", "pillars", "-o", str(tmp_path / d), "-q", *SMALL]) == 0
    a = (tmp_path / "a" / "final.exr").read_bytes()
    b = (tmp_path / "b" / "final.exr").read_bytes()
    assert a == b


def test_render_preview_is_the_exposed_final_and_a_failed_preview_leaves_nothing(tmp_path, monkeypatch):
    # the preview (exposure and PNG) is written on a thread beside the EXR files: its codes are srgb8 of the final
    # buffer at the exposure its tEXt records, and when it fails the output folder is not even created
    out = tmp_path / "out"
    assert main(["render", "pillars", "-o", str(out), "-q", *SMALL]) == 0
    data = (out / "final.png").read_bytes()
    exposure = float(png_text(data)["vlref_exposure"])
    want = srgb8(read_image(out / "final.exr").astype(np.float64), exposure)
    assert np.abs(iio.imread(data, extension=".png").astype(int) - want).max() <= 1  # the EXR holds float32

    def broken(*args):
        raise OSError("disk full")
    monkeypatch.setattr(render_cli, "write_png", broken)
    with pytest.raises(OSError, match="disk full"):
        main(["render", "pillars", "-o", str(tmp_path / "failed"), "-q", *SMALL])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no folder, no .failed.*.partial


def test_half_float_stores_the_light_buffers_as_half(tmp_path):
    assert main(["render", "pillars", "-o", str(tmp_path / "f"), "-q", *SMALL]) == 0
    assert main(["render", "pillars", "-o", str(tmp_path / "h"), "-q", "--half-float", *SMALL]) == 0
    for name in ("final", "inscatter", "transmittance"):
        full = read_image(tmp_path / "f" / f"{name}.exr")
        assert np.array_equal(read_image(tmp_path / "h" / f"{name}.exr"), full.astype(np.float16).astype(np.float32))
    assert (tmp_path / "h" / "depth.exr").read_bytes() == (tmp_path / "f" / "depth.exr").read_bytes()


def test_stages_write_shadow_maps_and_pass_buffers(tmp_path):
    out = tmp_path / "s"
    assert main(["render", "pillars", "-o", str(out), "-q", "--stages", *SMALL]) == 0
    names = {p.name for p in out.iterdir()}
    assert any(n.startswith("shadow_") for n in names), names
    assert "scene_colour.exr" in names


@pytest.mark.parametrize("args, needle", [
    (["render", "no_such_scene"], "no_such_scene"),
    (["render", "pillars", "--set", "lights.0.spot_angel=30"],
     "<command line>: --set lights.0.spot_angel=30: unknown key, did you mean spot_angle?"),
    (["render", "pillars", "--set", "medium.anisotropy=1.5"], "--set medium.anisotropy=1.5: must be < 1.0"),
    (["render", "pillars", "--set", "render.width=0"], "--set render.width=0: must be >= 1"),
    (["render", "pillars", "--set", "lights.0.direction=[0,0,0]"], "--set lights.0.direction=[0,0,0]: zero-length"),
    (["render", "pillars", "--set", "lights.7.range=1"], "lights[7]"),
    (["render", "pillars", "--technique", "raytraced"], 'render.technique="raytraced": must be one of'),
])
def test_bad_input_exits_2_names_file_key_reason_and_writes_nothing(tmp_path, capsys, args, needle):
    out = tmp_path / "o"
    assert main([*args, "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert needle in err
    assert not out.exists()


def test_bad_scene_file_names_the_file(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[[lights]]\ntype = 'point'\nrange = -2\n")
    assert main(["render", str(bad), "-o", str(tmp_path / "o"), "-q"]) == 2
    assert f"{bad}: lights[0].range: must be > 0.0" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_console_script_entry_point_runs():
    r = subprocess.run([sys.executable, "-m", "vlref", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and __version__ in r.stdout


def test_reference_writes_reference_and_error_and_reports_the_largest_estimate(tmp_path, capsys):
    out = tmp_path / "ref"
    assert main(["reference", "pillars", "-o", str(out), "--set", "render.width=12", "--set", "render.height=8",
                 "--rel-tol", "1e-3", "--shadow-samples", "64"]) == 0
    assert "largest error estimate" in capsys.readouterr().out
    ref = read_image(out / "reference.exr")
    err = read_image(out / "error.exr")[..., 0]
    assert ref.shape == (8, 12, 3) and np.isfinite(ref).all()
    assert (err >= 0).all() and np.isfinite(err).all()


def test_reference_refuses_an_empty_shadow_grid(tmp_path, capsys):
    assert main(["reference", "pillars", "-o", str(tmp_path / "ref"), "--shadow-samples", "0"]) == 2
    assert "--shadow-samples: must be at least 1, not 0" in capsys.readouterr().err
    assert not (tmp_path / "ref").exists()


@pytest.mark.parametrize("rule", [7, 3])
def test_reference_solves_with_the_rule_asked_for_and_records_it(tmp_path, rule):
    out = tmp_path / "ref"
    assert main(["reference", "pillars", "-o", str(out), "--set", "render.width=12", "--set", "render.height=8",
                 "--rel-tol", "1e-1", "--shadow-samples", "8", "--rule", str(rule)]) == 0
    _, meta = read_exr(out / "inscatter.exr")
    assert meta["rule"] == str(rule) and meta["shadow_samples"] == "8"
    scene = load_scene("pillars", ["render.width=12", "render.height=8"])
    written = read_image(out / "inscatter.exr")
    coarse, fine = (render_reference(scene, rel_tol=1e-1, shadow_samples=8, rule=r).inscatter for r in (rule, 15))
    assert np.array_equal(written, coarse.astype(written.dtype))
    assert not np.array_equal(written, fine.astype(written.dtype))


def test_reference_refuses_an_unknown_kronrod_rule(tmp_path, capsys):
    assert main(["reference", "pillars", "-o", str(tmp_path / "ref"), "--rule", "5"]) == 2
    assert "--rule: invalid choice: 5" in capsys.readouterr().err
    assert not (tmp_path / "ref").exists()


def test_bias_reports_error_against_steps(tmp_path, capsys):
    out = tmp_path / "bias"
    assert main(["bias", "pillars", "--technique", "physical", "--steps", "4,16", "-o", str(out),
                 "--set", "render.width=12", "--set", "render.height=8"]) == 0
    text = capsys.readouterr().out
    assert "log-log slope" in text and "technique physical" in text
    assert (out / "bias.json").is_file() and (out / "bias_error.exr").is_file()
