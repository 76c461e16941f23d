"""Scale-out on Dask (vlref.work_items): golden entries, reference tiles and sweep points give the same bytes
on a cluster as in this process; failures are reported by item and write nothing; a worker killed
mid-run loses nothing.

One 2-worker LocalCluster per module (worker processes with one Dask thread each, NUMBA_CACHE_DIR passed
through, built by vlref.work_items.local_cluster as `--scheduler local:2` builds it), reached through its
tcp:// address, so the tests also exercise the existing-scheduler path. `distributed` comes with the
`test` extra (setup.cfg), so it is imported, not skipped.
"""

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import distributed
import numpy as np
import pytest

from vlref.cli import main
from vlref.work_items import local_cluster
from vlref.oracle.golden import SUITE_FILE, verify
from vlref.reference import render_reference
from vlref.reference.tiles import render_reference_tiled
from vlref.scene import load_scene

GOLDEN_DIR = Path(__file__).resolve().parents[1] / "data" / "golden"  # the checkout's goldens, installed or not
SMALL_REF = ["pillars", "--set", "render.width=32", "--set", "render.height=18", "--rel-tol", "1e-3"]
GOLDEN_SUBSET = ["--only", "pillars/physical", "--only", "pillars/killzone", "--only", "pillars/radial"]


@pytest.fixture(scope="module")
def cluster():
    """``(scheduler address, client)`` of a 2-worker local cluster."""
    with local_cluster(2) as c, distributed.Client(c) as client:
        yield c.scheduler_address, client


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_reference_tiles_on_the_cluster_equal_the_in_process_bytes(tmp_path, cluster):
    address, _ = cluster
    assert main(["reference", *SMALL_REF, "-o", str(tmp_path / "a")]) == 0
    assert main(["reference", *SMALL_REF, "-o", str(tmp_path / "b"), "--scheduler", address, "--tile-rows", "5"]) == 0
    a, b = _files(tmp_path / "a"), _files(tmp_path / "b")
    assert sorted(a) == ["error.exr", "inscatter.exr", "reference.exr", "reference.png"]
    assert a == b


def test_golden_build_and_verify_on_the_cluster_equal_in_process(tmp_path, cluster):
    address, _ = cluster
    assert main(["golden", "build", "-q", "--dir", str(tmp_path / "a"), *GOLDEN_SUBSET]) == 0
    assert main(["golden", "build", "-q", "--dir", str(tmp_path / "b"), *GOLDEN_SUBSET, "--scheduler", address]) == 0
    a, b = _files(tmp_path / "a"), _files(tmp_path / "b")
    assert len(a) == 1 + 3 * 3  # manifest + 3 entries x 3 buffers
    assert a == b
    only = ["pillars/*"]
    here = verify(GOLDEN_DIR, SUITE_FILE, only, log=lambda *a: None)
    there = verify(GOLDEN_DIR, SUITE_FILE, only, log=lambda *a: None, scheduler=address, quiet=True)
    assert [o.name for o in here] == [o.name for o in there] == sorted(o.name for o in here) and len(here) >= 3
    assert all(not o.problems for o in here + there)
    assert [o.margins for o in here] == [o.margins for o in there]


