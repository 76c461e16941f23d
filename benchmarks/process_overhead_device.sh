#!/bin/bash
# The process around the kernels, main against a branch on one device machine (BENCHMARKS.md, "The program's own
# process: Numba without cffi and extensions, files synced beside the writing"). Run in the lead's checkout on the
# device with .dev/main7a4 (main) and .dev/BRANCH carried:  bash .dev/BRANCH/benchmarks/process_overhead_device.sh BRANCH
# 1. everything the processes import byte-compiled into PYTHONPYCACHEPREFIX (the device's NumPy has no .pyc files);
# 2. benchmarks/startup_ab.py twice in a copy of main (one Numba cache: the branch changes no kernel file): main,
#    branch, branch, main, main, branch each time, the bench's whole_render with its split; the first also profiles;
# 3. the outputs of (b) at 1920x1080 (16 steps) written by each tree's `vlref render` path, hashed;
# 4. Numba's initialisation alone in fresh processes of the branch, declared own-kernels-only or not, alternated.
set -e
BRANCH=$1
python3 -m pip install -q --upgrade --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site LD_LIBRARY_PATH=$PWD/.device-libs/lib:$LD_LIBRARY_PATH XDG_RUNTIME_DIR=/tmp \
       NUMBA_CACHE_DIR=/tmp/nc PYTHONUNBUFFERED=1 PYTHONPYCACHEPREFIX=/tmp/pyc
ROOT=$PWD
BR=$ROOT/.dev/$BRANCH
rm -rf /tmp/ab && mkdir -p /tmp/ab && cp -r .dev/main7a4 /tmp/ab/main
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD /tmp/ab/main/vlref $BR/vlref \
    /tmp/site > /dev/null 2>&1 || true
lscpu | grep -E "Model name|^CPU\(s\)" ; nproc; python3 -c "import sys, numba, numpy; print(sys.version, numba.__version__, numpy.__version__)"
python3 -c "from importlib import metadata; print('distributions:', len(list(metadata.distributions())))"
mkdir -p $OUT/ab1 $OUT/ab2 && cd /tmp/ab/main
python3 $BR/benchmarks/startup_ab.py $OUT/ab1 150 $BR
python3 $BR/benchmarks/startup_ab.py $OUT/ab2 20 $BR
HASH='
import hashlib, pathlib, tempfile
from vlref.cli.commands import program_command
render_to_folder = program_command("render").render_to_folder
from vlref.bench import bench_scene
with tempfile.TemporaryDirectory() as d:
    render_to_folder(bench_scene(1920, 1080, 16, "four", 1024), d + "/out")
    print(" ".join(f"{p.name} {hashlib.sha256(p.read_bytes()).hexdigest()[:16]}" for p in sorted(pathlib.Path(d, "out").iterdir())))
'
echo "main   $(python3 -c "$HASH")" | tee $OUT/hashes.txt
CHANGED=$(cd $BR && for f in $(find vlref -name '*.py'); do cmp -s $f /tmp/ab/main/$f || echo $f; done)
echo "changed: $CHANGED"
for f in $CHANGED; do cp $BR/$f /tmp/ab/main/$f; done
echo "branch $(python3 -c "$HASH")" | tee -a $OUT/hashes.txt
PYTHONPATH=/tmp/ab/main:$PYTHONPATH python3 $BR/benchmarks/own_kernels_init.py 4 | tee $OUT/own_kernels_init.txt
