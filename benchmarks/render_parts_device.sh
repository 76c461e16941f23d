#!/bin/bash
# The whole `vlref render` of (b), main against a branch on one device machine, each tree with its own Numba cache,
# then the parts of its ray-cast stage and of the branch's changes (BENCHMARKS.md, "SciPy's BLAS threads, kernels
# loaded ahead"). Run in the lead's checkout on the device with .dev/MAIN and .dev/BRANCH carried, the
# wheels installed into /tmp/site and PYTHONPYCACHEPREFIX set:
#     bash .dev/BRANCH/benchmarks/render_parts_device.sh MAIN BRANCH PAIRS ROUNDS
# 1. everything the processes import byte-compiled into PYTHONPYCACHEPREFIX (the device's NumPy has no .pyc files);
# 2. benchmarks/whole_render_ab.py: both caches filled, PAIRS rounds of main, branch, branch, main, outputs hashed;
# 3. benchmarks/render_parts.py: ROUNDS rounds of the ray cast's parts, of the render with and without the kernels
#    loaded ahead, and with and without SciPy's BLAS kept to one thread.
set -e
MAIN=$1 BRANCH=$2 PAIRS=${3:-4} ROUNDS=${4:-2}
ROOT=$PWD
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD $ROOT/.dev/$MAIN/vlref \
    $ROOT/.dev/$BRANCH/vlref /tmp/site > /dev/null 2>&1 || true
lscpu | grep -E "Model name|^CPU\(s\)|Thread" ; nproc
python3 -c "import sys, numba, numpy; print(sys.version, numba.__version__, numpy.__version__)"
python3 $ROOT/.dev/$BRANCH/benchmarks/whole_render_ab.py $OUT $PAIRS $ROOT/.dev/$MAIN $ROOT/.dev/$BRANCH /tmp/wrab \
    | tee $OUT/whole_render_ab.txt
python3 $ROOT/.dev/$BRANCH/benchmarks/render_parts.py $OUT $ROUNDS $ROOT/.dev/$MAIN $ROOT/.dev/$BRANCH /tmp/wrab \
    | tee $OUT/render_parts.txt
