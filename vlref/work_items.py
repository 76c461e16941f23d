"""Independent work items, run in this process or on a Dask cluster (``--scheduler``).

Task model
----------
An :class:`Item` is a pure function call ``fn(*args, **kwargs)`` with a unique ``key`` (the name it is
reported under): a golden entry, a tile of rows of a reference image, a sweep point. It returns
picklable arrays and metadata; it writes no file. The caller writes every result into one
:func:`vlref.io.output_folders.output_dir` as it arrives, so a run either lands whole or leaves nothing, and the
bytes written do not depend on where an item ran. An argument ``After(key)`` stands for the result of
an earlier item (a sweep point needs its reference).

Schedulers (:func:`parse_scheduler`)
------------------------------------
* ``None``: in this process, items in order; bad input (:class:`InputError`) stops the run as
  :class:`ItemsFailed` naming the item, other exceptions propagate (as without Dask);
* ``local`` / ``local:N``: a ``distributed.LocalCluster`` of N worker processes (default: one per
  core) with one Dask thread each, started for the run and closed after it;
* ``tcp://host:port``: an existing Dask scheduler (its workers must import the same vlref).

On a cluster
------------
* Threads: each worker runs one item at a time per Dask thread, and every item sets its own Numba
  thread count (``numba.set_num_threads`` is per calling thread, so it is set inside the item, in the
  thread that runs it) to ``cores of its host // (Dask threads on that host)``: workers × Dask threads
  × Numba threads ≤ cores. A ``local:N`` cluster also starts its workers with ``NUMBA_NUM_THREADS``
  at that value.
* Numba compiles once per worker process (kernels are ``cache=True``): the workers inherit
  ``NUMBA_CACHE_DIR``, so on one host the first worker to compile a kernel writes it and the others load it.
* Failures: an item that raises is reported by key (:class:`ItemsFailed`), the others still run,
  nothing is written. An item whose worker died is rerun on another worker once
  (``distributed.scheduler.allowed-failures = 1`` on a ``local`` cluster; an existing scheduler
  applies its own setting, Dask's default 3), then reported as failed.
* A tqdm bar on stderr counts finished items; the dashboard link is printed (the dashboard needs
  ``bokeh``, part of the ``distributed`` extra).
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

from .errors import InputError
from .processes import host_cores, ignoring_sigint

__all__ = ["Item", "After", "ItemsFailed", "parse_scheduler", "run_items",
           "local_cluster"]


@dataclass(frozen=True)
class Item:
    """One unit of work: ``fn(*args, **kwargs)``, reported as ``key``."""

    key: str
    fn: Callable
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)


@dataclass(frozen=True)
class After:
    """An argument standing for the result of the earlier item ``key``."""

    key: str


class ItemsFailed(Exception):
    """Items that failed on a cluster: ``failures`` is a list of ``(key, reason)``.

    ``bad_input``: every failure is bad input (:class:`InputError`; the CLI exits 2, else 1).
    """

    def __init__(self, failures: list[tuple[str, str]], bad_input: bool):
        self.failures = failures
        self.bad_input = bad_input
        super().__init__(f"{len(failures)} item(s) failed:\n" + "\n".join(f"  {k}: {r}" for k, r in failures))


_LOCAL = re.compile(r"^local(?::(\d+))?$")


def parse_scheduler(text: str | None):
    """``None`` -> None; ``local[:N]`` -> ``("local", N)``; ``tcp://host:port`` -> ``("address", text)``."""
    if text is None:
        return None
    m = _LOCAL.match(text)
    if m:
        n = int(m.group(1)) if m.group(1) else host_cores()
        if n < 1:
            raise InputError("<command line>", "--scheduler", f"local:N needs N >= 1, got {text!r}")
        return ("local", n)
    if re.match(r"^(tcp|tls|inproc|ucx)://\S+$", text):
        return ("address", text)
    raise InputError("<command line>", "--scheduler",
                     f"expected local, local:N or a scheduler address tcp://host:port, got {text!r}")


def _numba_threads(threads_by_host: dict[str, int]) -> None:
    """Set this thread's Numba thread count from the budget of the worker's host (see the module docstring)."""
    import numba
    from distributed import get_worker

    host = get_worker().address.split("://")[-1].rsplit(":", 1)[0]
    budget = threads_by_host.get(host, min(threads_by_host.values()))
    numba.set_num_threads(max(1, min(budget, numba.config.NUMBA_NUM_THREADS)))


def _call(threads_by_host, fn, args, kwargs, after):
    """The function a worker runs: ``(seconds, fn(*args, **kwargs))`` with its thread budget set; the
    arguments at the positions ``after`` are results of other items, ``(seconds, result)``."""
    _numba_threads(threads_by_host)
    args = tuple(a[1] if i in after else a for i, a in enumerate(args))
    start = time.perf_counter()
    result = fn(*args, **kwargs)
    return time.perf_counter() - start, result


def local_cluster(n_workers: int, quiet: bool = True):
    """A ``distributed.LocalCluster`` of ``n_workers`` processes with one Dask thread each.

    Each worker gets ``NUMBA_NUM_THREADS = max(1, cores // n_workers)``, the parent's ``NUMBA_CACHE_DIR``
    and this vlref on ``PYTHONPATH``; the scheduler reruns an item lost with its worker once. ``quiet``: the
    cluster logs only critical messages (its errors while it shuts down, such as heartbeats to a scheduler
    already closed after an interrupt, are noise; an item's failure reaches the caller as :class:`ItemsFailed`),
    else warnings too.
    """
    import logging

    import dask
    from distributed import LocalCluster

    root = str(Path(__file__).resolve().parents[1])
    env = {"NUMBA_NUM_THREADS": str(max(1, host_cores() // n_workers)), "OMP_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    if os.environ.get("NUMBA_CACHE_DIR"):
        env["NUMBA_CACHE_DIR"] = os.environ["NUMBA_CACHE_DIR"]
    # the workers ignore Ctrl-C (sent to the whole process group): this process closes the cluster (vlref.processes)
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}), ignoring_sigint():
        return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, env=env,
                            dashboard_address=":0", silence_logs=logging.CRITICAL if quiet else logging.WARNING)


