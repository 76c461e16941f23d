# The device's set-up for an A/B of two trees (sourced, with MAIN and BRANCH set, in the lead's checkout): the wheels
# installed into /tmp/site, the environment, everything the processes import byte-compiled into PYTHONPYCACHEPREFIX
# (the device's NumPy has no .pyc files), the machine described.
python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site LD_LIBRARY_PATH=$PWD/.device-libs/lib:$LD_LIBRARY_PATH XDG_RUNTIME_DIR=/tmp \
       PYTHONUNBUFFERED=1 PYTHONPYCACHEPREFIX=/tmp/pyc
ROOT=$PWD
SP=$(python3 -c "import numpy,os;print(os.path.dirname(os.path.dirname(numpy.__file__)))")
STD=$(python3 -c "import sysconfig;print(sysconfig.get_paths()['stdlib'])")
python3 -m compileall -q -j 0 $SP/numpy $SP/numba $SP/llvmlite $SP/scipy $SP/yaml $STD $ROOT/.dev/$MAIN/vlref \
    $ROOT/.dev/$BRANCH/vlref /tmp/site > /dev/null 2>&1 || true
lscpu | grep -E "Model name|^CPU\(s\)|Thread" ; nproc; python3 -c "import sys, numba, numpy; print(sys.version, numba.__version__, numpy.__version__)"
