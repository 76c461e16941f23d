"""glibc's malloc keeps freed memory in the render program's process (vlref.allocator)."""

import json
import subprocess
import sys

import pytest

_GROWING = """
import json, resource, sys
import numpy as np
from vlref.allocator import keep_freed_memory
from vlref.cli.commands import program_command
took = None
if sys.argv[1] == "direct":
    took = keep_freed_memory()
elif sys.argv[1] == "program":  # the render program's own process
    program_command("render")
def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt
start = faults()
for kib in range(256, 4096, 256):  # each larger than any freed before it: glibc's adaptive threshold never covers it
    a = np.ones(kib << 7)  # kib KiB of float64, every page written (below 4 MiB: NumPy asks no huge pages)
    del a
print(json.dumps({"took": took, "faults": faults() - start}))
"""


def _growing(mode: str) -> dict:
    out = subprocess.run([sys.executable, "-c", _GROWING, mode], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mallopt is glibc's (Linux)")
def test_freed_buffers_are_reused_instead_of_faulted_in_again():
    # 30 MiB written in buffers of 0.25..3.75 MiB, each freed before the next: by default each is a fresh mapping
    # (~7 700 faults of 4 KiB); with the settings the heap's freed top is reused and only its growth faults in
    # (3.75 MiB: ~1 000)
    default, kept, program = _growing("none"), _growing("direct"), _growing("program")
    assert kept["took"] is True
    assert default["faults"] > 7_000
    assert kept["faults"] < 2_000 and program["faults"] < 2_000
