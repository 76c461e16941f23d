"""The NumPy passes of a frame run in row blocks on threads (:mod:`vlref.row_blocks`) against their whole-frame
expressions, in one process (medians of 7 after a warm-up call), and the ray directions with other largest block
sizes (``MAX_BLOCK_ROWS``). BENCHMARKS.md, "The stages around the kernels".

    PYTHONPATH=$PWD python3 benchmarks/row_blocks_sizes.py
"""

import json

import numpy as np

from vlref import row_blocks
from vlref.bench.config import bench_scene, median_time
from vlref.camera import camera_from_settings, pixel_rays
from vlref.geometry.raycast import per_object


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
    default = row_blocks.MAX_BLOCK_ROWS
    for rows in (8, 16, 32, default):
        row_blocks.MAX_BLOCK_ROWS = rows
        out[f"directions_max_rows_{rows}_s"] = median_time(lambda: pixel_rays(camera, 1920, 1080), 7)
    row_blocks.MAX_BLOCK_ROWS = default
    out["directions_one_thread_s"] = median_time(lambda: pixel_rays(camera, 1920, 1080, threads=1), 7)
    out["albedo_fancy_index_s"] = median_time(lambda: np.concatenate([table, np.zeros((1, 3))])[ids], 7)
    out["albedo_take_blocks_s"] = median_time(lambda: per_object(table, ids), 7)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
