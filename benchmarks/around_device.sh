#!/bin/bash
# The whole `vlref render` of (b) around its march, main against a branch on one device machine (BENCHMARKS.md, "The
# render's first kernel loaded first, the albedo on demand, each EXR file written as its channels are made"). Run in
# the lead's checkout on the device with .dev/MAIN and .dev/BRANCH carried:
#     bash .dev/BRANCH/benchmarks/around_device.sh MAIN BRANCH PAIRS
# 1. everything the processes import byte-compiled into PYTHONPYCACHEPREFIX (the device's NumPy has no .pyc files);
# 2. benchmarks/whole_render_ab.py: both caches filled, PAIRS rounds of main, branch, branch, main, the outputs hashed;
# 3. `python3 -X importtime` of what `vlref render` imports, main and branch alternated, 3 times each.
set -e
MAIN=$1 BRANCH=$2 PAIRS=${3:-3}
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site LD_LIBRARY_PATH=$PWD/.device-libs/lib:$LD_LIBRARY_PATH XDG_RUNTIME_DIR=/tmp \
       PYTHONUNBUFFERED=1 PYTHONPYCACHEPREFIX=/tmp/pyc
ROOT=$PWD
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD $ROOT/.dev/$MAIN/vlref \
    $ROOT/.dev/$BRANCH/vlref /tmp/site > /dev/null 2>&1 || true
lscpu | grep -E "Model name|^CPU\(s\)" ; python3 -c "import sys, numba, numpy; print(sys.version, numba.__version__, numpy.__version__)"
python3 $ROOT/.dev/$BRANCH/benchmarks/whole_render_ab.py $OUT $PAIRS $ROOT/.dev/$MAIN $ROOT/.dev/$BRANCH /tmp/wrab
IMP='from vlref.cli.commands import program_command
program_command("render").render_to_folder'
for i in 1 2 3; do
    for t in $MAIN $BRANCH; do
        (cd /tmp && PYTHONPATH=$ROOT/.dev/$t:/tmp/site python3 -X importtime -c "$IMP" 2>> $OUT/importtime_$t.txt)
        echo "== end of run $i" >> $OUT/importtime_$t.txt
    done
done
echo done
