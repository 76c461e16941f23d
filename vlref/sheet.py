"""Techniques side by side: one exposure for all, each panel labelled with its level against physical.

``vlref render SCENE --technique all`` renders every technique whose ``applies`` rule accepts the scene
(:data:`vlref.techniques.TECHNIQUES`) and tone-maps every final image with the *same* exposure, the one
``physical``'s preview gets (``render.auto_exposure``), so that brightness differences between techniques
show (each ``final.png`` of a single render is auto-exposed on its own, which hides them).

The level of a technique is ``mean Y(inscatter) / mean Y(inscatter of physical)``, ``Y`` the Rec. 709
luminance (:func:`vlref.io.exposure.luminance`) averaged over the frame: how much more (or less) light the
technique scatters toward the camera than the physical single-scattering march of the same scene.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .io.exposure import luminance

__all__ = ["inscatter_level", "labelled", "contact_sheet"]

LABEL_HEIGHT = 14
"""Pixels of the label strip above each panel (PIL's default bitmap font is 11 px high)."""


def inscatter_level(inscatter: np.ndarray, physical_inscatter: np.ndarray) -> float:
    """``mean Y(inscatter) / mean Y(physical_inscatter)`` (module docstring); ``inf`` when physical is black
    and the technique is not, 1 when both are."""
    a, b = float(luminance(inscatter).mean()), float(luminance(physical_inscatter).mean())
    if b > 0.0:
        return a / b
    return 1.0 if a == 0.0 else float("inf")


def labelled(rgb8: np.ndarray, text: str) -> np.ndarray:
    """``rgb8`` (H, W, 3) uint8 under a black strip of :data:`LABEL_HEIGHT` rows with ``text`` in white
    (Pillow's default font; Pillow comes with imageio)."""
    from PIL import Image, ImageDraw

    h, w, _ = rgb8.shape
    strip = Image.new("RGB", (w, LABEL_HEIGHT))
    ImageDraw.Draw(strip).text((2, 1), text, fill=(255, 255, 255))
    return np.concatenate([np.asarray(strip, dtype=np.uint8), rgb8], axis=0)


def contact_sheet(panels: Sequence[np.ndarray], columns: int = 3, gap: int = 2) -> np.ndarray:
    """Panels of one size (H, W, 3) uint8 in rows of ``columns``, ``gap`` black pixels between them."""
    h, w, _ = panels[0].shape
    cols = min(columns, len(panels))
    rows = -(-len(panels) // cols)
    sheet = np.zeros((rows * h + (rows - 1) * gap, cols * w + (cols - 1) * gap, 3), dtype=np.uint8)
    for i, panel in enumerate(panels):
        r, c = divmod(i, cols)
        sheet[r * (h + gap):r * (h + gap) + h, c * (w + gap):c * (w + gap) + w] = panel
    return sheet
