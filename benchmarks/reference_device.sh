# The reference against main and Mitsuba 3 in one device call (BENCHMARKS.md, "The reference at Mitsuba's warm 1024
# spp launch"). Run from the lead's checkout root with this tree in .dev/TREE, main in .dev/MAIN, optionally an
# earlier state of this tree in .dev/PREV, and the Mitsuba bundle in .dev/mits.tar.xz
# (benchmarks/mitsuba_device.sh):
#     bash .dev/TREE/benchmarks/reference_device.sh TREE MAIN [PREV]
set -u
T=$PWD/.dev/$1 M=$PWD/.dev/$2 P=${3:+$PWD/.dev/$3} OUT=${OUT:-/tmp/out}
eval "$(bash benchmarks/mitsuba_device.sh unpack)"
export PYTHONUNBUFFERED=1
ab() {  # tree dir, tag, cache, settings
  (cd $1 && NUMBA_CACHE_DIR=$3 PYTHONPATH=$1 python3 benchmarks/reference_ab.py --tag $2 --repeats 9 --one-thread \
     --vlref $4)
}
MS=1/1/3,5e-1/1/3,1/1/7 TS=1/1/3,5e-1/1/3,7e-1/1/3,1/1/7
start=$(date +%s)
ab $M main /tmp/nc_main $MS > $OUT/warm_main.txt 2>&1 & ab $T tree /tmp/nc_tree $TS > $OUT/warm_tree.txt 2>&1 &
if [ -n "$P" ]; then ab $P prev /tmp/nc_prev $TS > $OUT/warm_prev.txt 2>&1 & fi
wait
echo "cold compiles (in parallel): $(( $(date +%s) - start )) s" | tee -a $OUT/ab.txt
order=("$M main /tmp/nc_main $MS" "$T tree /tmp/nc_tree $TS" "$T tree /tmp/nc_tree $TS" "$M main /tmp/nc_main $MS")
[ -n "$P" ] && order=("$M main /tmp/nc_main $MS" "$P prev /tmp/nc_prev $TS" "$T tree /tmp/nc_tree $TS"
                      "$T tree /tmp/nc_tree $TS" "$P prev /tmp/nc_prev $TS" "$M main /tmp/nc_main $MS")
for x in "${order[@]}"; do ab $x >> $OUT/ab.txt 2>&1; done
cd $T
for n in 16 1; do NUMBA_CACHE_DIR=/tmp/nc_tree PYTHONPATH=$T python3 benchmarks/reference_frame_split.py --threads $n \
  >> $OUT/frame_split.txt 2>&1; done
NUMBA_CACHE_DIR=/tmp/nc_tree PYTHONPATH=$T:/tmp/mits/site python3 benchmarks/mitsuba_ratio.py --width 80 --height 45 \
  --spp 1024,1024,4096 --mitsuba-budget 20 --repeats 3 --vlref 1/1/7,1/1/3,5e-1/1/3,3e-1/1/3,7e-1/1/3,2/1/3 \
  --out $OUT/m80.json > $OUT/m80.txt 2>&1
echo "all: $(( $(date +%s) - start )) s" >> $OUT/ab.txt
