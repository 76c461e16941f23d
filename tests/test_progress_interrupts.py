"""Progress of long kernels and clean interrupts.

* The physical march is one launch, watched: progress while it runs, a signal stops it within a tile's time, and
  no launch is left running; a thread's launches run on one launch thread, kept between them; the quadrature
  reference reports progress once per band of rows. Neither the bands nor the order in which threads take tiles
  changes a bit of a result.
* SIGINT / SIGTERM during every long command (render, render --frames, reference, bias, sweep, golden
  build / verify, march, bench, warmup), in this process or on a ``--scheduler local:2`` cluster: one line
  ``vlref: interrupted``, exit 130 / 143, no traceback (nor from a child process), no output folder and no
  temporary file or folder left behind.
"""

import ctypes
import os
import signal
import subprocess
import sys
import threading
import time
import weakref
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import types

import vlref
from vlref import progress
from vlref.cli.commands import Interrupted, _interruptible
from vlref.progress import reporting, row_bands
from vlref.reference import quadrature, render_reference
from vlref.render import render
from vlref.scene import load_scene

# The child processes import the vlref this process imported (the installed one in CI: its kernels are cached).
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(Path(vlref.__file__).resolve().parents[1]),
                                                               os.environ.get("PYTHONPATH")) if p))


def test_row_bands_cover_the_rows_once_in_order_and_report_each_band():
    for height, bands in ((1, 64), (7, 3), (90, 64), (1000, 64), (5, 1)):
        calls = []
        with reporting(lambda done, total: calls.append((done, total))):
            got = list(row_bands(height, bands))
        assert got[0][0] == 0 and got[-1][1] == height
        assert all(a[1] == b[0] for a, b in zip(got, got[1:]))
        sizes = [y1 - y0 for y0, y1 in got]
        assert len(got) == min(height, bands) and min(sizes) >= 1 and max(sizes) - min(sizes) <= 1
        assert calls == [(y1, height) for _, y1 in got]
    for height, bands, multiple in ((1080, 64, 16), (1080, 17, 16), (19, 64, 16), (100, 3, 7), (5, 4, 1)):
        got = list(row_bands(height, bands, multiple))
        assert got[0][0] == 0 and got[-1][1] == height and all(a[1] == b[0] for a, b in zip(got, got[1:]))
        assert len(got) == min(-(-height // multiple), bands) and all(y0 % multiple == 0 for y0, _ in got)
        units = [-(-(y1 - y0) // multiple) for y0, y1 in got]  # the last band may end inside a unit
        assert min(units) >= 1 and max(units) - min(units) <= 1


def test_the_march_reports_progress_while_its_one_launch_runs(monkeypatch):
    """The march is one launch on a thread of its own (vlref.progress.watched): the calling thread reports the tasks
    handed out so far, in rows, every POLL_S; rows increase, stay short of the total until the launch has returned,
    and end at the total."""
    monkeypatch.setattr(progress, "POLL_S", 0.002)
    scene = load_scene("pillars", ["render.width=320", "render.height=180", "render.steps=200"])
    calls = []

    def launching() -> bool:
        return any(t.name == "vlref-launch" for t in threading.enumerate())

    before = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))  # 5.8 M samples a thread: above SAMPLES_WATCHED
    try:
        with reporting(lambda done, total: calls.append((done, total, launching()))):
            render(scene)
    finally:
        numba.set_num_threads(before)
    assert len(calls) >= 10 and calls[-1][:2] == (180, 180)
    assert all(total == 180 and 0 < done < 180 for done, total, _ in calls[:-1])
    assert all(a[0] < b[0] for a, b in zip(calls, calls[1:]))
    # the reports came while the launch's thread ran, the last one after it had ended
    assert all(c[2] for c in calls[:-1]) and not calls[-1][2] and not launching()


def test_a_signal_stops_the_march_within_a_tile_and_leaves_no_launch_running():
    """SIGINT while the main thread waits on the march's launch (a march of tens of seconds on two threads) raises
    KeyboardInterrupt within a fraction of a second: the counter is set past the last task, the kernel's threads end
    with the tile they hold, and only then does the exception go on. A march right after runs as usual."""
    scene = load_scene("pillars", ["render.width=640", "render.height=360", "render.steps=4096"])
    calls = []
    sent = []

    def listener(done, total):
        calls.append(done)
        if len(calls) == 2:  # the launch is running: signal this process from another thread
            sent.append(time.perf_counter())
            threading.Thread(target=os.kill, args=(os.getpid(), signal.SIGINT)).start()

    before = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        with pytest.raises(KeyboardInterrupt), reporting(listener):
            render(scene)
        stopped = time.perf_counter() - sent[0]
        assert not [t for t in threading.enumerate() if t.name == "vlref-launch"]
        small = render(load_scene("pillars", ["render.width=32", "render.height=18", "render.steps=8"]), stages=True)
    finally:
        numba.set_num_threads(before)
    # 4096 steps over 230 400 pixels: ~25 s on two threads; the stop waits for a tile (~0.5 M samples: ~0.02 s)
    assert stopped < 1.5 and calls[-1] < 180
    assert np.isfinite(small.buffers["final"]).all()


def test_watched_raises_the_launchs_error_and_lets_an_exception_go_on_only_once_the_launch_has_stopped():
    def failing():
        raise ValueError("from the launch")

    with pytest.raises(ValueError, match="from the launch"):
        progress.watched(failing, np.zeros(1, dtype=np.int64), 10, 10)
    taken, ended = np.full(1, 100, dtype=np.int64), []  # a tenth of the tasks handed out: the listener is called

    def endless():  # runs until the counter is past the last task
        while taken[0] < 1000:
            time.sleep(0.001)
        ended.append(int(taken[0]))

    def listener(done, total):
        raise RuntimeError("from the listener")

    with pytest.raises(RuntimeError, match="from the listener"), reporting(listener):
        progress.watched(endless, taken, 1000, 100)
    assert ended == [progress.EXHAUSTED]  # stopped by the counter, before the exception went on


def test_a_threads_launches_run_on_one_launch_thread_kept_between_them_which_ends_with_that_thread(monkeypatch):
    """Every watched launch of one thread runs on the same launch thread (a daemon, named vlref-launch while it runs
    a launch, vlref-launch (idle) after): its OpenMP team is made once. Another thread's launches run on a launch
    thread of their own, which ends once that thread has ended; a forked child (another pid) gets a new one."""
    seen = []

    def launch():
        seen.append((threading.get_ident(), threading.current_thread().name))

    def watch():
        progress.watched(launch, np.zeros(1, dtype=np.int64), 1, 1)

    watch()
    watch()
    assert seen[0] == seen[1] and seen[0][0] != threading.get_ident() and seen[0][1] == "vlref-launch"
    kept = {t.ident: t for t in threading.enumerate()}[seen[0][0]]
    assert kept.daemon and kept.name == "vlref-launch (idle)"
    other = threading.Thread(target=watch)
    other.start()
    other.join()
    assert seen[2][0] not in (seen[0][0], threading.get_ident())
    deadline = time.monotonic() + 10
    while any(t.ident == seen[2][0] for t in threading.enumerate()) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not any(t.ident == seen[2][0] for t in threading.enumerate()) and kept.is_alive()
    monkeypatch.setattr(progress._launch_threads.kept, "pid", -1)  # as a forked child sees its parent's object
    watch()
    assert seen[3][0] != seen[0][0]
    watch()
    assert seen[4] == seen[3]


def test_a_small_march_runs_on_the_calling_thread_and_reports_its_end():
    """Below SAMPLES_WATCHED per thread the march is one launch on the calling thread, no thread of its own."""
    from vlref.techniques.physical import SAMPLES_WATCHED

    calls = []
    with reporting(lambda done, total: calls.append((done, total, [t.name for t in threading.enumerate()]))):
        render(load_scene("pillars", ["render.width=32", "render.height=18", "render.steps=8"]))
    assert 32 * 18 * 8 < SAMPLES_WATCHED and [c[:2] for c in calls] == [(18, 18)]
    assert "vlref-launch" not in calls[0][2]


def test_the_reference_reports_progress_band_by_band(monkeypatch):
    scene = load_scene("pillars", ["render.width=12", "render.height=10"])
    monkeypatch.setattr(quadrature, "RAYS_PER_BAND", 1)  # as many bands as rows
    calls = []
    with reporting(lambda done, total: calls.append((done, total))):
        render_reference(scene, rel_tol=1e-2, shadow_samples=16)
    assert calls == [(y, 10) for y in range(1, 11)]


def test_a_small_reference_runs_in_one_band():
    """Bands are sized by their shadow rays (quadrature.RAYS_PER_BAND per thread): a small image is one launch."""
    scene = load_scene("pillars", ["render.width=12", "render.height=10"])
    calls = []
    with reporting(lambda done, total: calls.append((done, total))):
        render_reference(scene, rel_tol=1e-2, shadow_samples=16)
    assert calls == [(10, 10)]


@pytest.mark.parametrize("technique", ["physical", "reference"])
def test_bands_change_no_bit(monkeypatch, technique):
    scene = load_scene("coloured_lights", ["render.width=24", "render.height=14", "render.steps=6"])
    runs = []
    before = numba.get_num_threads()
    for bands in (1, 5):
        monkeypatch.setattr(progress, "BANDS", bands)
        monkeypatch.setattr(quadrature, "RAYS_PER_BAND", 1)  # as many bands as BANDS allows
        if technique == "reference":
            res = render_reference(scene, rel_tol=1e-2, shadow_samples=16)
            runs.append({"inscatter": res.inscatter, "transmittance": res.transmittance, "error": res.error})
        else:  # one launch (no bands): on one thread, then on two taking the tiles in another order
            numba.set_num_threads(min(bands, 2, numba.config.NUMBA_NUM_THREADS))
            try:
                runs.append(render(scene, stages=True).buffers)
            finally:
                numba.set_num_threads(before)
    for name in runs[0]:
        assert np.array_equal(runs[0][name], runs[1][name], equal_nan=True), name


def _stderr_reader(proc, stream=None):
    """Collect the child's stderr (or ``stream``; tqdm writes without newlines) in a background thread."""
    chunks = []
    stream = proc.stderr if stream is None else stream

    def read():
        for chunk in iter(lambda: os.read(stream.fileno(), 4096), b""):
            chunks.append(chunk)

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    return chunks, thread


def _interrupt(work: Path, argv: list[str], marker: bytes, sig: int, group: bool = False, env=None) -> None:
    """Run ``vlref ARGV`` in ``work`` (empty), send ``sig`` once ``marker`` shows on its stdout or stderr (its
    long phase), and check the outcome: exit 128 + sig, the last line ``vlref: interrupted``, no traceback
    (nor from a child process), and ``work`` still empty (no output, no temporary file or folder).
    ``group``: to the whole process group, as Ctrl-C in a terminal does (children get it too); ``env``: more
    environment variables."""
    proc = subprocess.Popen([sys.executable, "-m", "vlref", *argv], cwd=work,
                            env=dict(ENV, PYTHONUNBUFFERED="1", **(env or {})),
                            stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, start_new_session=True)
    chunks, reader = _stderr_reader(proc, proc.stdout)
    deadline = time.monotonic() + 300  # a cold Numba cache compiles first
    while marker not in b"".join(chunks) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert proc.poll() is None, "the command ended before it could be interrupted: " + b"".join(chunks).decode()
    if group:
        os.killpg(proc.pid, sig)
    else:
        proc.send_signal(sig)
    try:
        rc = proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    reader.join(timeout=10)
    out = b"".join(chunks).decode(errors="replace")
    assert rc == 128 + sig, out
    assert "Traceback" not in out and "KeyboardInterrupt" not in out and "Error" not in out, out
    assert out.replace("\r", "\n").rstrip().splitlines()[-1].strip() == "vlref: interrupted", out
    assert sorted(p.name for p in work.iterdir()) == []  # no output folder, no .out.*.partial, no temp file


def _work(tmp_path: Path) -> Path:
    work = tmp_path / "work"
    work.mkdir()
    return work


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_mid_render_exits_cleanly(tmp_path, sig):
    # A render of several seconds; the bar appears once it has run for about a second: then signal it.
    _interrupt(_work(tmp_path), ["render", "pillars", "-o", "out", "--set", "render.steps=2048"],
               b"render pillars", sig)


QUADRATURE = ["--set", "render.width=160", "--set", "render.height=90"]  # a quadrature of several seconds
# two references of a fraction of a second each: the bar shows once the first is done (the dask test's marker)
SWEEP = """scene = "pillars"
set = ["render.width=64", "render.height=36"]
techniques = ["physical", "killzone"]
[grid]
"medium.anisotropy" = [0.0, 0.5]
"""
# five references of about a second each (~9 s in all on the dev box's two cores, warm): the signal, sent as the bar
# first shows, meets one of them (SWEEP's second one had once ended before its signal came)
SWEEP_LONG = SWEEP.replace("width=64", "width=160").replace("height=36", "height=90").replace(
    "[0.0, 0.5]", "[0.0, 0.2, 0.4, 0.6, 0.8]")


@pytest.mark.parametrize("argv, marker, sig", [
    # the reference used to crash (SystemError): the signal arrived inside the boxing of the kernel's returned arrays
    (["reference", "pillars", *QUADRATURE, "-o", "out"], b"stage 4/4", signal.SIGINT),
    (["bias", "pillars", "--technique", "killzone", "--steps", "4,8", *QUADRATURE, "-o", "out"], b"bias pillars",
     signal.SIGTERM),
    (["sweep", "{inputs}/sweep.toml", "-o", "out"], b"sweep", signal.SIGINT),
    (["render", "anim_spot", "--frames", "0:8", "--set", "render.steps=512", "-o", "out"], b"render anim_spot", signal.SIGTERM),
    (["golden", "build", "--dir", "golden"], b"built ", signal.SIGINT),
    (["golden", "verify"], b"ok ", signal.SIGTERM),
    (["march", "{inputs}/port/port.toml", "--set", "render.steps=4096", "-o", "out"], b"march port", signal.SIGINT),
    (["bench", "--quick"], b"[bench]", signal.SIGTERM),
    (["warmup", "--jobs", "2"], b"group, frame]", signal.SIGINT),  # its pool is up: the first group is done
], ids=["reference", "bias", "sweep", "frames", "golden-build", "golden-verify", "march", "bench", "warmup"])
def test_every_long_command_exits_cleanly_on_a_signal(tmp_path, argv, marker, sig):
    """Ctrl-C goes to the whole process group (warmup's pool, the march compiler get it too); SIGTERM to vlref."""
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    if "{inputs}/sweep.toml" in argv:
        (inputs / "sweep.toml").write_text(SWEEP_LONG)
    if "{inputs}/port/port.toml" in argv:
        from vlref.port import export_port
        # 640x360 at 4096 steps: the march lasts long enough (tens of seconds) to be interrupted mid-way
        export_port("pillars", inputs / "port", ("render.width=640", "render.height=360"))
    # warmup with a warm cache (CI fills it first) ends in about two seconds: give it an empty one, so that it
    # is still compiling when the signal comes
    env = {"NUMBA_CACHE_DIR": str(inputs / "cold-cache")} if argv[0] == "warmup" else None
    _interrupt(_work(tmp_path), [a.replace("{inputs}", str(inputs)) for a in argv], marker, sig,
               group=sig == signal.SIGINT, env=env)


def test_a_signal_that_lands_in_a_finalizer_still_interrupts_the_command():
    """A signal handled while a ``__del__`` runs (an object freed mid-command, as llvmlite's are while Numba
    compiles) interrupts the command: raised in the frame that freed the object, not inside the finalizer, where
    the interpreter would print "Exception ignored" and go on."""
    class SignalledOnFree:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGTERM)   # handled at the finalizer's next bytecode
            self.freed = True

    after = []
    with pytest.raises(Interrupted) as caught:
        with _interruptible():
            obj = SignalledOnFree()
            del obj
            after.append("ran on")
    assert caught.value.signum == signal.SIGTERM and after == []


@pytest.mark.parametrize("module, name", [("numba.core.types.abstract", "_on_type_disposal"), ("weakref", "__call__")])
def test_a_signal_that_lands_in_a_weakref_callback_still_interrupts_the_command(module, name):
    """A signal handled while a weakref callback runs (Numba's ``_on_type_disposal`` when one of its interned types
    dies; :class:`weakref.finalize`) interrupts the command: raised in the frame that freed the object, not inside
    the callback, where the interpreter would print "Exception ignored" and go on (a ``vlref golden verify`` under
    SIGTERM once exited 0 so)."""
    namespace = {"__name__": module, "os": os, "signal": signal}
    exec(f"def {name}(ref):\n    os.kill(os.getpid(), signal.SIGTERM)\n    {name}.ran_on = True\n", namespace)

    class Watched:
        pass

    after = []
    with pytest.raises(Interrupted) as caught:
        with _interruptible():
            obj = Watched()
            ref = weakref.ref(obj, namespace[name])
            del obj
            after.append("ran on")
    assert caught.value.signum == signal.SIGTERM and after == [] and ref() is None


def test_a_signal_that_lands_in_an_llvmlite_callback_still_interrupts_the_command():
    """A signal handled while LLVM calls llvmlite's Python code back through ctypes (its object cache's notify,
    while Numba compiles or loads a kernel) interrupts the command: raised in the frame that made the foreign call,
    not inside the callback, where ctypes would print "Exception ignored on calling ctypes callback function" and go
    on (a ``vlref bench`` under SIGTERM once exited 0 so)."""
    namespace = {"__name__": "llvmlite.binding.executionengine", "os": os, "signal": signal}
    exec("def notify():\n    os.kill(os.getpid(), signal.SIGTERM)\n    notify.ran_on = True\n", namespace)
    callback = ctypes.CFUNCTYPE(None)(namespace["notify"])
    after = []
    with pytest.raises(Interrupted) as caught:
        with _interruptible():
            callback()  # through C, as LLVM calls it
            after.append("ran on")
    assert caught.value.signum == signal.SIGTERM and after == []


def test_ctrl_c_under_a_local_dask_cluster_exits_cleanly(tmp_path):
    """``--scheduler local:2``: Ctrl-C reaches the worker processes too; they ignore it, and vlref closes the
    cluster: one line, no worker traceback (golden and reference tiles take the same path, vlref.work_items)."""
    (tmp_path / "sweep.toml").write_text(SWEEP)
    _interrupt(_work(tmp_path), ["sweep", str(tmp_path / "sweep.toml"), "-o", "out", "--scheduler", "local:2"],
               b"item/s", signal.SIGINT, group=True)


def test_warmup_covers_every_technique_and_precision():
    from vlref.techniques import TECHNIQUES
    from vlref.warmup import TASKS

    rendered = {tuple(overrides) for what, _, overrides in TASKS.values() if what in ("render", "sequence")}
    for technique in TECHNIQUES:
        assert any(f'render.technique="{technique}"' in o for o in rendered), technique
    assert any('render.precision="float32"' in o for o in rendered)
    assert {what for what, _, _ in TASKS.values()} == {"frame", "render", "sequence", "reference"}
    assert any("techniques.froxel.temporal=true" in o for o in rendered)  # the reprojection kernel too


def test_warmup_command_runs_every_task_and_reports_its_time(tmp_path):
    """With the cache filled (CI runs ``vlref warmup`` before the tests) this only loads the kernels."""
    proc = subprocess.run([sys.executable, "-m", "vlref", "warmup", "--jobs", "2"], cwd=tmp_path, env=ENV,
                          capture_output=True, text=True, timeout=1200)
    assert proc.returncode == 0, proc.stderr
    last = proc.stderr.replace("\r", "\n").strip().splitlines()[-1]
    from vlref.warmup import TASKS

    assert last.startswith(f"vlref warmup: {len(TASKS)} kernel groups compiled or loaded in ") and " s (cache: " in last
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("scene_name, extra", [
    ("pillars", []),
    ("colonnade", []),  # an OBJ mesh: a non-empty triangle BVH
    ("stained_glass", []),  # transparent tinted occluders: shadow-map tints
    ("slightlymad_spot", ['render.technique="physical"']),  # density noise
    ("pillars", ['render.precision="float32"']),
    ("pillars", ['lights.0.shadows.filter="exact"']),  # the march variant with the shadow-ray tracer
])
def test_each_stage_compiled_ahead_has_the_types_the_real_frame_calls(scene_name, extra):
    """``vlref render`` compiles later stages ahead on 1×1 frames with no objects (and a G-buffer of sky, no
    shadow maps but the stage's own): each must have exactly the types of the real frame's call, or the real
    render would compile again; so must the work each kernel calls by address (vlref.parallel.work)."""
    from vlref.geometry.raycast import _cast_rows
    from vlref.lights.shading import _shade_rows
    from vlref.lights.shadow_cast import _cast_chunks
    from vlref.march.physical import _march_tasks
    from vlref.post.composite import _sum_composite
    from vlref.ahead import AHEAD, compile_composite, compile_stage, stage_cached

    scene = load_scene(scene_name, ["render.width=8", "render.height=5", "render.steps=2", *extra])
    render(scene)
    called = {stage: set(kernel.signatures) for stage, (_, kernel) in AHEAD.items()}
    for stage, (_, kernel) in AHEAD.items():
        # the work, called by address: one argument of every signature is a first-class function
        assert all(any(isinstance(t, types.FunctionType) for t in sig) for sig in kernel.signatures), stage
    also = (_sum_composite, _march_tasks, _cast_chunks, _cast_rows, _shade_rows)  # the march's, the work
    after_march = {kernel: set(kernel.signatures) for kernel in also}
    for stage, (_, kernel) in AHEAD.items():
        compile_stage(stage, scene)
        assert set(kernel.signatures) == called[stage], stage
        assert {k: set(k.signatures) for k in after_march} == after_march, stage
        if stage == "march" or kernel.signatures:  # cache=True wrote it; the render command then starts no process
            assert stage_cached(stage, scene), stage
    compile_composite(scene)  # the march's buffers' composite, compiled by the main process meanwhile
    assert {k: set(k.signatures) for k in after_march} == after_march


class _Started:
    """A compile-ahead process that runs nothing (``compile_ahead``'s bookkeeping alone): alive until joined."""
    made = []

    def __init__(self, target, args, daemon):
        self.args, self.alive = args, True
        _Started.made.append(self)

    def start(self):
        pass

    def is_alive(self):
        return self.alive

    def join(self):
        self.alive = False

    def terminate(self):
        self.alive = False


@pytest.mark.parametrize("first", ["main", "march", "neither"])
def test_the_marchs_composite_is_compiled_once_by_the_process_that_gets_to_it_first(monkeypatch, first):
    """A cold render's composite of the march's buffers is compiled by the main process when it reaches the march
    while the march's process runs (``ready``), or by that process after the march, whichever takes the claim first;
    a process already ended leaves it to the render's own call."""
    import vlref.ahead as ahead

    compiled, caller = [], ["main"]
    monkeypatch.setattr(ahead, "compile_composite", lambda scene: compiled.append((caller[0], scene)))

    def march_process_claims():  # what the march's process does after the march
        caller[0] = "march"
        ahead._compile_composite_unless_claimed(claim, scene)
        caller[0] = "main"

    monkeypatch.setattr(ahead, "_stages_ahead", lambda scene: ["march"])
    monkeypatch.setattr(ahead, "host_cores", lambda: 2)
    monkeypatch.setattr(ahead, "_to_load_ahead", lambda scene, cold: [])
    monkeypatch.setattr(ahead.multiprocessing.context.SpawnContext, "Process", _Started)
    _Started.made.clear()
    scene = load_scene("pillars")
    with ahead.compile_ahead(scene) as ready:
        (march,) = _Started.made
        stage, _, claim = march.args
        assert stage == "march" and claim is not None
        if first == "march":
            march_process_claims()
        if first == "neither":  # that process ended without taking it
            march.alive = False
        ready(ahead.AHEAD["march"][0])  # the main process, done with the shadow maps
        if first == "main":  # the march's process comes later: claimed already
            march_process_claims()
    assert compiled == ([] if first == "neither" else [(first, scene)])
