#!/bin/bash
# The same-host alternated A/B of the march, main a776eca (.dev/main776) against this tree (.dev/i29-march), on the
# device (BENCHMARKS.md, "The march: fewer divisions per sample, measured, not adopted"): benchmarks/march_ab.py, warm
# (both trees and precisions side by side), then rounds of main, tree, tree, main until ROUNDS are done or BUDGET_S
# seconds have passed (checked before each process); PRECISIONS (default both) narrows what is compiled and timed.
# Run from the root of the checkout that carries .dev/main776, .dev/i29-march, .whl and .device-libs.
set -u
ROOT=$PWD ROUNDS=${ROUNDS:-5} BUDGET_S=${BUDGET_S:-230} PRECISIONS=${PRECISIONS:-float64 float32}
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl
export LD_LIBRARY_PATH=$ROOT/.device-libs/lib:${LD_LIBRARY_PATH:-} XDG_RUNTIME_DIR=/tmp PYTHONUNBUFFERED=1
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
export PYTHONPYCACHEPREFIX=/tmp/pyc
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD /tmp/site \
    .dev/main776/vlref .dev/i29-march/vlref > /dev/null
lscpu | grep -i "model name" | tee $OUT/machine.txt
AB=$ROOT/.dev/i29-march/benchmarks/march_ab.py
tree() { case $1 in main) echo $ROOT/.dev/main776;; *) echo $ROOT/.dev/i29-march;; esac; }
ab() { (cd $(tree $2) && PYTHONPATH=$PWD:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$2 python3 $AB "$@"); }
for label in main tree; do for p in $PRECISIONS; do ab warm $label $p > $OUT/warm-$label-$p.log 2>&1 & done; done
wait
echo "warm done at ${SECONDS} s"
for r in $(seq $ROUNDS); do
  for label in main tree tree main; do
    [ $SECONDS -gt $BUDGET_S ] && { echo "stopped in round $r at ${SECONDS} s"; break 2; }
    ab time $label $PRECISIONS
  done
done
echo "done at ${SECONDS} s"
