"""SHA-256 of the physical march's buffers, to show that a change of the march keeps the bits (BENCHMARKS.md, "The
march: bands in place, whole tiles, gathered depth reads").

Every bundled scene (16), the bench scene (b) (four PCF-shadowed lights) as it is, without its height fog and in a
bounded medium, and ``pillars`` in a bounded medium, at 48x27x16, each in the variants
{pcf, hard maps} x {float64, float32} x {light leg on, off}: :func:`vlref.techniques.physical.march_buffers`'s
``per_light`` and ``transmittance``, one digest each.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-old python3 benchmarks/march_hashes.py > before.json   # the old tree
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-new python3 benchmarks/march_hashes.py before.json     # exit 1 on a change
"""

import dataclasses
import hashlib
import itertools
import json
import sys
from pathlib import Path

import numpy as np

from vlref.bench.config import bench_scene
from vlref.render import prepare_frame
from vlref.scene.bundled import bundled_scenes
from vlref.scene.load import load_scene
from vlref.scene.model import Bounds
from vlref.scene.technique_params import resolved
from vlref.techniques.physical import march_buffers

SIZE = ("render.width=48", "render.height=27", "render.steps=16", "render.technique=physical")
VARIANTS = tuple(itertools.product(("pcf", "hard"), ("float64", "float32"), (True, False)))


def _digest(array: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()[:16]


def buffers(scene) -> dict:
    """``per_light`` and ``transmittance`` of ``scene`` in each variant, by key ``filter.precision.leg.buffer``."""
    out = {}
    for shadow_filter, precision, leg in VARIANTS:
        varied = dataclasses.replace(
            scene, render=dataclasses.replace(scene.render, precision=precision),
            techniques=dataclasses.replace(scene.techniques, physical=dataclasses.replace(
                scene.techniques.physical, light_extinction=leg)))
        frame = prepare_frame(varied)
        maps = frame.shadow_maps(shadow_filter)
        per_light, trans = march_buffers(frame.scene, frame.camera, frame.gbuffer.distance, frame.lights, maps,
                                         frame.geometry.arrays, resolved(frame.scene, "steps"),
                                         resolved(frame.scene, "sampling"))
        key = f"{shadow_filter}.{precision}.{'leg' if leg else 'noleg'}"
        out[f"{key}.per_light"], out[f"{key}.transmittance"] = per_light, trans
    return out


def hashes(scene) -> dict:
    """Digest of ``per_light`` and ``transmittance`` of ``scene`` in each variant."""
    return {key: _digest(array) for key, array in buffers(scene).items()}


def main() -> int:
    four = bench_scene(48, 27, 16, "four", 256)
    scenes = {"bench_four": four,
              # the light leg's branches for a homogeneous medium and a bounded one (with and without height fog)
              "bench_four_homogeneous": four.replace(medium=dataclasses.replace(four.medium, height_fog=None)),
              "bench_four_bounded": four.replace(medium=dataclasses.replace(
                  four.medium, bounds=Bounds(min=(-6.0, -1.0, -4.0), max=(6.0, 5.0, 6.0))))}
    pillars = load_scene("pillars", SIZE)
    scenes["pillars_bounded"] = pillars.replace(medium=dataclasses.replace(
        pillars.medium, bounds=Bounds(min=(-3.0, -1.0, -3.0), max=(3.0, 4.0, 3.0))))
    scenes.update({name: load_scene(name, SIZE) for name in sorted(bundled_scenes())})
    result = {name: hashes(scene) for name, scene in scenes.items()}
    if len(sys.argv) < 2:
        json.dump(result, sys.stdout, indent=1)
        return 0
    before = json.loads(Path(sys.argv[1]).read_text())
    # a buffer on either side only, or with another digest
    keys = {(s, k) for side in (before, result) for s in side for k in side[s]}
    changed = sorted(f"{s}: {k}" for s, k in keys if before.get(s, {}).get(k) != result.get(s, {}).get(k))
    print("\n".join(changed) or f"same bits: {len(keys)} buffers of {len(result)} scenes")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
