"""SHA-256 of every buffer of every golden-suite entry (81 entries: every bundled scene under every technique that
applies, at the suite's 64x36x8), to show that a change keeps the bits of every technique, not only within the
suite's float32 tolerance (BENCHMARKS.md, "The cold first render: no Python entry for the helpers").

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-old python3 benchmarks/golden_hashes.py > before.json   # the old tree
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-new python3 benchmarks/golden_hashes.py before.json     # exit 1 on a change
"""

import hashlib
import json
import sys

import numpy as np

from vlref.oracle.golden import load_suite, suite_entries
from vlref.render import render
from vlref.scene import load_scene
from vlref.sequence import render_sequence


def _buffers(entry) -> dict:
    """Every buffer of ``entry``'s render, as :func:`vlref.oracle.golden.render_entry` renders it (a temporal froxel
    entry: frames 0..F in sequence, the last kept)."""
    scene = load_scene(entry.scene, entry.overrides)
    if scene.render.technique == "froxel" and scene.techniques.froxel.temporal:
        return list(render_sequence(scene, range(scene.render.frame + 1)))[-1][1].buffers
    return render(scene).buffers


def digests() -> dict:
    """``{entry name: {buffer: sha256 of its bytes, dtype and shape}}``."""
    return {entry.name: {name: hashlib.sha256(np.ascontiguousarray(a).tobytes() + repr((a.dtype.str, a.shape)).encode())
                         .hexdigest() for name, a in sorted(_buffers(entry).items())}
            for entry in suite_entries(load_suite())}


def main(before: str | None = None) -> int:
    now = digests()
    if before is None:
        print(json.dumps(now, indent=1))
        return 0
    old = json.loads(open(before).read())
    changed = [f"{e}/{b}" for e in sorted(set(old) | set(now)) for b in sorted(set(old.get(e, {})) | set(now.get(e, {})))
               if old.get(e, {}).get(b) != now.get(e, {}).get(b)]
    buffers = sum(len(v) for v in now.values())
    print(f"{len(now)} entries, {buffers} buffers; changed: {len(changed)}", *changed[:20], sep="\n")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
