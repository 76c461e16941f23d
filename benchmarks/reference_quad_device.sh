# The reference's quadrature kernel without its per-evaluation calls, against main, in one device call (BENCHMARKS.md,
# "The integrand compiled into the quadrature's loop"). Run from the lead's checkout root with this tree in .dev/TREE,
# main in .dev/MAIN and the Mitsuba bundle in .dev/mitsuba-bundle; results under $OUT:
#     bash .dev/TREE/benchmarks/reference_quad_device.sh TREE MAIN
set -u
T=$PWD/.dev/$1 M=$PWD/.dev/$2 OUT=${OUT:-/tmp/out} AB=$PWD/.dev/$1/benchmarks/reference_call_ab.py
export PYTHONUNBUFFERED=1
(nproc; lscpu | grep -E "Model name|Thread|Core|Socket|NUMA node\(s\)"
 python3 -c "import numba, numpy; print('numba', numba.__version__, 'numpy', numpy.__version__)") > $OUT/machine.txt 2>&1
start=$(date +%s)
python3 .dev/mitsuba-bundle/unpack.py .dev/mitsuba-bundle /tmp/mits > /dev/null 2>&1 &
ab() {  # tree dir, tag, Numba cache, arguments
  (cd $1 && NUMBA_CACHE_DIR=$3 PYTHONPATH=$1 python3 $AB --tag $2 "${@:4}")
}
cold() {  # a cold process (compiles), its wall time in ms
  local s=$(date +%s%N); ab "$@"; echo "{\"cold_process_ms\": $(( ($(date +%s%N) - s) / 1000000 ))}"
}
V=7e-1/1/3,1/1/3
cold $M main /tmp/nc_main --vlref $V --rounds 1 --calls 3 --hashes > $OUT/warm_main.txt 2>&1 &
cold $T tree /tmp/nc_tree --vlref $V --rounds 1 --calls 3 --hashes > $OUT/warm_tree.txt 2>&1 &
wait
echo "cold compiles in parallel, Mitsuba unpacked: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
for x in "$M main /tmp/nc_main" "$T tree /tmp/nc_tree" "$T tree /tmp/nc_tree" "$M main /tmp/nc_main"; do
  ab $x --vlref $V --rounds 3 --calls 20 >> $OUT/ab.txt 2>&1
done
for x in "$M main /tmp/nc_main" "$T tree /tmp/nc_tree" "$T tree /tmp/nc_tree" "$M main /tmp/nc_main"; do
  NUMBA_NUM_THREADS=1 ab $x --vlref 7e-1/1/3 --rounds 1 --calls 10 >> $OUT/ab1.txt 2>&1
done
echo "A/B: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
(cd $T && NUMBA_CACHE_DIR=/tmp/nc_tree PYTHONPATH=$T:/tmp/mits/site LD_LIBRARY_PATH=/tmp/mits/lib \
  python3 benchmarks/mitsuba_ratio.py --width 80 --height 45 --spp 1024,1024 --mitsuba-budget 10 --repeats 5 \
  --vlref 7e-1/1/3,1/1/3 --out $OUT/m80.json > $OUT/m80.txt 2>&1)
echo "all: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
