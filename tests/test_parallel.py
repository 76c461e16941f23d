"""vlref.parallel: tasks handed out on demand (each exactly once, whatever the threads), borrowed records
(the same data, no reference counts), and work called by address (the same result, not linked into the kernel)."""

import numba
import numpy as np
import pytest
from numba import njit, prange, types
from numba.core.errors import TypingError

from vlref.lights.pack import PackedLights
from vlref.geometry.raycast import _raycast_kernel
from vlref.lights.shading import _shade
from vlref.lights.shadow_cast import _cast_face
from vlref.march.physical import _march_kernel
from vlref.parallel import COUNTER, WORKERS, borrowed, take, task_counter, work, workers


@njit(parallel=True)
def _take_all(n_tasks, hits, owner):
    taken = np.zeros(1, dtype=np.int64)
    for worker in prange(WORKERS):
        while True:
            task = take(taken)
            if task >= n_tasks:
                break
            hits[task] += 1  # a task has one taker, so no two threads write the same element
            owner[task] = worker


@pytest.mark.parametrize("n_tasks", [0, 1, 7, 5000])
@pytest.mark.parametrize("threads", [1, 2])
def test_every_task_is_taken_exactly_once(n_tasks, threads):
    before = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        hits = np.zeros(n_tasks, dtype=np.int64)
        owner = np.full(n_tasks, -1, dtype=np.int64)
        _take_all(n_tasks, hits, owner)
    finally:
        numba.set_num_threads(before)
    assert np.all(hits == 1)
    assert np.all((owner >= 0) & (owner < WORKERS))


@njit(parallel=True)
def _take_all_counted(n_tasks, hits, workers):
    taken = task_counter()
    for _ in prange(workers):
        while True:
            task = take(taken)
            if task >= n_tasks:
                break
            hits[task] += 1


def _parfors(kernel):
    return len(kernel.overloads[kernel.signatures[0]].metadata["parfor_diagnostics"].initial_parfors)


def test_a_task_counter_adds_no_parfor_to_a_kernel():
    """``np.zeros`` in a parallel kernel is a parfor (a gufunc) of its own; ``task_counter`` is a call: the kernel
    lowers its ``prange`` alone. vlref's kernels that take tasks make their counter with it (the march's comes as an
    argument, made by its caller, which watches it: :func:`vlref.progress.watched`)."""
    hits = np.zeros(100, dtype=np.int64)
    _take_all_counted(100, hits, WORKERS)
    _take_all(100, np.zeros(100, dtype=np.int64), np.zeros(100, dtype=np.int64))
    assert np.all(hits == 1) and task_counter()[0] == 0
    assert _parfors(_take_all_counted) == 1 and _parfors(_take_all) == 2
    for kernel in (_raycast_kernel, _shade, _cast_face):
        names = kernel.py_func.__code__.co_names
        assert "task_counter" in names and "zeros" not in names, kernel
    assert "taken" in _march_kernel.py_func.__code__.co_varnames and "zeros" not in _march_kernel.py_func.__code__.co_names


@pytest.mark.parametrize("tasks, size", [(0, 1), (1, 1), (2, 2), (5, 2)])
def test_workers_are_one_per_thread_no_more_than_the_tasks_and_take_every_task(tasks, size):
    """Two threads (where Numba has them): ``workers`` is the kernel's ``prange`` count, one per thread and no more
    than the tasks (at least one); Numba's thread count is left as it is, and the workers take every task."""
    threads = min(2, numba.config.NUMBA_NUM_THREADS)
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        assert workers(tasks) == min(size, threads) and numba.get_num_threads() == threads
        hits = np.zeros(7 * tasks, dtype=np.int64)
        _take_all_counted(hits.size, hits, workers(tasks))
        assert np.all(hits == 1)
    finally:
        numba.set_num_threads(before)


def test_take_counts_up_from_the_counter():
    @njit
    def three(counter):
        return take(counter), take(counter), take(counter)

    counter = np.array([5], dtype=np.int64)
    assert three(counter) == (5, 6, 7) and counter[0] == 8


@njit
def _copies(record):
    view = borrowed(record)  # copies own their memory: they may leave the kernel, the view may not
    return view.ints.copy(), view.floats.copy(), view.cookies.shape, view.lut.copy()


