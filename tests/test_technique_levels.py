"""Techniques side by side: every technique's default render of every bundled scene it
applies to has a usable PNG preview (automatic exposure), and its HDR level lies within 10x of
``physical`` on the same scene unless docs/TECHNIQUES.md states the ratio and the reason."""

import re
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from vlref.cli import main
from vlref.io.exposure import luminance
from vlref.io.images import read_image
from vlref.io.png import png_text
from vlref.scene import bundled_scenes, load_scene
from vlref.techniques import TECHNIQUES

DOCS = Path(__file__).resolve().parents[1] / "docs" / "TECHNIQUES.md"
SIZE = ["render.width=64", "render.height=36"]


def documented_levels() -> dict[tuple[str, str], tuple[float, str]]:
    """``(scene, technique) -> (ratio, reason)`` from the table under 'HDR level against `physical`'."""
    text = DOCS.read_text(encoding="utf-8").split("### HDR level against `physical`", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (\w+) \| (\w+) \| ([0-9.e+-]+) \| (.*?) \|$", text, flags=re.M)
    return {(scene, tech): (float(ratio), reason.strip()) for scene, tech, ratio, reason in rows}


def _level_and_png(tmp_path, name, technique, sets):
    out = tmp_path / technique
    assert main(["render", name, "--technique", technique, "-q", "-o", str(out), *sum((["--set", s] for s in sets), [])]) == 0
    final = read_image(out / "final.exr")
    level = float(np.percentile(luminance(final), 99.0))
    data = (out / "final.png").read_bytes()
    return level, iio.imread(data, extension=".png"), png_text(data)


@pytest.mark.parametrize("name", sorted(bundled_scenes()))
def test_previews_are_exposed_and_levels_match_physical_or_the_documented_reason(tmp_path, name):
    base = load_scene(name, SIZE)
    sets = SIZE + [f"lights.{i}.shadows.resolution=128" for i, l in enumerate(base.lights)
                   if l.shadows is not None and l.shadows.resolution > 128]
    documented = documented_levels()
    levels = {}
    for technique, entry in TECHNIQUES.items():
        if not entry.applies(base):
            continue
        level, png, text = _level_and_png(tmp_path, name, technique, sets)
        levels[technique] = level
        # the preview: exposure = 1 / level (p99 -> 1 -> ACES 0.80 -> sRGB code ~231), recorded in the PNG
        assert float(text["vlref_exposure"]) == pytest.approx(1.0 / level, rel=1e-5), technique
        assert "percentile 99" in text["vlref_exposure_rule"]
        y = luminance(png.astype(np.float64) / 255.0)
        assert 0.75 <= np.percentile(y, 99.0) <= 0.97, (technique, np.percentile(y, 99.0))
        assert (png == 255).all(axis=2).mean() <= 0.02, technique  # not washed out
    for technique, level in levels.items():
        ratio = level / levels["physical"]
        if (name, technique) in documented:
            stated, reason = documented[(name, technique)]
            assert reason and (stated > 10 or stated < 0.1)
            assert stated / 2 <= ratio <= stated * 2, (name, technique, ratio, stated)
        else:
            assert 0.1 <= ratio <= 10.0, f"{name}/{technique}: {ratio:.3g}x physical and no reason in {DOCS.name}"


def test_documented_table_is_not_empty_and_names_real_pairs():
    documented = documented_levels()
    assert len(documented) >= 5
    scenes = bundled_scenes()
    for scene, technique in documented:
        assert scene in scenes and technique in TECHNIQUES
