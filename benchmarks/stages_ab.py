"""A/B of the frame's stages inside the process, for several trees on one machine (BENCHMARKS.md, "The scene
colour's shadow rays inlined").

    python3 benchmarks/stages_ab.py OUT.json LABEL=TREE [LABEL=TREE ...]

Each tree gets its own ``NUMBA_CACHE_DIR``, filled by one cold process per tree (all at once), as
``frame_stages_ab.py`` does (its ``COLD``: ``vlref render``'s path of (b) at 320x180, the maps of cage and
window). Then the trees in order and in reverse (A, B, B, A), each process running the bench's
``whole_render`` (a fresh ``vlref render`` of (b) at 1920x1080x64, four shadowed lights: wall and stage split),
then in itself (medians after a warm-up call): the scene colour of (b) at 1080p (5 calls) and the march of (a) and
(b) as the bench's ``march`` section times it (``physical.render`` of a prepared frame, 3 calls each), and SHA-256
digests of the scene colour and of (a)'s and (b)'s march buffers, which must agree between the trees. (Commit
451351f's version also timed the march with its outputs faulted in on threads, a change measured and reverted.)
"""

import json
import subprocess
import sys

from frame_stages_ab import COLD, _env  # benchmarks/ is the script's folder: its caches and cold process

CHILD = """
import hashlib, json, time
import numpy as np
from vlref.bench.config import bench_scene, median_time as median
from vlref.bench.renders import _whole
from vlref.lights.shading import scene_colour
from vlref.render import prepare_frame
from vlref.techniques import physical
out = {}
whole = _whole(None, 1920, 1080, 64, "four", 1024)
out.update(whole_s=whole["process_s"], split=whole["split"])
digest = lambda *arrays: hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)).hexdigest()[:16]
frames = {}
for name, lights in (("a", "one"), ("b", "four")):
    scene = bench_scene(1920, 1080, 64, lights, 1024)
    frame = prepare_frame(scene)
    frame.shadow_maps()
    frames[name] = (scene, frame)
scene, frame = frames["b"]
out["shading_s"] = median(lambda: scene_colour(frame.gbuffer, scene, frame.geometry, frame.lights), 5)
out["colour_digest"] = digest(frame.scene_colour)
for name, (scene, frame) in frames.items():
    out[f"march_{name}_s"] = median(lambda: physical.render(scene, frame), 3)
    res = physical.render(scene, frame)
    out[f"march_{name}_digest"] = digest(*(res[k] for k in sorted(res)))
print(json.dumps(out))
"""

def _measure(tree: str, label: str) -> dict:
    """One process of ``tree`` running ``CHILD``: its figures."""
    proc = subprocess.run([sys.executable, "-c", CHILD], cwd=tree, env=_env(tree, label), capture_output=True,
                          text=True)
    if proc.returncode:
        raise SystemExit(f"{label}: {proc.stderr[-3000:]}")
    figures = json.loads(proc.stdout.strip().splitlines()[-1])
    print(label, json.dumps(figures), flush=True)
    return figures


def main(out: str, trees: dict) -> None:
    cold = [subprocess.Popen([sys.executable, "-c", COLD], cwd=tree, env=_env(tree, label), stdout=subprocess.DEVNULL)
            for label, tree in trees.items()]
    if any(proc.wait() for proc in cold):
        raise SystemExit("a cold render failed")
    results = {label: [] for label in trees}
    for label in list(trees) + list(trees)[::-1]:
        results[label].append(_measure(trees[label], label))
        with open(out, "w") as f:
            json.dump(results, f, indent=1)
    for key in ("colour_digest", "march_a_digest", "march_b_digest"):
        print(key, {label: sorted({r[key] for r in rs}) for label, rs in results.items()})
    for key in ("whole_s", "shading_s", "march_a_s", "march_b_s"):
        print(key, "  ".join(f"{label} {' / '.join(f'{r[key]:.4f}' for r in rs)}" for label, rs in results.items()))
    for stage in results[list(trees)[0]][0]["split"]:
        print("split", stage, "  ".join(f"{label} {' / '.join('%.3f' % r['split'][stage] for r in rs)}"
                                        for label, rs in results.items()))


if __name__ == "__main__":
    main(sys.argv[1], dict(arg.split("=", 1) for arg in sys.argv[2:]))
