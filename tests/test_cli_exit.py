"""How the `vlref` program's process ends after `vlref render` (vlref.cli.commands.exit_at_once): the exit code,
stdout and stderr flushed, atexit handlers run (a temporary folder's finalizer), the outputs complete and equal
to an in-process render, and the interpreter's tear-down skipped; the interpreter's own exit where a non-daemon
thread still runs. Each case is one fresh `vlref` process (about 2 s with a warm cache)."""

import subprocess
import sys
from pathlib import Path

import numpy as np

from vlref.io.images import read_image
from vlref.render import render
from vlref.scene import load_scene

TINY = ["render.width=16", "render.height=9", "render.steps=4"]

PROGRAM = r"""
import os, sys, tempfile, threading, time
from pathlib import Path
held = tempfile.TemporaryDirectory(prefix="vlref-exit-test-")  # removed by its finalizer at exit (atexit)
print("held", held.name)  # stdout is a pipe: block-buffered, written only when flushed


# the interpreter's own exit runs threading's exit hooks (where concurrent.futures registers) before tearing
# the modules down; exit_at_once, with no other thread running, has nothing for them to do and skips both
threading._register_atexit(lambda: os.write(2, b"torn down\n"))
if sys.argv[1] == "--thread":  # a non-daemon thread that outlives the command: the interpreter waits for it
    sys.argv.pop(1)
    target = Path(sys.argv.pop(1))

    def outlive_the_command():
        while threading.main_thread().is_alive():  # until the interpreter's exit stops the main thread
            time.sleep(0.02)
        target.write_text("joined")

    threading.Thread(target=outlive_the_command).start()
from vlref.cli import main
sys.exit(main())
"""


def _vlref(*args: str) -> subprocess.CompletedProcess:
    sets = [a for s in TINY for a in ("--set", s)]
    return subprocess.run([sys.executable, "-c", PROGRAM, *args, *sets], capture_output=True, text=True)


def test_a_render_ends_at_once_with_everything_the_exit_must_do(tmp_path):
    out = tmp_path / "out"
    proc = _vlref("render", "pillars", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    held = Path(proc.stdout.split("held ", 1)[1].split()[0])
    assert not held.exists()  # the atexit handlers ran
    assert f"wrote {out}" in proc.stderr  # stderr's summary line came out
    assert "torn down" not in proc.stderr  # the tear-down was skipped
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no temporary folder left beside it
    buffers = render(load_scene("pillars", TINY)).buffers
    for name in ("final", "inscatter", "transmittance", "depth"):
        written = read_image(out / f"{name}.exr")
        expected = buffers[name].astype(np.float32)
        assert np.array_equal(written.reshape(expected.shape), expected), name  # complete files, same values
    assert (out / "final.png").stat().st_size > 0


def test_bad_input_keeps_exit_code_2_and_its_message():
    proc = _vlref("render", "no_such_scene_file.toml")
    assert proc.returncode == 2
    assert "vlref: error:" in proc.stderr and "no_such_scene_file.toml" in proc.stderr
    assert "torn down" not in proc.stderr


def test_a_running_non_daemon_thread_leaves_the_exit_to_the_interpreter(tmp_path):
    joined = tmp_path / "joined.txt"
    proc = _vlref("--thread", str(joined), "render", "pillars", "-q", "-o", str(tmp_path / "out"))
    assert proc.returncode == 0, proc.stderr
    assert joined.read_text() == "joined"  # the interpreter stopped the main thread, then waited for this one
    assert "torn down" in proc.stderr  # and tore the modules down as usual
