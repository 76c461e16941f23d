# `vlref reference` against Mitsuba 3 on the device (BENCHMARKS.md, "The reference against Mitsuba 3, rerun").
#
#     bash benchmarks/mitsuba_device.sh bundle          # here: .dev/mits.tar.xz (30 MB), from PyPI
#     bash benchmarks/mitsuba_device.sh run [RUNS...]   # on the device, from the tree's root: one
#                                                       # benchmarks/mitsuba_ratio.py process per RUNS word (default
#                                                       # "1 2"), reports in $OUT/m80_RUN.{txt,json}
#     eval "$(bash benchmarks/mitsuba_device.sh unpack)"  # on the device: the bundle in /tmp/mits, and the
#                                                       # environment Mitsuba needs (reference_device.sh and
#                                                       # reference_call_device.sh), with /tmp/mits/site to add to
#                                                       # PYTHONPATH
#
# The device has no network and its venv no Mitsuba: the bundle is Mitsuba 3.6.4 and Dr.Jit 1.0.5 (Python 3.12 wheels)
# unpacked, less the variants the ratio does not load (CUDA, mono, spectral), within the 64 MiB the run tool carries
# beside the tree (carry [".dev/mits.tar.xz"]). Dr.Jit's LLVM backend needs a libLLVM: the device's own
# (Ubuntu 24.04, /usr/lib/x86_64-linux-gnu/libLLVM-17.so.1) serves, so none is carried.
set -eu
case "${1:-}" in
bundle)
  tmp=$(mktemp -d)
  pip download -q --only-binary=:all: --no-deps --python-version 3.12 --platform manylinux2014_x86_64 \
    --platform manylinux_2_17_x86_64 -d "$tmp" mitsuba==3.6.4 drjit==1.0.5
  mkdir -p "$tmp/site" .dev
  for w in "$tmp"/*.whl; do python3 -m zipfile -e "$w" "$tmp/site"; done
  (cd "$tmp/site" && rm -rf mitsuba/cuda_* mitsuba/llvm_ad_mono* mitsuba/llvm_ad_spectral* mitsuba/scalar_spectral* \
     mitsuba/include mitsuba/mitsuba_stubs mitsuba/cmake ./*.dist-info)
  tar cf - -C "$tmp" site | xz -6 -T0 > .dev/mits.tar.xz
  rm -rf "$tmp"
  ls -l .dev/mits.tar.xz
  ;;
unpack)
  [ -d /tmp/mits/site ] || { mkdir -p /tmp/mits && tar xJf .dev/mits.tar.xz -C /tmp/mits; }
  echo "export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-17.so.1}"
  ;;
run)
  shift
  OUT=${OUT:?the folder for the reports}
  eval "$(bash "$0" unpack)"
  export PYTHONPATH=$PWD:/tmp/mits/site NUMBA_CACHE_DIR=${NUMBA_CACHE_DIR:-/tmp/nc} PYTHONUNBUFFERED=1
  lscpu | grep -E "Model name|^CPU\(s\)"
  for run in ${*:-1 2}; do
    python3 benchmarks/mitsuba_ratio.py --width 80 --height 45 --spp 1024,1024,4096,16384 --mitsuba-budget 20 \
      --repeats 3 --one-thread --vlref 1e-4/512/15,1/1/3,5e-1/1/3,3e-1/1/3,7e-1/1/3,2/1/3 \
      --out "$OUT/m80_$run.json" > "$OUT/m80_$run.txt" 2>&1
    grep -E "^(vlref|mitsuba|same error)" "$OUT/m80_$run.txt"
  done
  ;;
*)
  echo "usage: $0 bundle | unpack | run [RUNS...]" >&2
  exit 2
  ;;
esac
