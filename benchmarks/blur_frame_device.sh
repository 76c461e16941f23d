#!/bin/bash
# One device call for BENCHMARKS.md "The bilateral blur's divisions, its output, and the reference's frame": the post
# A/B of benchmarks/post_device.sh (PASSES, BLUR, REPEATS, ROUNDS as there; RADIAL empty) and the reference's frame
# alone (benchmarks/prepare_frame_ab.py, fresh processes main, tree, tree, main), a main tree against this one.
# Run from the checkout root where both trees sit, with the wheels in /tmp/site and the device calls' environment:
#   bash .dev/TREE/benchmarks/blur_frame_device.sh .dev/MAIN .dev/TREE OUTDIR
set -u
M=$(cd "$1" && pwd); T=$(cd "$2" && pwd); O=$(mkdir -p "$3" && cd "$3" && pwd)
export PYTHONPYCACHEPREFIX=/tmp/pyc
frame() { (cd "$1" && PYTHONPATH=$1:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$2 python3 "$T/benchmarks/prepare_frame_ab.py" --tag $2 "${@:3}"); }
frame "$M" main --calls 1 > /dev/null 2>&1 &
frame "$T" tree --calls 1 > /dev/null 2>&1 &
wait
echo "frames compiled $(date -u +%T)" >&2
RADIAL= bash "$T/benchmarks/post_device.sh" "$M" "$T" "$O"
for label in main tree tree main; do
  D=$M; [ $label = tree ] && D=$T
  frame "$D" $label --calls ${CALLS:-300}
done > "$O/frame_ab.jsonl" 2>&1
echo "frames done $(date -u +%T)" >&2
cat "$O/frame_ab.jsonl"
