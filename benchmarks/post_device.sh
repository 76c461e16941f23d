#!/bin/bash
# Device A/B of the radial and the bilateral blur (BENCHMARKS.md, "The radial and the bilateral blur: where their time
# goes on the device"): a main tree against this one on the same machine. Run from the checkout root where both trees sit, with the wheels installed in
# /tmp/site and the environment of the device calls:
#   bash .dev/TREE/benchmarks/post_device.sh .dev/MAIN .dev/TREE OUTDIR
# Writes OUTDIR/cpu.txt, post_ab.jsonl (benchmarks/post_ab.py's radial blur of both trees in fresh processes, main,
# tree, tree, main, tree, main), radial.json (benchmarks/radial_variants.py: every radial variant in one process, then
# main and tree at 1, 2, 4, 8 and 16 threads) and blur.json (benchmarks/blur_variants.py, every bilateral variant in
# one process).
set -u
M=$(cd "$1" && pwd); T=$(cd "$2" && pwd); O=$(mkdir -p "$3" && cd "$3" && pwd)
RADIAL=${RADIAL:-"main tree fixed_rows first_columns no_rows"}
BLUR=${BLUR:-"tree blocks1 no_div"}
{ lscpu; cat /sys/kernel/mm/transparent_hugepage/enabled; python3 -c "import numba, numpy, sys; print(sys.version, numpy.__version__, numba.__version__)"; } > "$O/cpu.txt" 2>&1
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
export PYTHONPYCACHEPREFIX=/tmp/pyc
python3 -m compileall -q -j 0 "$SP/numpy" "$SP/numba" "$SP/llvmlite" "$SP/scipy" "$SP/yaml" "$STD" "$M/vlref" "$T/vlref" /tmp/site > /dev/null 2>&1
run() { (cd "$T" && PYTHONPATH=$T:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$1 python3 "${@:2}"); }
for n in $RADIAL; do run rv benchmarks/radial_variants.py warm /tmp/rv "$n" --main "$M/vlref/post/radial.py" & done
for n in $BLUR; do run bv benchmarks/blur_variants.py warm /tmp/bv "$n" --main "$M/vlref/post/blur.py" & done
for label in main tree; do
  D=$M; [ $label = tree ] && D=$T
  (cd "$D" && PYTHONPATH=$D:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$label python3 "$T/benchmarks/post_ab.py" warm $label --only radial_blur_64) &
done
wait
echo "warm done $(date -u +%T)" >&2
for label in main tree tree main tree main; do
  D=$M; [ $label = tree ] && D=$T
  (cd "$D" && PYTHONPATH=$D:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$label python3 "$T/benchmarks/post_ab.py" time $label --only radial_blur_64 --repeats 5)
done > "$O/post_ab.jsonl" 2>&1
echo "post_ab done $(date -u +%T)" >&2
run rv benchmarks/radial_variants.py time /tmp/rv $RADIAL --main "$M/vlref/post/radial.py" --rounds 3 > "$O/radial.json" 2> "$O/radial.err"
run rv benchmarks/radial_variants.py time /tmp/rv main tree --main "$M/vlref/post/radial.py" --rounds 1 --scaling 1,2,4,8,16 > "$O/scaling.json" 2>> "$O/radial.err"
echo "radial done $(date -u +%T)" >&2
run bv benchmarks/blur_variants.py time /tmp/bv $BLUR --main "$M/vlref/post/blur.py" --rounds 6 > "$O/blur.json" 2> "$O/blur.err"
echo "blur done $(date -u +%T)" >&2
cat "$O/post_ab.jsonl"
python3 -c "
import json
for f in ('radial', 'scaling', 'blur'):
    try:
        d = json.load(open('$O/' + f + '.json'))
    except ValueError:
        print(f, 'no result'); continue
    print(f, d.get('same_bits_as_first', d.get('sha256_hv')), json.dumps(d['medians']), json.dumps(d.get('scaling_ms', {})))"
