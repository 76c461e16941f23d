"""Every output is deterministic: the same scene gives the same bits for 1, 2 and 16 threads.

Numba launches NUMBA_NUM_THREADS worker threads whatever the core count, so a subprocess with 16
threads really runs 16-way parallel kernels even on a 2-core machine.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

SCRIPT = """
import sys, numba, numpy as np
from vlref.render import render
from vlref.scene import load_scene
scene = load_scene(sys.argv[1], ["render.width=40", "render.height=24", "render.steps=8",
                                 f'render.technique="{sys.argv[2]}"'])
numba.set_num_threads(int(sys.argv[3]))
b = render(scene, stages=True).buffers
np.savez(sys.argv[4], **{k: v for k, v in b.items()})
"""


def _render(tmp_path, scene, technique, threads):
    out = tmp_path / f"{scene}_{technique}_{threads}.npz"
    env = dict(os.environ, NUMBA_NUM_THREADS="16")
    subprocess.run([sys.executable, "-c", SCRIPT, scene, technique, str(threads), str(out)], env=env, check=True)
    return np.load(out)


@pytest.mark.parametrize("scene, technique", [("coloured_lights", "physical"), ("cage", "killzone"),
                                              ("window", "slightlymad")])
def test_same_bits_for_1_2_and_16_threads(tmp_path, scene, technique):
    runs = [_render(tmp_path, scene, technique, n) for n in (1, 2, 16)]
    assert set(runs[0].files) == set(runs[1].files) == set(runs[2].files)
    for name in runs[0].files:
        for other in runs[1:]:
            assert np.array_equal(runs[0][name], other[name], equal_nan=True), name
