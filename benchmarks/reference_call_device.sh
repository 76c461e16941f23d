# The reference's whole call against main (also under OMP_WAIT_POLICY=passive, a probe), the frame's split and Mitsuba 3
# in one device call (BENCHMARKS.md, "The reference's fixed costs: one worker per thread, the frame without NumPy's
# generic paths"). Run from the lead's checkout root with this tree in .dev/TREE, main in .dev/MAIN and the Mitsuba
# bundle in .dev/mits.tar.xz (benchmarks/mitsuba_device.sh); results under $OUT:
#     bash .dev/TREE/benchmarks/reference_call_device.sh TREE MAIN
# PROBES=0 leaves out the OMP_WAIT_POLICY=passive probe and the frame's split; ONE_THREAD=1 adds an A/B on one Numba
# thread (BENCHMARKS.md, "The integrand compiled into the quadrature's loop"). warm_*.txt end with the cold process's
# wall time (both trees compile in parallel).
set -u
T=$PWD/.dev/$1 M=$PWD/.dev/$2 OUT=${OUT:-/tmp/out} AB=$PWD/.dev/$1/benchmarks/reference_call_ab.py
export PYTHONUNBUFFERED=1
(nproc; lscpu | grep -E "Model name|Thread|Core|Socket|NUMA node\(s\)"
 python3 -c "import numba, numpy; print('numba', numba.__version__, 'numpy', numpy.__version__)") > $OUT/machine.txt 2>&1
start=$(date +%s)
bash benchmarks/mitsuba_device.sh unpack > /dev/null &
ab() {  # tree dir, tag, Numba cache, arguments
  (cd $1 && NUMBA_CACHE_DIR=$3 PYTHONPATH=$1 python3 $AB --tag $2 "${@:4}")
}
cold() {  # a cold process (it compiles), then its wall time in ms
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
if [ "${ONE_THREAD:-0}" = 1 ]; then
  for x in "$M main /tmp/nc_main" "$T tree /tmp/nc_tree" "$T tree /tmp/nc_tree" "$M main /tmp/nc_main"; do
    NUMBA_NUM_THREADS=1 ab $x --vlref 7e-1/1/3 --rounds 1 --calls 10 >> $OUT/ab1.txt 2>&1
  done
fi
if [ "${PROBES:-1}" = 1 ]; then
  for x in "$T tree /tmp/nc_tree" "$M main /tmp/nc_main" "$M main /tmp/nc_main" "$T tree /tmp/nc_tree"; do
    OMP_WAIT_POLICY=passive ab $x --vlref $V --rounds 3 --calls 20 >> $OUT/ab.txt 2>&1
  done
fi
echo "A/B: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
if [ "${PROBES:-1}" = 1 ]; then
  for x in "$M /tmp/nc_main 16" "$T /tmp/nc_tree 16" "$T /tmp/nc_tree 1"; do
    set -- $x
    (echo "=== $1, $3 threads"; cd $1 && NUMBA_CACHE_DIR=$2 PYTHONPATH=$1 python3 $T/benchmarks/reference_frame_split.py \
       --threads $3 --repeats 30) >> $OUT/frame_split.txt 2>&1
  done
  echo "split: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
fi
eval "$(bash benchmarks/mitsuba_device.sh unpack)"
(cd $T && NUMBA_CACHE_DIR=/tmp/nc_tree PYTHONPATH=$T:/tmp/mits/site \
  python3 benchmarks/mitsuba_ratio.py --width 80 --height 45 --spp 1024,1024 --mitsuba-budget 10 --repeats 5 \
  --vlref 7e-1/1/3,1/1/3,5e-1/1/3 --out $OUT/m80.json > $OUT/m80.txt 2>&1)
echo "all: $(( $(date +%s) - start )) s" >> $OUT/machine.txt