def test_a_borrowed_record_has_the_same_arrays():
    rng = np.random.default_rng(3)
    lights = PackedLights(rng.integers(0, 9, (3, 8)), rng.random((3, 25)), np.zeros((0, 3)),
                          rng.random((2, 5))[:, ::2])  # a strided view keeps its strides
    ints, floats, cookies, lut = _copies(lights)
    assert np.array_equal(ints, lights.ints) and np.array_equal(floats, lights.floats)
    assert cookies == (0, 3) and np.array_equal(lut, lights.lut)


def test_borrowing_keeps_numbers_and_none():
    @njit
    def go(a, x, nothing):
        b, y, z = borrowed((a, x, nothing))
        return b[1] + y, z is None

    assert go(np.arange(3.0), 2.5, None) == (3.5, True)


def test_only_arrays_numbers_and_none_can_be_borrowed():
    @njit
    def go(items):
        return borrowed(items)

    with pytest.raises(TypingError, match="cannot borrow"):
        go(numba.typed.List([1.0, 2.0]))
    with pytest.raises(TypingError, match="1-d int64 array"):
        njit(lambda c: take(c))(np.zeros(1, dtype=np.int32))


@njit
def _count_tasks(taken, n_tasks, hits):
    while True:
        task = take(taken)
        if task >= n_tasks:
            return
        hits[task] += 1


@njit(parallel=True)
def _count_linked(n_tasks, hits):
    taken = np.zeros(1, dtype=np.int64)
    for _ in prange(WORKERS):
        _count_tasks(taken, n_tasks, hits)


@njit(parallel=True)
def _count_by_address(n_tasks, hits, count_tasks):
    taken = np.zeros(1, dtype=np.int64)
    for _ in prange(WORKERS):
        count_tasks(taken, n_tasks, hits)


def test_work_called_by_address_does_the_same_and_is_not_linked_into_the_kernel():
    """A kernel that calls its work by address (``work``) takes every task once, as the kernel calling it directly
    does; the work's code is in the direct kernel's LLVM module and not in the other's (what the compile saves)."""
    linked, by_address = np.zeros(5000, dtype=np.int64), np.zeros(5000, dtype=np.int64)
    _count_linked(5000, linked)
    count_tasks = work(_count_tasks, COUNTER, 5000, by_address)
    _count_by_address(5000, by_address, count_tasks)
    assert np.all(linked == 1) and np.all(by_address == 1)
    assert work(_count_tasks, COUNTER, 5000, by_address) is count_tasks  # kept per function and types
    assert work(_count_tasks, COUNTER, 5000, np.zeros(3, dtype=np.int32)) is not count_tasks
    (signature,) = _count_by_address.signatures
    assert isinstance(signature[-1], types.FunctionType)
    # typed by the type made with the work (vlref.parallel._typeof_work), Numba's own rule's type, not a new one
    assert numba.typeof(count_tasks) is signature[-1] is types.FunctionType(count_tasks.signature())
    assert "_count_tasks" in _count_linked.inspect_llvm(_count_linked.signatures[0])
    assert "_count_tasks" not in _count_by_address.inspect_llvm(signature)


def test_work_is_found_again_by_the_arguments_types_without_typing_them(monkeypatch):
    """The second look-up of a work for arguments of the same types (other values, other arrays) returns the kept
    Work without ``numba.typeof`` (the ray cast's records took ~0.2 ms a call to type); arguments of other types
    (dtype, layout, a record of other arrays) get their own."""
    hits = np.zeros(7, dtype=np.int64)
    first = work(_count_tasks, COUNTER, 7, hits)

    def no_typeof(value):
        raise AssertionError(f"typed again: {value!r}")

    monkeypatch.setattr(numba, "typeof", no_typeof)
    assert work(_count_tasks, COUNTER, 12, np.ones(40, dtype=np.int64)) is first
    monkeypatch.undo()
    assert work(_count_tasks, COUNTER, 7, np.zeros(7, dtype=np.int32)) is not first
    strided = np.zeros(14, dtype=np.int64)[::2]
    other = work(_count_tasks, COUNTER, 7, strided)
    assert other is not first and other.signature().args[-1].layout == "A"
