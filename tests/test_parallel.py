"""vlref.parallel: tasks handed out on demand (each exactly once, whatever the threads), and borrowed records
(the same data, no reference counts)."""

import numba
import numpy as np
import pytest
from numba import njit, prange
from numba.core.errors import TypingError

from vlref.lights.pack import PackedLights
from vlref.parallel import WORKERS, borrowed, take


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
