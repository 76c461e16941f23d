"""Where writing a 1080p render's default outputs goes (BENCHMARKS.md, "The frame around the kernels"): one render of
scene (b) at 1920x1080 (16 steps: the buffers' content, not the march, matters here), then in this process each part
of ``vlref render``'s writing timed alone (medians of 3) and the whole ``save_render`` with and without fsync.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=... python3 benchmarks/write_split.py
"""

import io
import os
import statistics
import tempfile
import time

import OpenEXR

from vlref.bench import bench_scene
from vlref.cli.options import preview_exposure
from vlref.io.exr import channel_dict, openexr
from vlref.io.output_folders import output_dir
from vlref.io.png import png_bytes
from vlref.io.render_files import save_render
from vlref.io.tonemap import srgb8
from vlref.render import render

MAIN = ("final", "depth", "inscatter", "transmittance")


def timed(fn, repeats=3):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main():
    scene = bench_scene(1920, 1080, 16, "four", 1024)
    result = render(scene)
    openexr()
    t, (exposure, meta, _) = timed(lambda: preview_exposure(scene, result.buffers["final"]))
    print(f"preview exposure {t:.3f} s")
    t, codes = timed(lambda: srgb8(result.buffers["final"], exposure))
    print(f"srgb8 (bands on threads) {t:.3f} s")
    t, png = timed(lambda: png_bytes(codes, meta))
    print(f"PNG encode (zlib 1) {t:.3f} s, {len(png) / 1e6:.2f} MB")
    t, data = timed(lambda: {n: channel_dict(result.buffers[n], None) for n in MAIN})
    print(f"float32 channels {t:.3f} s")
    for comp in ("NO", "RLE", "ZIPS", "ZIP", "PIZ", "ZSTD"):
        c = getattr(OpenEXR, comp + "_COMPRESSION")

        def write():
            size = 0
            for d in data.values():
                b = io.BytesIO()
                with OpenEXR.File({"compression": c, "type": OpenEXR.scanlineimage}, d) as f:
                    f.write(b)
                size += len(b.getvalue())
            return size
        t, size = timed(write)
        print(f"EXR {comp:4s} to memory, one file after another {t:.3f} s, {size / 1e6:.1f} MB")
    real_fsync = os.fsync
    for label, fsync in (("with fsync", real_fsync), ("fsync a no-op", lambda fd: None)):
        os.fsync = fsync
        with tempfile.TemporaryDirectory() as folder:
            def save():
                with output_dir(folder + "/out") as out:
                    save_render(out, result, stages=False, main=MAIN, exposure=exposure, png_meta=meta)
            t, _ = timed(save)
        print(f"save_render {label} {t:.3f} s")
    os.fsync = real_fsync


if __name__ == "__main__":
    main()
