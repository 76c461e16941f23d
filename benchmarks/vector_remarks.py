"""Which of the march's loops LLVM vectorises for another CPU, compiled on this machine (BENCHMARKS.md, "The march
outside its steps"): the device's Xeon (LLVM ``emeraldrapids``, AVX-512) from the dev box (Zen 3, AVX2), whose own
cost model leaves other loops scalar (table lookups: it does not gather).

    PYTHONPATH=$PWD python3 benchmarks/vector_remarks.py [CPU]      # default emeraldrapids

A first process builds the arguments of :func:`vlref.march.physical._march_tasks` for bench scene (a) at 64x36 and
pickles them; a second one, with ``NUMBA_CPU_NAME``/``NUMBA_CPU_FEATURES`` for ``CPU`` (``FEATURES``; any other CPU
takes ``NUMBA_CPU_FEATURES`` from the environment), a fresh cache and line numbers (``NUMBA_DEBUGINFO``), only
compiles it (the code would not run here) with LLVM's loop-vectoriser remarks on, and prints per source line the
loops vectorised (with their width) and the reasons the others were not. Debug information can change what LLVM
does at the margins: a guide for where to look, not a measurement.
"""

import collections
import os
import pickle
import re
import subprocess
import sys
import tempfile

FEATURES = {"emeraldrapids": "+64bit,+avx,+avx2,+avx512f,+avx512dq,+avx512bw,+avx512vl,+avx512cd,+avx512vnni,"
                             "+avx512ifma,+avx512vbmi,+bmi,+bmi2,+cmov,+cx16,+f16c,+fma,+fxsr,+lzcnt,+mmx,+movbe,"
                             "+popcnt,+sse,+sse2,+sse3,+sse4.1,+sse4.2,+ssse3,+xsave,+prfchw,+adx"}

COMPILE = r'''
import pickle, sys, numba
import llvmlite.binding as llvm
for option in ("-pass-remarks=loop-vectorize", "-pass-remarks-missed=loop-vectorize",
               "-pass-remarks-analysis=loop-vectorize"):
    llvm.set_option("", option)
from vlref.march import physical
args = pickle.load(open(sys.argv[1], "rb"))
physical._march_tasks.compile(tuple(numba.typeof(a) for a in args))
'''


def arguments(path: str) -> None:
    """Pickle ``_march_tasks``' arguments for bench scene (a) at 64x36 into ``path``."""
    import numpy as np

    from vlref.bench.config import FULL, bench_scene
    from vlref.march.patterns import offsets
    from vlref.medium import pack_medium
    from vlref.render import prepare_frame
    from vlref.scene.technique_params import resolved

    w, h = 64, 36
    scene = bench_scene(w, h, FULL.steps, "one", FULL.shadow_resolution)
    frame = prepare_frame(scene)
    cam = frame.camera
    args = (np.zeros(1, np.int64), (np.int64(0), np.int64(h)), np.int64(FULL.steps), True, np.int64(8),
            np.asarray(cam.position, dtype=np.float64), np.ascontiguousarray(cam.ray_directions(w, h)),
            np.minimum(frame.gbuffer.distance, scene.render.max_distance),
            offsets(resolved(scene, "sampling"), w, h, scene.render.seed), pack_medium(scene, np.float64),
            frame.lights.astype(np.float64), frame.shadow_maps().table, None, np.empty((1, h, w, 3)),
            np.empty((h, w)))
    with open(path, "wb") as fh:
        pickle.dump(args, fh)


def main(cpu: str = "emeraldrapids") -> None:
    with tempfile.TemporaryDirectory(prefix="vlref_remarks_") as folder:
        path = os.path.join(folder, "args.pickle")
        subprocess.run([sys.executable, __file__, "--arguments", path], check=True)
        env = dict(os.environ, NUMBA_CPU_NAME=cpu, NUMBA_DEBUGINFO="1", NUMBA_CACHE_DIR=os.path.join(folder, "cache"),
                   NUMBA_CPU_FEATURES=FEATURES.get(cpu, os.environ.get("NUMBA_CPU_FEATURES", "")))
        proc = subprocess.run([sys.executable, "-c", COMPILE, path], env=env, capture_output=True, text=True)
    if proc.returncode:
        raise SystemExit(proc.stderr[-3000:])
    lines = collections.defaultdict(collections.Counter)
    for match in re.finditer(r"remark: (\S+?):(\d+):\d+: (.*)", proc.stderr):
        message = match.group(3)
        if "indicates that interleaving" not in message and "already been vectorized" not in message:
            lines[(match.group(1), int(match.group(2)))][message[:100]] += 1
    for (source, line), messages in sorted(lines.items()):
        done = sorted(f"{m} x{n}" for m, n in messages.items() if m.startswith("vectorized"))
        print(f"{'VECTOR' if done else 'scalar'} {source}:{line}: {'; '.join(done or sorted(messages))}")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--arguments"]:
        arguments(sys.argv[2])
    else:
        main(*sys.argv[1:2])
