"""Peak memory of a render, estimated from the scene before anything is allocated.

``estimate(scene)`` = frame buffers + shadow maps + process:

* frame buffers: ``width * height * B_t`` bytes, ``B_t`` the peak bytes per pixel of technique ``t``
  (G-buffer, ray directions, scene colour, the technique's pass buffers, the outputs, float64): its
  registry entry's ``bytes_per_pixel`` (:data:`vlref.techniques.TECHNIQUES`);
* shadow maps: every shadowed light's faces (spot 1, point 6, directional ``cascades``) of
  ``resolution^2`` texels at ``SHADOW_BYTES_PER_TEXEL[type]`` each (the float32 map; the texels' rays are
  made inside the casting kernel, a chunk at a time);
* ``PROCESS_BYTES``: the interpreter, NumPy, Numba and the compiled kernels.

``B_t`` and the per-texel sizes are tracemalloc peaks of ``render(scene, stages=True)`` on the bundled
scenes (pillars, forest, cage; 320x180 and 640x360; shadow maps 256^2 and 512^2), rounded up;
``tests/test_memory.py`` holds the estimate to a factor of 1.5 of a measured peak.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Sequence

from .errors import InputError
from .scene.load import parse_override
from .techniques import TECHNIQUES

__all__ = ["MemoryEstimate", "estimate", "available_bytes", "check_memory"]

SHADOW_BYTES_PER_TEXEL = {"spot": 5, "point": 7, "directional": 5}
"""Peak bytes per shadow-map texel by light type (measured 4.0, 6.8, 4.9 at 512^2 with the rays cast in the
kernel, chunk by chunk)."""
PROCESS_BYTES = 300e6
GB = 1e9


@dataclass(frozen=True)
class MemoryEstimate:
    """Bytes of the frame buffers, of the shadow maps and of the process; ``largest``: the scene key of the
    biggest part (``render.width`` or ``lights[i].shadows.resolution``)."""

    frame: float
    shadows: float
    process: float
    largest: str

    @property
    def total(self) -> float:
        return self.frame + self.shadows + self.process


def _faces(light) -> int:
    return {"spot": 1, "point": 6}.get(light.type, light.shadows.cascades)


def estimate(scene) -> MemoryEstimate:
    """The peak memory of ``render(scene)`` (module docstring), in bytes."""
    r = scene.render
    frame = float(r.width) * r.height * TECHNIQUES[r.technique].bytes_per_pixel
    maps = [(i, float(_faces(l)) * l.shadows.resolution ** 2 * SHADOW_BYTES_PER_TEXEL[l.type])
            for i, l in enumerate(scene.lights) if l.shadows is not None and l.shadows.enabled]
    shadows = sum(b for _, b in maps)
    largest = "render.width"
    if maps:
        i, size = max(maps, key=lambda m: m[1])
        if size > frame:
            largest = f"lights[{i}].shadows.resolution"
    return MemoryEstimate(frame, shadows, PROCESS_BYTES, largest)


def _read_number(path: str) -> float | None:
    try:
        with open(path, encoding="ascii") as fh:
            text = fh.read().split()[0]
        return None if text == "max" else float(text)
    except (OSError, ValueError, IndexError):
        return None


def available_bytes() -> float | None:
    """Memory a new allocation can get: the smallest of ``MemAvailable`` (``/proc/meminfo``; elsewhere the
    free physical pages of ``sysconf``), the cgroup v2 headroom ``memory.max - memory.current`` and the
    address-space limit ``RLIMIT_AS`` (``ulimit -v``); None when none is known (no check)."""
    limits = []
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            limits += [float(line.split()[1]) * 1024.0 for line in fh if line.startswith("MemAvailable:")]
    except OSError:
        pass
    if not limits:
        try:
            limits.append(float(os.sysconf("SC_AVPHYS_PAGES")) * float(os.sysconf("SC_PAGE_SIZE")))
        except (AttributeError, OSError, ValueError):
            pass
    cg_max, cg_now = _read_number("/sys/fs/cgroup/memory.max"), _read_number("/sys/fs/cgroup/memory.current")
    if cg_max is not None and cg_now is not None:
        limits.append(max(cg_max - cg_now, 0.0))
    try:
        import resource
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            limits.append(float(soft))
    except (ImportError, OSError, ValueError):
        pass
    return min(limits) if limits else None


def _set_on_command_line(largest: str, overrides: Sequence[str]) -> str | None:
    """The ``--set`` item of ``overrides`` that sets what the estimate's ``largest`` part grows with (the image
    size for ``render.width``, that light's map resolution for ``lights[i].shadows.resolution``), or None."""
    causes = ({"render.width", "render.height"} if largest == "render.width"
              else {largest.replace("[", ".").replace("]", "")})
    for item in reversed(overrides):  # the last one wins, as when the scene is loaded
        if ".".join(map(str, parse_override(item)[0])) in causes:
            return item
    return None


def check_memory(scene, available: float | None = None, overrides: Sequence[str] = ()) -> MemoryEstimate:
    """Raise :class:`InputError` ``(scene file, largest part, "needs about N GB, M GB available")`` when the
    estimate exceeds the available memory (``available``, default :func:`available_bytes`). When one of the
    ``--set`` ``overrides`` set that part, the error names it: ``("<command line>", "--set KEY=VALUE", ...)``."""
    est = estimate(scene)
    available = available_bytes() if available is None else available
    if available is not None and est.total > available:
        item = _set_on_command_line(est.largest, overrides)
        file, key = ("<command line>", f"--set {item}") if item else (scene.source or "<scene>", est.largest)
        raise InputError(file, key, f"needs about {est.total / GB:.1f} GB, {available / GB:.1f} GB available "
                         "(--ignore-memory-check renders anyway)")
    return est
