#!/bin/bash
# The device call of BENCHMARKS.md "The march in fewer bands": what the device's Python environment has byte-compiled
# and what its import costs with and without .pyc files, then main against a branch (whole `vlref render` of (b),
# alternated, one Numba cache: benchmarks/startup_ab.py) and the march's bands (benchmarks/march_bands.py), both
# with every imported module byte-compiled. Run in main's checkout, /tmp/site holding the wheels:
#     bash BRANCH/benchmarks/volumetrics_device.sh BRANCH OUT_DIR
set -u
B=$(cd "$1" && pwd); OUT=$2
SP=$(python3 -c "import numpy, os; print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig; print(sysconfig.get_paths()['stdlib'])")
{ echo "python3: $(command -v python3)"; python3 -VV; echo "PYTHONDONTWRITEBYTECODE=${PYTHONDONTWRITEBYTECODE-unset}"
  echo "THP: $(cat /sys/kernel/mm/transparent_hugepage/enabled)"; echo "cores: $(nproc)"; echo "site: $SP; stdlib: $STD"
  for p in numpy numba llvmlite scipy yaml; do
    echo "$p: $(find "$SP/$p" -name '*.pyc' 2>/dev/null | wc -l) pyc / $(find "$SP/$p" -name '*.py' 2>/dev/null | wc -l) py"
  done
  echo "stdlib: $(find "$STD" -maxdepth 2 -name '*.pyc' | wc -l) pyc / $(find "$STD" -maxdepth 1 -name '*.py' | wc -l) py (top level)"
  ls -la "$SP/numpy/__pycache__" 2>&1 | head -4; } > "$OUT/env.txt" 2>&1
python3 -m compileall -q -j 0 vlref /tmp/site "$B/vlref" > /dev/null 2>&1
PROBE='import time
t = time.perf_counter()
from vlref.cli.commands import program_command
program_command("render")
t1 = time.perf_counter()
from vlref.jit_init import initialise_numba
initialise_numba()
t2 = time.perf_counter()
print(f"import {t1 - t:.3f} numba_init {t2 - t1:.3f}")
import sys
open("/tmp/mods.txt", "w").write("\n".join(m.__file__ for m in list(sys.modules.values())
                                           if (getattr(m, "__file__", None) or "").endswith(".py")))'
TIMEFORMAT=%R
probe() { { echo -n "$1: "; { time python3 -c "$PROBE" ; } 2>&1 | tr '\n' ' '; echo; } >> "$OUT/import.txt"; }
python3 -X importtime -c "$PROBE" 2> "$OUT/importtime_plain.txt"
probe plain
echo -n "compileall into /tmp/pyc, s: " >> "$OUT/import.txt"
export PYTHONPYCACHEPREFIX=/tmp/pyc
{ time { timeout 60 python3 -m compileall -q -j 0 "$SP/numpy" "$SP/numba" "$SP/llvmlite" "$SP/scipy" "$SP/yaml" \
  vlref /tmp/site "$B/vlref" > /dev/null 2>&1; python3 -m compileall -q -i /tmp/mods.txt > /dev/null 2>&1; } ; } 2>> "$OUT/import.txt"
for m in pyc pyc plain plain pyc; do if [ $m = pyc ]; then probe pyc; else (unset PYTHONPYCACHEPREFIX; probe plain); fi; done
python3 -X importtime -c "$PROBE" 2> "$OUT/importtime_pyc.txt"
PYTHONPATH=/tmp/site timeout 150 python3 "$B/benchmarks/startup_ab.py" "$OUT" 1 "$B" > "$OUT/startup_ab.txt" 2>&1
PYTHONPATH=$PWD:/tmp/site timeout 60 python3 "$B/benchmarks/march_bands.py" "$OUT/bands.json" > "$OUT/bands.txt" 2>&1
echo done >> "$OUT/import.txt"
