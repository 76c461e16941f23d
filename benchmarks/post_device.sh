#!/bin/bash
# Device A/B of the post passes (BENCHMARKS.md, "The radial and the bilateral blur: where their time goes on the
# device"): a main tree against this one on the same machine. Run from the checkout root where both trees sit, with
# the wheels installed in /tmp/site and the environment of the device calls:
#   bash .dev/TREE/benchmarks/post_device.sh .dev/MAIN .dev/TREE OUTDIR
# Writes OUTDIR/cpu.txt; post_ab.jsonl: benchmarks/post_ab.py of both trees in fresh processes (main, tree, tree, main,
# tree, main) for each pass of PASSES; radial.json and scaling.json: benchmarks/radial_variants.py, the RADIAL variants
# in one process, then main and the tree at 1, 2, 4, 8 and 16 threads; blur.json: benchmarks/blur_variants.py, the
# BLUR variants in one process. An empty RADIAL or BLUR skips that part; REPEATS (post_ab.py) and ROUNDS (variants).
set -u
M=$(cd "$1" && pwd); T=$(cd "$2" && pwd); O=$(mkdir -p "$3" && cd "$3" && pwd)
PASSES=${PASSES-"radial_blur_64"}
RADIAL=${RADIAL-"main tree fixed_rows first_columns no_rows"}
BLUR=${BLUR-"tree blocks1 no_div"}
REPEATS=${REPEATS:-5}; ROUNDS=${ROUNDS:-3}
{ lscpu; cat /sys/kernel/mm/transparent_hugepage/enabled; python3 -c "import numba, numpy, sys; print(sys.version, numpy.__version__, numba.__version__)"; } > "$O/cpu.txt" 2>&1
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
export PYTHONPYCACHEPREFIX=/tmp/pyc
python3 -m compileall -q -j 0 "$SP/numpy" "$SP/numba" "$SP/llvmlite" "$SP/scipy" "$SP/yaml" "$STD" "$M/vlref" "$T/vlref" /tmp/site > /dev/null 2>&1
in_tree() { (cd "$1" && PYTHONPATH=$1:/tmp/site NUMBA_CACHE_DIR=/tmp/nc-$2 python3 "${@:3}"); }
for n in $RADIAL; do in_tree "$T" rv benchmarks/radial_variants.py warm /tmp/rv "$n" --main "$M/vlref/post/radial.py" & done
for n in $BLUR; do in_tree "$T" bv benchmarks/blur_variants.py warm /tmp/bv "$n" --main "$M/vlref/post/blur.py" & done
for p in $PASSES; do
  in_tree "$M" main "$T/benchmarks/post_ab.py" warm main --only "$p" &
  in_tree "$T" tree "$T/benchmarks/post_ab.py" warm tree --only "$p" &
done
wait
echo "warm done $(date -u +%T)" >&2
for p in $PASSES; do
  for label in main tree tree main tree main; do
    D=$M; [ $label = tree ] && D=$T
    in_tree "$D" $label "$T/benchmarks/post_ab.py" time $label --only "$p" --repeats "$REPEATS"
  done
done > "$O/post_ab.jsonl" 2>&1
echo "post_ab done $(date -u +%T)" >&2
if [ -n "$RADIAL" ]; then
  in_tree "$T" rv benchmarks/radial_variants.py time /tmp/rv $RADIAL --main "$M/vlref/post/radial.py" --rounds "$ROUNDS" > "$O/radial.json" 2> "$O/radial.err"
  in_tree "$T" rv benchmarks/radial_variants.py time /tmp/rv main tree --main "$M/vlref/post/radial.py" --rounds 1 --scaling 1,2,4,8,16 > "$O/scaling.json" 2>> "$O/radial.err"
  echo "radial done $(date -u +%T)" >&2
fi
if [ -n "$BLUR" ]; then
  in_tree "$T" bv benchmarks/blur_variants.py time /tmp/bv $BLUR --main "$M/vlref/post/blur.py" --rounds $((2 * ROUNDS)) > "$O/blur.json" 2> "$O/blur.err"
  echo "blur done $(date -u +%T)" >&2
fi
cat "$O/post_ab.jsonl"
python3 -c "
import json
for f in ('radial', 'scaling', 'blur'):
    try:
        d = json.load(open('$O/' + f + '.json'))
    except (OSError, ValueError):
        print(f, 'no result'); continue
    print(f, d.get('same_bits_as_first', d.get('sha256_hv')), json.dumps(d['medians']), json.dumps(d.get('scaling_ms', {})))"