def test_sweep_on_the_cluster_equals_in_process_and_converges(tmp_path, cluster):
    address, _ = cluster
    spec = tmp_path / "sweep.toml"
    spec.write_text('scene = "pillars"\nset = ["render.width=24", "render.height=14"]\n'
                    'techniques = ["physical", "killzone"]\nmetrics = ["error", "time", "flip"]\nrel_tol = 1e-3\n'
                    '[grid]\n"render.steps" = [4, 16]\n')
    assert main(["sweep", str(spec), "-o", str(tmp_path / "a"), "-q"]) == 0
    assert main(["sweep", str(spec), "-o", str(tmp_path / "b"), "-q", "--scheduler", address]) == 0
    a, b = _files(tmp_path / "a"), _files(tmp_path / "b")
    a.pop("timings.csv")
    timings = b.pop("timings.csv")
    assert sorted(a) == ["killzone/000.exr", "killzone/001.exr", "physical/000.exr", "physical/001.exr",
                         "reference/0.exr", "summary.csv"]
    assert a == b
    lines = timings.decode().splitlines()
    assert lines[0] == "item,seconds" and len(lines) == 6 and all(float(l.split(",")[1]) > 0 for l in lines[1:])
    import csv
    rows = {r["item"]: r for r in csv.DictReader(a["summary.csv"].decode().splitlines())}
    # the physical march is first order in the step length: 4x the steps, about a quarter of the error
    ratio = float(rows["physical/000"]["mean_abs"]) / float(rows["physical/001"]["mean_abs"])
    assert rows["physical/000"]["render.steps"] == "4" and 2.5 < ratio < 6.5
    # the reference written is the quadrature reference of the same scene (float32 in the EXR)
    from vlref.io.images import read_image
    ref = render_reference(load_scene("pillars", ["render.width=24", "render.height=14"]), rel_tol=1e-3)
    np.testing.assert_array_equal(read_image(tmp_path / "b" / "reference" / "0.exr"), ref.inscatter.astype(np.float32))
    assert all(0.0 <= float(r["flip"]) <= 1.0 for r in rows.values())


def test_failures_are_reported_by_item_and_nothing_is_written(tmp_path, cluster, capsys):
    address, _ = cluster
    suite = tmp_path / "suite.toml"
    suite.write_text(SUITE_FILE.read_text().replace('buffers = ["final", "inscatter", "transmittance"]',
                                                    'buffers = ["final", "nosuch"]'))
    out = tmp_path / "golden"
    assert main(["golden", "build", "-q", "--dir", str(out), "--suite", str(suite), "--only", "pillars/physical",
                        "--only", "pillars/killzone", "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert "2 item(s) failed" in err and "pillars/physical: InputError" in err and "pillars/killzone: InputError" in err
    assert "no buffer(s) nosuch" in err
    assert not out.exists() and not list(tmp_path.glob(".golden.*"))


def test_bad_scheduler_is_bad_input_and_dask_stays_unimported(tmp_path, capsys):
    assert main(["reference", *SMALL_REF, "-o", str(tmp_path / "r"), "--scheduler", "local:0"]) == 2
    assert main(["reference", *SMALL_REF, "-o", str(tmp_path / "r"), "--scheduler", "http://x"]) == 2
    assert "--scheduler" in capsys.readouterr().err and not (tmp_path / "r").exists()
    code = ("import sys, vlref.cli, vlref.oracle.golden, vlref.sweep, vlref.reference.tiles; "
            "sys.exit(int(any(m.split('.')[0] in ('dask', 'distributed') for m in sys.modules)))")
    assert subprocess.run([sys.executable, "-c", code], cwd=Path(__file__).parents[1]).returncode == 0


def test_a_worker_killed_mid_run_loses_nothing(cluster):
    """SIGKILL a worker while it runs a tile: the scheduler reruns its tiles elsewhere, the nanny restarts it."""
    address, client = cluster
    scene = load_scene("pillars", ["render.width=64", "render.height=36"])
    pids = client.run(os.getpid)
    killed = []

    def kill_a_busy_worker():
        deadline = time.monotonic() + 60
        while not killed and time.monotonic() < deadline:
            busy = [(w, keys) for w, keys in client.processing().items() if keys and w in pids]
            if busy:
                os.kill(pids[busy[0][0]], signal.SIGKILL)
                killed.append(busy[0])
            time.sleep(0.01)

    thread = threading.Thread(target=kill_a_busy_worker)
    thread.start()
    tiled = render_reference_tiled(scene, 1e-4, scheduler=address, rows_per_tile=2, quiet=True)
    thread.join()
    assert killed and killed[0][1], "a worker was killed while it had tiles"
    whole = render_reference(scene, rel_tol=1e-4)
    for name in ("inscatter", "transmittance", "final", "error"):
        np.testing.assert_array_equal(getattr(tiled, name), getattr(whole, name))
    np.testing.assert_array_equal(tiled.stats["shadow_boundaries"], whole.stats["shadow_boundaries"])
    assert tiled.stats["intervals"] == whole.stats["intervals"] and tiled.stats["tiles"] == 18
    client.wait_for_workers(2, timeout=60)  # the nanny restarted it
    assert pids[killed[0][0]] not in client.run(os.getpid).values()
