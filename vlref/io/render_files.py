"""A render's files: one EXR per buffer (with the render's metadata) and the ``final.png`` preview."""

from __future__ import annotations

import concurrent.futures
import re
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ..processes import host_cores
from .exr import channel_dict, checked_channels, write_exr
from .png import write_png

__all__ = ["save_buffers", "save_render"]

_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


def save_buffers(out_dir, buffers: Mapping[str, np.ndarray], metadata: Mapping[str, object] | None = None,
                 half: Sequence[str] = ()) -> list[Path]:
    """Write ``<name>.exr`` for each buffer into the existing folder ``out_dir``; returns the paths in the order
    of ``buffers``.

    Every buffer is validated (name, shape, dtype) before the first file is written, and each file is
    written atomically; wrap the call in :func:`vlref.io.output_folders.output_dir` for an all-or-nothing set.
    The buffers named in ``half`` are stored as half floats (:func:`vlref.io.exr.write_exr`). The float32
    channels of all buffers are made on a thread per buffer (NumPy's casts release the GIL) while the files are
    written one after another, each as soon as its channels are made (each compressed on OpenEXR's thread pool): the
    first file's compression no longer waits for the other buffers' channels.
    """
    out_dir = Path(out_dir)
    for name, array in buffers.items():
        if not _SAFE_NAME.match(name):
            raise ValueError(f"buffer name {name!r} is not a safe file name")
        if name in half and np.asarray(array).dtype.kind != "f":
            raise ValueError(f"buffer {name!r}: integer buffers stay float32 (half asked)")
    checked = [checked_channels(array, None) for array in buffers.values()]
    with concurrent.futures.ThreadPoolExecutor(max(1, min(len(buffers), host_cores()))) as pool:
        channels = pool.map(lambda data: channel_dict(data, None), checked)  # in order, as each is made
        return [write_exr(out_dir / f"{name}.exr", data, metadata=metadata, half=name in half)
                for name, data in zip(buffers, channels)]


def save_render(out_dir, result, stages: bool, main: Sequence[str], exposure: float = 1.0,
                png_meta: Mapping[str, str] | None = None, half: Sequence[str] = (), preview: bool = True) -> list[Path]:
    """Write a :class:`vlref.render.RenderResult`: the ``main`` buffers (all with ``stages``) as EXR
    with the result's metadata (those in ``half`` as half floats), plus (``preview``) the ``final.png`` preview at
    ``exposure`` (``png_meta``: its tEXt). The preview is encoded on a second thread while the EXR files are
    written (zlib and OpenEXR release the GIL; the EXR files on a thread each as well measured no faster on the
    device: BENCHMARKS.md, "The frame around the kernels")."""
    names = list(result.buffers) if stages else [n for n in main if n in result.buffers]
    buffers = {n: result.buffers[n] for n in names}
    if not preview:
        return save_buffers(out_dir, buffers, result.metadata, half)
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        png = pool.submit(write_png, Path(out_dir) / "final.png", result.buffers["final"], exposure, png_meta)
        paths = save_buffers(out_dir, buffers, result.metadata, half)
        paths.append(png.result())
    return paths
