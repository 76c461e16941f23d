#!/bin/bash
# The march in one watched launch against main's bands, on one device machine (BENCHMARKS.md, "The march in one
# launch, watched"). Run in the lead's checkout on the device with .dev/MAIN and .dev/BRANCH carried:
#     bash .dev/BRANCH/benchmarks/launch_device.sh MAIN BRANCH PAIRS ROUNDS
# 1. everything the processes import byte-compiled into PYTHONPYCACHEPREFIX (the device's NumPy has no .pyc files);
# 2. each tree's own Numba cache given the float32 variant of the march's stage first (as the full bench's march
#    section leaves the cache before its whole render: several variants of the march's kernel, work and sum);
# 3. benchmarks/whole_render_ab.py: the float64 caches filled, PAIRS rounds of main, branch, branch, main, outputs
#    hashed;
# 4. benchmarks/volumetrics_fresh.py, one render in a fresh process, ROUNDS times main then branch (the stage's
#    pieces, the loads ahead against the march's start);
# 5. benchmarks/march_launch_ab.py on the branch: bands, one call, one watched launch in one process.
set -e
MAIN=$1 BRANCH=$2 PAIRS=${3:-5} ROUNDS=${4:-3}
source $(dirname "$0")/device_ab_env.sh
F32='import dataclasses
from vlref.ahead import compile_stage
from vlref.bench import bench_scene
s = bench_scene(320, 180, 64, "four", 1024)
compile_stage("march", s.replace(render=dataclasses.replace(s.render, precision="float32")))'
T0=$(date +%s)
(cd $ROOT/.dev/$MAIN && PYTHONPATH=$ROOT/.dev/$MAIN:/tmp/site NUMBA_CACHE_DIR=/tmp/wrab/a python3 -c "$F32") &
(cd $ROOT/.dev/$BRANCH && PYTHONPATH=$ROOT/.dev/$BRANCH:/tmp/site NUMBA_CACHE_DIR=/tmp/wrab/b python3 -c "$F32") &
wait
echo "float32 march stage compiled in both caches: $(( $(date +%s) - T0 )) s"
python3 $ROOT/.dev/$BRANCH/benchmarks/whole_render_ab.py $OUT $PAIRS $ROOT/.dev/$MAIN $ROOT/.dev/$BRANCH /tmp/wrab
for i in $(seq $ROUNDS); do
    for t in main:$MAIN:a branch:$BRANCH:b; do
        IFS=: read label tree cache <<< "$t"
        echo "== volumetric pieces, $label, fresh process $i"
        (cd $ROOT/.dev/$tree && PYTHONPATH=$ROOT/.dev/$tree:/tmp/site NUMBA_CACHE_DIR=/tmp/wrab/$cache \
            python3 $ROOT/.dev/$BRANCH/benchmarks/volumetrics_fresh.py 1) | tail -1
    done
done | tee $OUT/pieces.txt
(cd $ROOT/.dev/$BRANCH && PYTHONPATH=$ROOT/.dev/$BRANCH:/tmp/site NUMBA_CACHE_DIR=/tmp/wrab/b \
    python3 benchmarks/march_launch_ab.py $OUT/launch.json 1920 1080 64 3 16) | tee $OUT/launch.txt