@contextlib.contextmanager
def _client(spec, quiet: bool) -> Iterator[Any]:
    """A connected ``distributed.Client`` for a parsed scheduler spec (the local cluster closes after)."""
    try:
        from distributed import Client
    except ImportError:
        raise InputError("<command line>", "--scheduler", "Dask is not installed (pip install 'vlref[distributed]')"
                         ) from None
    kind, value = spec
    with contextlib.ExitStack() as stack:
        if kind == "local":
            cluster = stack.enter_context(local_cluster(value))
            client = stack.enter_context(Client(cluster))
        else:
            try:
                client = stack.enter_context(Client(value, timeout="20s"))
            except OSError as exc:
                raise InputError("<command line>", "--scheduler", f"cannot reach {value} ({exc})") from None
        if not quiet:
            link = client.dashboard_link
            print(f"dask: {len(client.scheduler_info()['workers'])} workers at {client.scheduler.address}; "
                  f"dashboard {link or 'unavailable (needs bokeh)'}", file=sys.stderr)
        yield client


def _threads_by_host(client) -> dict[str, int]:
    """Numba threads per item on each host: its cores // the Dask threads of all its workers."""
    workers = client.scheduler_info(n_workers=-1)["workers"]
    cores = client.run(host_cores)
    dask_threads: dict[str, int] = {}
    host_of = {}
    for address, info in workers.items():
        host = address.split("://")[-1].rsplit(":", 1)[0]
        host_of[address] = host
        dask_threads[host] = dask_threads.get(host, 0) + int(info["nthreads"])
    out = {}
    for address, n in cores.items():
        host = host_of.get(address, address.split("://")[-1].rsplit(":", 1)[0])
        out[host] = max(1, int(n) // max(1, dask_threads.get(host, 1)))
    return out


def _resolve(args, results):
    return tuple(results[a.key] if isinstance(a, After) else a for a in args)


def run_items(items: Sequence[Item], scheduler: str | None = None,
              on_result: Callable[[str, Any, float], None] | None = None, desc: str = "items",
              quiet: bool = False) -> None:
    """Run ``items``; call ``on_result(key, result, seconds)`` in this process as each one finishes.

    ``seconds`` is the item's own run time (wall clock where it ran). In this process items run in
    order; on a cluster they finish in any order. Results referenced by ``After`` are kept until the
    run ends; others are dropped after ``on_result``. Raises :class:`ItemsFailed` after the run when
    items failed on a cluster (the others were still reported to ``on_result``).
    """
    on_result = on_result or (lambda key, result, seconds: None)
    keys = [item.key for item in items]
    if len(set(keys)) != len(keys):
        raise ValueError("item keys must be unique")
    spec = parse_scheduler(scheduler)
    if spec is None:
        _run_here(items, on_result, desc, quiet)
        return
    with _client(spec, quiet) as client:
        _run_on(client, items, on_result, desc, quiet)


def _run_here(items: Sequence[Item], on_result, desc: str, quiet: bool) -> None:
    """Run ``items`` in order in this process (a bar once they have run a second). Bad input stops the run as
    :class:`ItemsFailed` naming the item; any other exception propagates as it is."""
    from tqdm import tqdm

    needed = {a.key for item in items for a in item.args if isinstance(a, After)}
    results: dict[str, Any] = {}
    with tqdm(total=len(items), desc=desc, unit="item", file=sys.stderr, delay=1.0, leave=False,
              disable=quiet) as bar:
        for item in items:
            start = time.perf_counter()
            try:
                result = item.fn(*_resolve(item.args, results), **item.kwargs)
            except InputError as exc:
                raise ItemsFailed([(item.key, f"{type(exc).__name__}: {exc}")], True) from None
            on_result(item.key, result, time.perf_counter() - start)
            if item.key in needed:
                results[item.key] = result
            bar.update(1)


def _run_on(client, items: Sequence[Item], on_result, desc: str, quiet: bool) -> None:
    from distributed import as_completed
    from tqdm import tqdm

    threads = _threads_by_host(client)
    run = uuid.uuid4().hex[:8]
    futures = {}
    for item in items:
        after = tuple(i for i, a in enumerate(item.args) if isinstance(a, After))
        futures[item.key] = client.submit(_call, threads, item.fn, _resolve(item.args, futures), item.kwargs,
                                          after, key=f"vlref-{run}-{item.key}", pure=False)
    key_of = {f.key: k for k, f in futures.items()}
    needed = {a.key for item in items for a in item.args if isinstance(a, After)}
    failures: list[tuple[str, str]] = []
    bad_input = True
    with tqdm(total=len(items), desc=desc, unit="item", file=sys.stderr, leave=False, disable=quiet) as bar:
        for future in as_completed(list(futures.values())):
            key = key_of[future.key]
            if future.status == "error":
                exc = future.exception()
                bad_input = bad_input and isinstance(exc, InputError)
                failures.append((key, f"{type(exc).__name__}: {exc}"))
            else:
                seconds, result = future.result()
                on_result(key, result, seconds)
            if key not in needed:
                del futures[key]
            bar.update(1)
    if failures:
        order = {k: i for i, k in enumerate(item.key for item in items)}
        raise ItemsFailed(sorted(failures, key=lambda f: order[f[0]]), bad_input)
