#!/bin/bash
# Whether loading the march's work and the lights' sum ahead (the scene's variant) pays in the whole render, beside
# the one watched launch (BENCHMARKS.md, "The march in one launch, watched"; run at 574cede, whose vlref/ahead.py
# loaded them so; the change was then reverted, and the swap below is a no-op in later trees). Run in the lead's checkout on the device
# with .dev/MAIN and .dev/BRANCH carried:
#     bash .dev/BRANCH/benchmarks/loads_ahead_device.sh MAIN BRANCH ROUNDS
# Each tree's own Numba cache holds the float32 variant of the march's stage and the float64 render of (b) (as the
# full bench leaves it); then ROUNDS rounds of main, branch, branch with main's vlref/ahead.py ("noahead": the march's
# work and sum loaded by the render itself where the cache holds several variants; ahead.py holds no compiled
# function, so the branch's cache serves it), in the order main, branch, noahead, noahead, branch, main: each run the
# tree's own bench_whole_render with one repeat (a fresh process), its split printed as JSON.
set -e
MAIN=$1 BRANCH=$2 ROUNDS=${3:-4}
source $(dirname "$0")/device_ab_env.sh
F32='import dataclasses, tempfile
from vlref.ahead import compile_stage
from vlref.bench import bench_scene
from vlref.cli.render import render_to_folder
if __name__ == "__main__":
    s = bench_scene(320, 180, 64, "four", 1024)
    compile_stage("march", s.replace(render=dataclasses.replace(s.render, precision="float32")))
    with tempfile.TemporaryDirectory() as f:
        render_to_folder(s, f + "/out")'
ONE='import dataclasses, json
from vlref.bench.config import FULL
from vlref.bench.renders import bench_whole_render
print(json.dumps(bench_whole_render(dataclasses.replace(FULL, repeats=1))))'
T0=$(date +%s)
(cd $ROOT/.dev/$MAIN && PYTHONPATH=$ROOT/.dev/$MAIN:/tmp/site NUMBA_CACHE_DIR=/tmp/la/a python3 -c "$F32") &
(cd $ROOT/.dev/$BRANCH && PYTHONPATH=$ROOT/.dev/$BRANCH:/tmp/site NUMBA_CACHE_DIR=/tmp/la/b python3 -c "$F32") &
wait
echo "caches filled: $(( $(date +%s) - T0 )) s"
cp -p $ROOT/.dev/$BRANCH/vlref/ahead.py /tmp/ahead_branch.py
one() {  # label tree cache
    (cd $ROOT/.dev/$2 && PYTHONPATH=$ROOT/.dev/$2:/tmp/site NUMBA_CACHE_DIR=/tmp/la/$3 python3 -c "$ONE") | tail -1 | \
        sed "s/^/$1 /"
}
one main $MAIN a > /dev/null; one branch $BRANCH b > /dev/null  # dropped
for i in $(seq $ROUNDS); do
    for v in main branch noahead noahead branch main; do
        if [ $v = noahead ]; then cp $ROOT/.dev/$MAIN/vlref/ahead.py $ROOT/.dev/$BRANCH/vlref/ahead.py; fi
        case $v in main) one main $MAIN a;; *) one $v $BRANCH b;; esac
        cp -p /tmp/ahead_branch.py $ROOT/.dev/$BRANCH/vlref/ahead.py
    done
done | tee $OUT/loads_ahead.txt
