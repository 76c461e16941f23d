#!/bin/bash
# Device A/B of the bilateral blur (BENCHMARKS.md, "The bilateral blur: both axes in one kernel, the sums opened and
# closed in the taps"): a main tree against this one on the same machine. Run from the checkout root where both
# trees sit, with the wheels installed in /tmp/site and the environment COMMON to the device calls:
#   bash .dev/TREE/benchmarks/blur_device.sh .dev/MAIN .dev/TREE OUTDIR
# Writes OUTDIR/cpu.txt, post_ab.jsonl (benchmarks/post_ab.py of both trees in fresh processes, main, tree, tree,
# main) and variants.json (benchmarks/blur_variants.py, every variant in one process).
set -u
M=$(cd "$1" && pwd); T=$(cd "$2" && pwd); O=$(mkdir -p "$3" && cd "$3" && pwd)
VARIANTS=${VARIANTS:-"tree main ymm planes512 blocks1 exp_ymm frame no_exp"}
{ lscpu; cat /sys/kernel/mm/transparent_hugepage/enabled; python3 -c "import numba, numpy, sys; print(sys.version, numpy.__version__, numba.__version__)"; } > "$O/cpu.txt" 2>&1
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
export PYTHONPYCACHEPREFIX=/tmp/pyc
python3 -m compileall -q -j 0 "$SP/numpy" "$SP/numba" "$SP/llvmlite" "$SP/scipy" "$SP/yaml" "$STD" "$M/vlref" "$T/vlref" /tmp/site > /dev/null 2>&1 &
for n in $VARIANTS; do
  (cd "$T" && PYTHONPATH=$T:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-bv python3 benchmarks/blur_variants.py warm /tmp/bv "$n" --main "$M/vlref/post/blur.py") &
done
for label in main tree; do
  D=$M; [ $label = tree ] && D=$T
  (cd "$D" && PYTHONPATH=$D:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$label python3 "$T/benchmarks/post_ab.py" warm $label --only bilateral_blur_hv) &
done
wait
echo "warm done $(date -u +%T)" >&2
for label in main tree tree main; do
  D=$M; [ $label = tree ] && D=$T
  (cd "$D" && PYTHONPATH=$D:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$label python3 "$T/benchmarks/post_ab.py" time $label --only bilateral_blur_hv --repeats 9)
done > "$O/post_ab.jsonl" 2>&1
echo "post_ab done $(date -u +%T)" >&2
cd "$T" && PYTHONPATH=$T:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-bv python3 benchmarks/blur_variants.py time /tmp/bv $VARIANTS --main "$M/vlref/post/blur.py" --rounds 8 > "$O/variants.json" 2> "$O/variants.err"
echo "variants done $(date -u +%T)" >&2
cat "$O/post_ab.jsonl"; python3 -c "import json; d=json.load(open('$O/variants.json')); print(d['sha256_hv']); print(d['medians'])"
