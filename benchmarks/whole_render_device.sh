#!/bin/bash
# The whole `vlref render` of (b), main against a branch on one device machine, each tree with its own Numba cache
# (BENCHMARKS.md, "One pass for the lights' sum and the composite; the render without the reference"). Run in the
# lead's checkout on the device with .dev/MAIN and .dev/BRANCH carried:
#     bash .dev/BRANCH/benchmarks/whole_render_device.sh MAIN BRANCH PAIRS ROUNDS
# 1. everything the processes import byte-compiled into PYTHONPYCACHEPREFIX (the device's NumPy has no .pyc files);
# 2. benchmarks/whole_render_ab.py: both caches filled, PAIRS rounds of main, branch, branch, main, the outputs hashed;
# 3. benchmarks/volumetrics_fresh.py, one render in a fresh process, ROUNDS times main, branch, and the branch with
#    glibc's malloc asking for transparent huge pages (GLIBC_TUNABLES=glibc.malloc.hugetlb=1);
set -e
MAIN=$1 BRANCH=$2 PAIRS=${3:-4} ROUNDS=${4:-3}
source $(dirname "$0")/device_ab_env.sh
python3 $ROOT/.dev/$BRANCH/benchmarks/whole_render_ab.py $OUT $PAIRS $ROOT/.dev/$MAIN $ROOT/.dev/$BRANCH /tmp/wrab
for i in $(seq $ROUNDS); do
    for t in main:$MAIN:a branch:$BRANCH:b hugetlb:$BRANCH:b; do
        IFS=: read label tree cache <<< "$t"
        TUNE=$([ $label = hugetlb ] && echo glibc.malloc.hugetlb=1 || echo "")
        echo "== volumetric pieces, $label, fresh process $i"
        (cd $ROOT/.dev/$tree && GLIBC_TUNABLES=$TUNE PYTHONPATH=$ROOT/.dev/$tree:/tmp/site \
            NUMBA_CACHE_DIR=/tmp/wrab/$cache python3 $ROOT/.dev/$BRANCH/benchmarks/volumetrics_fresh.py 1) | tail -2
    done
done | tee $OUT/pieces.txt
# 4. the render command's import alone, fresh processes alternated (main, branch) x 10
IMP='import time; t0 = time.perf_counter()
from vlref.cli.commands import program_command
program_command("render").render_to_folder
import sys; print(round(time.perf_counter() - t0, 4), len([m for m in sys.modules if m.startswith("vlref")]))'
for i in $(seq 10); do
    for t in $MAIN $BRANCH; do
        echo "import $t $(cd /tmp && PYTHONPATH=$ROOT/.dev/$t:/tmp/site python3 -c "$IMP")"
    done
done | tee $OUT/import_ab.txt
