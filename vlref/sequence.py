"""Frame sequences: render frames A..B-1 of a scene in order, chaining temporal history, and write them.

``vlref render SCENE --frames A:B`` writes, into the output folder,

* ``<buffer>.<frame:04d>.exr`` for every main buffer (all buffers with ``--stages``), each frame's
  render of :func:`vlref.render.render` with ``render.frame = frame`` (the animation evaluated there,
  :func:`vlref.scene.animation.scene_at`);
* ``final.<frame:04d>.png`` previews and ``preview.gif`` (Pillow, through imageio) at
  ``animation.fps`` (24 without an animation);
* ``preview.mp4`` when the optional ``imageio-ffmpeg`` is installed (``pip install vlref[video]``).

Temporal techniques (``froxel`` with ``temporal = true``) start a fresh history at frame ``A`` and pass
each frame's state to the next (:class:`vlref.froxel.temporal.History`).
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Callable, Iterator, Sequence

import numpy as np

from .errors import InputError
from .io.files import write_bytes
from .io.png import write_png
from .io.render_files import save_buffers
from .io.tonemap import srgb8
from .render import render

__all__ = ["parse_frames", "render_sequence", "write_sequence", "preview_gif", "write_mp4"]


def parse_frames(text: str, scene) -> range:
    """``"A:B"`` -> frames A .. B-1 (``"A:"``: up to ``animation.frames``; ``"A"``: frame A alone)."""
    where = ("<command line>", "--frames")
    try:
        if ":" in text:
            a, b = text.split(":", 1)
            start = int(a) if a.strip() else 0
            stop = int(b) if b.strip() else (scene.animation.frames if scene.animation is not None else None)
            if stop is None:
                raise InputError(*where, f"{text!r}: the scene has no [animation] to give the last frame; write A:B")
        else:
            start = int(text)
            stop = start + 1
    except ValueError:
        raise InputError(*where, f"expected A:B (frames A to B-1), got {text!r}") from None
    if start < 0 or stop <= start:
        raise InputError(*where, f"need 0 <= A < B, got {text!r}")
    return range(start, stop)


def render_sequence(scene, frames: Sequence[int], stages: bool = False,
                    progress: Callable[[str], None] | None = None) -> Iterator[tuple[int, object]]:
    """Yield ``(frame, RenderResult)`` for each frame in order, each frame given the previous one's history."""
    history = None
    for f in frames:
        s = scene.replace(render=dataclasses.replace(scene.render, frame=int(f)))
        result = render(s, stages=stages, progress=progress, history=history)
        history = result.history
        yield int(f), result


def preview_gif(images: Sequence[np.ndarray], fps: float) -> bytes:
    """An endlessly looping GIF of 8-bit sRGB frames (H, W, 3) at ``fps``."""
    import imageio.v3 as iio

    buf = io.BytesIO()
    iio.imwrite(buf, np.stack(images), extension=".gif", duration=1000.0 / fps, loop=0)
    return buf.getvalue()


def write_mp4(path: Path, images: Sequence[np.ndarray], fps: float) -> bool:
    """Write an H.264 MP4 when imageio-ffmpeg is installed; False (nothing written) when it is not."""
    try:
        import imageio_ffmpeg  # noqa: F401  (the optional `video` extra)
    except ImportError:
        return False
    import imageio.v2 as iio2

    # libx264 needs even sizes: pad by edge repetition to a multiple of 2 (no rescaling)
    h, w = images[0].shape[:2]
    padded = [np.pad(im, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") for im in images]
    iio2.mimwrite(str(path), padded, fps=fps, macro_block_size=1, format="FFMPEG")
    return True


def write_sequence(out_dir: Path, scene, frames: Sequence[int], stages: bool, main: Sequence[str],
                   progress: Callable[[str], None] | None = None, on_frame: Callable[[int], None] | None = None
                   ) -> list[Path]:
    """Render and write ``frames`` of ``scene`` into the existing folder ``out_dir`` (module docstring)."""
    fps = scene.animation.fps if scene.animation is not None else 24.0
    paths, previews = [], []
    for f, result in render_sequence(scene, frames, stages, progress):
        names = list(result.buffers) if stages else [n for n in main if n in result.buffers]
        paths += save_buffers(out_dir, {f"{n}.{f:04d}": result.buffers[n] for n in names}, result.metadata)
        paths.append(write_png(out_dir / f"final.{f:04d}.png", result.buffers["final"], exposure=scene.render.exposure))
        previews.append(srgb8(result.buffers["final"], scene.render.exposure))
        if on_frame is not None:
            on_frame(f)
    paths.append(write_bytes(out_dir / "preview.gif", preview_gif(previews, fps)))
    if write_mp4(out_dir / "preview.mp4", previews, fps):
        paths.append(out_dir / "preview.mp4")
    return paths
