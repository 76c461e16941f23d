#!/usr/bin/env bash
# The WebGPU port on the device machine's GPU (NVIDIA H100, Vulkan): every variant at 160x90 and 1280x720 and the
# conformance suite, judged by `vlref verdict` (kz_check.py). Run from the project root of a copy carried to the
# device with .whl (wgpu and the other wheels) and .device-libs (the Vulkan loader and GL dispatch library the
# NVIDIA ICD needs but the device image lacks); tables go to $OUT (default: ./device-out).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
WHEELS="${WHEELS:-$ROOT/.whl}"
LIBS="${LIBS:-$ROOT/.device-libs}"
OUT="${OUT:-$ROOT/device-out}"
mkdir -p "$OUT" /tmp/kz-site
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/kz-site "$WHEELS"/*.whl
export PYTHONPATH="$ROOT:/tmp/kz-site" LD_LIBRARY_PATH="$LIBS/lib:${LD_LIBRARY_PATH:-}" XDG_RUNTIME_DIR=/tmp \
       NUMBA_CACHE_DIR=/tmp/kz-numba PYTHONUNBUFFERED=1
cd "$ROOT"
python3 -c "import sys; sys.path.insert(0, 'ports/wgpu'); import kz_port; print(kz_port.device()[0].info)"
check() {   # kz_check ARGS... > $OUT/NAME.md (rows as they are judged), stderr to NAME.log
    local name=$1; shift
    python3 ports/wgpu/kz_check.py "$@" > "$OUT/$name.md" 2> "$OUT/$name.log" \
        || echo "kz_check $*: not everything judged as expected" >> "$OUT/$name.log"
}
check variants_160x90 --size 160x90 --set render.steps=16 -o /tmp/kz-160x90
check suite --suite -o /tmp/kz-suite
check variants_1280x720 --size 1280x720 --set render.steps=16 -o /tmp/kz-1280x720
