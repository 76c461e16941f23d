"""The NumPy passes of a frame run in row blocks on threads (:mod:`vlref.row_blocks`) against their whole-frame
expressions, in one process (medians of 7 after a warm-up call), and the ray directions at other block sizes.
BENCHMARKS.md, "The stages around the kernels".

    PYTHONPATH=$PWD python3 benchmarks/row_blocks_sizes.py
"""

import json

import numpy as np

from vlref import row_blocks
from vlref.bench.config import bench_scene, median_time
from vlref.camera import camera_from_settings, pixel_rays
from vlref.geometry.raycast import _per_object
from vlref.march.patterns import _bayer_offsets, offsets


def main() -> None:
    scene = bench_scene(1920, 1080, 64, "four", 1024)
    camera = camera_from_settings(scene.camera, 1920, 1080)

    def whole_frame_rays():
        nx, ny = camera.pixel_ndc()
        t = camera.tan_half_fov
        d = np.stack([nx * t * camera.aspect, ny * t, np.ones_like(nx)], axis=-1) @ camera.rotation.T
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    ids = np.random.default_rng(0).integers(-1, 5, (1080, 1920)).astype(np.int32)
    table = np.random.default_rng(1).random((5, 3))
    out = {"directions_whole_frame_s": median_time(whole_frame_rays, 7)}
    for rows in (8, 16, 32, 68):
        row_blocks.in_row_blocks.__defaults__ = (None, rows)
        out[f"directions_blocks_{rows}_s"] = median_time(lambda: pixel_rays(camera, 1920, 1080), 7)
    row_blocks.in_row_blocks.__defaults__ = (None, row_blocks.BLOCK_ROWS)
    out["directions_one_thread_s"] = median_time(lambda: pixel_rays(camera, 1920, 1080, threads=1), 7)
    out["bayer8_tile_copy_s"] = median_time(
        lambda: np.tile(_bayer_offsets(8), (1080 // 8 + 1, 1920 // 8 + 1))[:1080, :1920].copy(), 7)
    out["bayer8_blocks_s"] = median_time(lambda: offsets("bayer8", 1920, 1080), 7)
    out["albedo_fancy_index_s"] = median_time(lambda: np.concatenate([table, np.zeros((1, 3))])[ids], 7)
    out["albedo_take_blocks_s"] = median_time(lambda: _per_object(table, ids), 7)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
