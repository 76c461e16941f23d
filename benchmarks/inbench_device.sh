# The ray cast inside the bench's process, on the device (BENCHMARKS.md, "The camera ray cast inside the bench's
# process, and twice as fast"): run in the tree, after the wheels are installed and PYTHONPATH and $OUT are set.
# One process with a fresh Numba cache (as a full `vlref bench` runs), then three with the cache it filled.
SP=$(python3 -c "import numpy, os; print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig; print(sysconfig.get_paths()['stdlib'])")
export PYTHONPYCACHEPREFIX=/tmp/pyc
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD vlref /tmp/site benchmarks
{ nproc; lscpu | head -25; grep . /sys/kernel/mm/transparent_hugepage/enabled /sys/kernel/mm/transparent_hugepage/defrag \
  /sys/fs/cgroup/cpu.max /proc/sys/kernel/numa_balancing; uname -r; uptime; } > $OUT/machine.txt 2>&1
S=march,scaling,raycast,shadow_maps
export NUMBA_CACHE_DIR=/tmp/nc-inbench
for run in "cold raycast $S" "warm-each each $S" "warm-raycast raycast $S" "fresh each raycast,shadow_maps"; do
  set -- $run
  start=$(date +%s.%N)
  python3 benchmarks/inbench_raycast.py $1 --probe $2 --sections $3 >> $OUT/probes.jsonl 2>> $OUT/err.txt
  echo "$1 rc=$? $(python3 -c "print(round($(date +%s.%N) - $start, 1))") s" >> $OUT/machine.txt
done
