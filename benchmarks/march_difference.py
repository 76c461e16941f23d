"""How far a change of the march moves its buffers (BENCHMARKS.md, "The march: fewer divisions per sample, measured,
not adopted"): the physical march's ``per_light`` and ``transmittance`` of every bundled scene and the bench scenes
(a) one spot and (b) four lights, in the variants of ``march_hashes.py`` ({pcf, hard maps} x {float64, float32} x
{light leg on, off}), stored by one tree and compared by the other: per precision, the largest relative difference
``|new - old| / |old|`` over the elements (the march's sums are of non-negative terms: no cancellation), and the
elements where exactly one side is 0.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-old python3 benchmarks/march_difference.py save before.npz  # old tree
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-new python3 benchmarks/march_difference.py compare before.npz
"""

import sys

import numpy as np

from march_hashes import SIZE, buffers
from vlref.bench.config import bench_scene
from vlref.scene.bundled import bundled_scenes
from vlref.scene.load import load_scene


def all_buffers() -> dict:
    scenes = {"bench_one": bench_scene(48, 27, 16, "one", 256), "bench_four": bench_scene(48, 27, 16, "four", 256)}
    scenes.update({name: load_scene(name, SIZE) for name in sorted(bundled_scenes())})
    return {f"{name}/{key}": array for name, scene in scenes.items() for key, array in buffers(scene).items()}


def compare(before: dict, after: dict) -> None:
    worst = {}
    for key in sorted(before):
        old, new = np.asarray(before[key], np.float64), np.asarray(after[key], np.float64)
        precision = key.split("/")[1].split(".")[1]
        nonzero = old != 0.0
        rel = np.abs(new[nonzero] - old[nonzero]) / np.abs(old[nonzero])
        top = float(rel.max()) if rel.size else 0.0
        one_side = int(np.count_nonzero((old == 0.0) != (new == 0.0)))
        finite = bool(np.isfinite(new).all())
        print(f"{key}: max rel {top:.3e}, one side 0: {one_side}, finite: {finite}")
        w = worst.setdefault(precision, [0.0, 0, "", True])
        if top > w[0]:
            w[0], w[2] = top, key
        w[1] += one_side
        w[3] = w[3] and finite
    for precision, (top, one_side, key, finite) in sorted(worst.items()):
        print(f"{precision}: max relative difference {top:.3e} ({key}), elements 0 on one side only: {one_side}, "
              f"all finite: {finite}")


if __name__ == "__main__":
    if sys.argv[1] == "save":
        np.savez(sys.argv[2], **all_buffers())
    else:
        compare(dict(np.load(sys.argv[2])), all_buffers())
