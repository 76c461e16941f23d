"""The ``physical`` technique: the energy-conserving single-scattering march of docs/PHYSICS.md "The integral".

Buffers: ``inscatter`` (H, W, 3) = the sum of ``inscatter_light_<i>`` over lights (in light order),
``transmittance`` (H, W) = ``exp(-τ(0, t_end))``, ``final = scene_colour · transmittance + inscatter``
(sky pixels carry ``render.sky_color`` in the scene colour; view rays end at ``render.max_distance``).

Settings: ``render.steps`` and ``render.sampling`` (defaults ``techniques.physical``), the offsets of
:func:`vlref.march.patterns.offsets` with ``render.seed``; ``render.precision``;
``techniques.physical.light_extinction``. The march runs at the frame's full resolution (the
technique has no post passes, so ``render.resolution`` does not apply). With noise the light leg
uses ``ceil(sqrt(steps))`` midpoint sub-steps, whose O(1/steps) error matches the march's own order.

Performance: the march's outputs are new memory, which the operating system maps (and zeroes) on its first write, a
huge page of 2 MB at a time; the march takes its tiles in row order, so its threads all reached each page at once and
waited for its one mapping (1080p, one light: 6-10 ms more than into outputs already mapped, on the device). They are
mapped first, a block of rows per thread (:func:`vlref.row_blocks.in_row_blocks`, NumPy's fill without the GIL), with
the rays' ends ``min(distance, render.max_distance)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..march.patterns import offsets
from ..march.physical import march_physical, march_tiles
from ..medium import pack_medium
from ..post.composite import sum_and_composite
from ..progress import watched
from ..row_blocks import in_row_blocks
from ..scene.technique_params import resolved

__all__ = ["render", "march_buffers", "SAMPLES_WATCHED"]

# pixel × step × light samples per thread above which the march runs on a thread of its own, watched (a moving bar,
# Ctrl-C within a tile's time: vlref.progress.watched); below, ~0.04 s on a 16-core server and ~0.1 s on a busy
# 2-core box, it runs on the calling thread (a thread of its own cost 0.5-3.5 ms a launch on the busy dev box)
SAMPLES_WATCHED = 2_000_000


def march_buffers(scene, camera, gbuffer_distance, lights, shadow_maps, geo, steps: int, sampling: str):
    """Run the physical march on explicit inputs: ``(per_light (n,H,W,3), transmittance (H,W))``.

    ``gbuffer_distance`` (H, W) distance along each pixel ray (``inf`` = sky); ``lights`` a
    :class:`vlref.lights.PackedLights`, ``shadow_maps`` a :class:`vlref.lights.shadow_pack.ShadowMaps`.
    """
    dtype = np.float32 if scene.render.precision == "float32" else np.float64
    h, w = gbuffer_distance.shape
    dirs = camera.ray_directions(w, h, copy=False).astype(dtype, copy=False)  # read only
    beta = offsets(sampling, w, h, scene.render.seed).astype(dtype, copy=False)
    medium = pack_medium(scene, dtype)
    packed = lights.astype(dtype)
    t_end = np.empty((h, w), dtype=dtype)
    per_light = np.empty((packed.count, h, w, 3), dtype=dtype)  # the march writes every element
    trans = np.empty((h, w), dtype=dtype)

    def prepare(y0: int, y1: int) -> None:  # the rays' ends, and the outputs mapped first (module docstring)
        np.minimum(gbuffer_distance[y0:y1], scene.render.max_distance, out=t_end[y0:y1])
        per_light[:, y0:y1].fill(0)
        trans[y0:y1].fill(0)

    in_row_blocks(h, w, prepare)
    # The frame is marched in one launch, watched where it is long (SAMPLES_WATCHED)
    position = np.asarray(camera.position, dtype=dtype)
    # the geometry only where a light traces shadow rays: with None the march compiles without the ray tracer
    # (a second, smaller kernel; vlref.march.physical.march_physical)
    traced = geo if shadow_maps.traces_rays else None
    taken = np.zeros(1, dtype=np.int64)
    args = (position, dirs, t_end, beta, int(steps), medium, packed, shadow_maps.table, traced,
            bool(scene.techniques.physical.light_extinction), int(math.ceil(math.sqrt(steps))), per_light, trans,
            (np.int64(0), np.int64(h)), taken)
    threaded = h * w * int(steps) * packed.count > SAMPLES_WATCHED * numba.get_num_threads()
    watched(lambda: march_physical(*args), taken, march_tiles(w, h), h, threaded)
    return per_light, trans


def render(scene, frame) -> dict[str, np.ndarray]:
    """``inscatter``, ``transmittance``, ``final`` and ``inscatter_light_<i>`` (module docstring)."""
    per_light, trans = march_buffers(scene, frame.camera, frame.gbuffer.distance, frame.lights, frame.shadow_maps(),
                                     frame.geometry.arrays, resolved(scene, "steps"), resolved(scene, "sampling"))
    inscatter, final = sum_and_composite(per_light, frame.scene_colour, trans)
    out = {"inscatter": inscatter, "transmittance": trans, "final": final}
    out.update({f"inscatter_light_{k}": per_light[k] for k in range(per_light.shape[0])})
    return out
