"""Make the pictures of docs/TECHNIQUES.md "Faithful artifacts": ``python docs/faithful_artifacts.py``.

Each picture is a 240x135 render of a bundled scene at the technique's defaults (shadow maps capped at
512^2), its preview PNG as ``vlref render`` writes it (auto exposure, ACES, sRGB), beside ``physical``'s
render of the same scene at the same exposure, written to docs/img/<name>.png (about 20-40 KB each).
"""

from pathlib import Path

import numpy as np

from vlref.io.exposure import luminance, percentile_exposure
from vlref.io.files import write_bytes
from vlref.io.png import png_bytes
from vlref.io.tonemap import srgb8
from vlref.render import render
from vlref.scene import load_scene
from vlref.sheet import contact_sheet, labelled

SIZE = ["render.width=240", "render.height=135", "lights.0.shadows.resolution=512"]
PICTURES = {  # file name: (scene, technique)
    "artifacts_slightlymad": ("pillars", "slightlymad"),
    "artifacts_froxel": ("pillars", "froxel"),
    "artifacts_radial": ("pillars", "radial"),
}


def picture(scene_name: str, technique: str) -> np.ndarray:
    """The technique's final image beside physical's, labelled, each at its own preview exposure."""
    panels = []
    for name in (technique, "physical"):
        final = render(load_scene(scene_name, [*SIZE, f'render.technique="{name}"'])).buffers["final"]
        exposure, _ = percentile_exposure(luminance(final), 99.0)
        panels.append(labelled(srgb8(final, exposure), f"{scene_name} {name}"))
    return contact_sheet(panels, columns=2)


if __name__ == "__main__":
    out = Path(__file__).resolve().parent / "img"
    out.mkdir(exist_ok=True)
    for file, (scene_name, technique) in PICTURES.items():
        write_bytes(out / f"{file}.png", png_bytes(picture(scene_name, technique)))
        print(f"wrote {out / file}.png")
