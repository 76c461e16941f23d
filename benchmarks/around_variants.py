"""The whole ``vlref render`` of (b) at 1920x1080x64 in fresh processes of one tree, with each of this round's
changes switched off in turn (BENCHMARKS.md, "Around the march: the BVH build loaded first, the albedo on demand,
each EXR file written as its channels are made, Numba without colorama"): what each bought, on one machine.

    python3 benchmarks/around_variants.py OUT_DIR ROUNDS [CACHE_DIR]

Variants: ``all`` (the tree), ``geometry`` (the BVH build not loaded ahead first: ``LOADED_AHEAD`` without it),
``write`` (the float32 channels of every buffer made before the first file, as before), ``albedo`` (the albedo made
by the render, as before), ``colorama`` (imported, as Numba's import did). The cache is filled by a cold render of
(b) at 320x180 first, then one 1080p run is dropped; ``ROUNDS`` rounds of the variants in order and in reverse. Each
run is a fresh process that imports what ``vlref render`` imports, renders (b) with ``render_to_folder`` into a
folder that the parent removes after the process ended, and ends with ``exit_at_once``; its split as
``bench_whole_render``'s, with ``rest`` (the process wall less the split's parts). Writes
``OUT_DIR/around_variants.json``.
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHILD = """
import concurrent.futures, json, pickle, sys, time
t0 = time.perf_counter()
if sys.argv[2] == "colorama":
    import colorama  # imported, as Numba's import imported it before
from vlref.cli.commands import exit_at_once, program_command
render_to_folder = program_command("render").render_to_folder
t1 = time.perf_counter()
import vlref.ahead, vlref.io.render_files as files, vlref.render
from vlref.io.exr import channel_dict, write_exr
variant = sys.argv[2]
if variant == "geometry":
    del vlref.ahead.LOADED_AHEAD["geometry"]
if variant == "write":
    def save_buffers(out_dir, buffers, metadata=None, half=()):
        with concurrent.futures.ThreadPoolExecutor(max(1, min(len(buffers), files.host_cores()))) as pool:
            channels = list(pool.map(lambda array: channel_dict(array, None), buffers.values()))
        return [write_exr(out_dir / f"{name}.exr", data, metadata=metadata, half=name in half)
                for name, data in zip(buffers, channels)]
    files.save_buffers = save_buffers
if variant == "albedo":
    vlref.render.RenderBuffers.deferred = staticmethod(lambda make, *args: make(*args))
with open(sys.argv[1], "rb") as fh:
    scene = pickle.load(fh)
result, _, write_s, _ = render_to_folder(scene, sys.argv[3])
t2 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "stages": result.timings, "write_s": write_s, "in_process_s": t2 - t0}))
exit_at_once(0)
"""

VARIANTS = ("all", "geometry", "write", "albedo", "colorama")
SIZE = tuple(int(v) for v in os.environ.get("AROUND_SIZE", "1920x1080").split("x"))


def main(out_dir: str, rounds: int, cache_dir: str = "/tmp/around_cache") -> None:
    from vlref.bench import bench_scene
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    report = {"runs": {v: [] for v in VARIANTS}}
    with tempfile.TemporaryDirectory() as folder:
        scene_file = Path(folder) / "scene.pickle"
        small = Path(folder) / "small.pickle"
        scene_file.write_bytes(__import__("pickle").dumps(bench_scene(*SIZE, 64, "four", 1024)))
        small.write_bytes(__import__("pickle").dumps(bench_scene(320, 180, 64, "four", 1024)))

        def run(variant: str, scene: Path) -> dict:
            out = Path(folder) / "out"
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-c", CHILD, str(scene), variant, str(out)], env=env,
                                  capture_output=True, text=True, check=True)
            wall = time.perf_counter() - start
            subprocess.run(["rm", "-rf", str(out)], check=True)
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            split = {"start_and_import": r["import_s"], **r["stages"], "write": r["write_s"],
                     "exit": wall - r["in_process_s"]}
            split["rest"] = wall - sum(split.values())
            return {"seconds": wall, "split": split}

        run("all", small)  # fills the cache
        run("all", scene_file)  # dropped
        for _ in range(rounds):
            for variant in VARIANTS + VARIANTS[::-1]:
                r = run(variant, scene_file)
                report["runs"][variant].append(r)
                print(variant, f"{r['seconds']:.3f} s;", ", ".join(f"{k} {v:.3f}" for k, v in r["split"].items()),
                      flush=True)
    report["median"] = {v: {"seconds": statistics.median(r["seconds"] for r in runs),
                            **{s: statistics.median(r["split"][s] for r in runs) for s in runs[0]["split"]}}
                        for v, runs in report["runs"].items()}
    print("medians:", json.dumps(report["median"]), flush=True)
    (Path(out_dir) / "around_variants.json").write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), *sys.argv[3:])
