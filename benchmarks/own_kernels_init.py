"""Numba's initialisation (``vlref.jit_init.initialise_numba``) in fresh processes, declared ones that run vlref's
kernels alone (``vlref render``'s program: no cffi support, no extension entry-point scan) and not, alternated
(BENCHMARKS.md, "The program's own process: Numba without cffi and extensions, files synced beside the writing").

    cd CHECKOUT && PYTHONPATH=$PWD python3 benchmarks/own_kernels_init.py ROUNDS
"""

import statistics
import subprocess
import sys

CHILD = """
import sys, time
from vlref.cli.commands import program_command
program_command("render" if sys.argv[1] == "own" else "scenes")  # only "render" declares its process
import vlref.cli.render
t = time.perf_counter()
from vlref.jit_init import initialise_numba
initialise_numba()
print(time.perf_counter() - t, "cffi" in sys.modules)
"""


def main(rounds: int) -> None:
    times = {"own": [], "other": []}
    for _ in range(rounds):
        for label in ("other", "own", "own", "other"):
            out = subprocess.run([sys.executable, "-c", CHILD, label], capture_output=True, text=True,
                                 check=True).stdout.split()
            times[label].append(float(out[0]))
            print(label, f"{float(out[0]):.3f} s, cffi imported: {out[1]}", flush=True)
    print({k: f"median {statistics.median(v):.3f} s, min {min(v):.3f} s" for k, v in times.items()})


if __name__ == "__main__":
    main(int(sys.argv[1]))
