#!/usr/bin/env bash
# Scale-out figures of BENCHMARKS.md on the 16-core device: a 1280x720 reference and a 1080p golden build,
# in-process and on LocalClusters of 1, 4 and 16 workers (workers x Numba threads = 16).
#
# The device has NumPy, Numba and SciPy but not Dask, OpenEXR or tqdm: carry their wheels (built here with
#   pip download -d wheels --only-binary=:all: --python-version 3.12 --platform manylinux2014_x86_64 \
#       "dask[distributed]>=2024.1" "OpenEXR>=3.2" "tqdm>=4.60"
# ) and run, from the repository root:
#   WHEELS=wheels bash benchmarks/scale_device.sh reference   # writes scale16_reference.json, prints a table
#   SKIP_INSTALL=1 bash benchmarks/scale_device.sh golden     # writes scale16_golden.json
# (each section is one command of a few minutes: 4 reference runs of ~1.5 min, 4 suite builds; no
# argument runs both)
# Set SITE (default /tmp/site) to install elsewhere, SKIP_INSTALL=1 when /tmp/site is filled already.
set -euo pipefail
cd "$(dirname "$0")/.."
SITE="${SITE:-/tmp/site}"
if [ -z "${SKIP_INSTALL:-}" ]; then
    # every carried wheel but NumPy's (OpenEXR pulls one; the device's own NumPy must stay, Numba is built for it)
    python3 -m pip install -q --no-index --no-deps --target "$SITE" \
        $(ls "${WHEELS:?set WHEELS to the folder of wheels}"/*.whl | grep -v '/numpy-')
fi
export PYTHONPATH="$PWD:$SITE${PYTHONPATH:+:$PYTHONPATH}"
export NUMBA_CACHE_DIR="${NUMBA_CACHE_DIR:-/tmp/nc}"
python3 -c "import dask, distributed, OpenEXR, tqdm; print('dask', dask.__version__, 'OpenEXR', OpenEXR.__version__)"
WHAT="${1:-reference,golden}"
python3 benchmarks/scale.py --schedulers none,local:1,local:4,local:16 --what "$WHAT" \
    --ref-size 1280x720 --rel-tol 1e-4 --tile-rows 16 --golden-size 1920x1080 -o "scale16_${WHAT/,/_}.json"
