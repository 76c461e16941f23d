"""Row blocks on threads: every row in exactly one block, blocks of bounded and even size, a small frame on the
calling thread."""

import threading

import pytest

from vlref.row_blocks import MAX_BLOCK_ROWS, MIN_BLOCK_PIXELS, in_row_blocks


def _blocks(height, width, threads):
    spans, names, lock = [], set(), threading.Lock()

    def record(y0, y1):
        with lock:
            spans.append((y0, y1))
            names.add(threading.current_thread().name)

    in_row_blocks(height, width, record, threads)
    return sorted(spans), names


@pytest.mark.parametrize("height", [0, 1, 7, MAX_BLOCK_ROWS, MAX_BLOCK_ROWS + 1, 1080, 2161])
@pytest.mark.parametrize("width", [1920, 80])
@pytest.mark.parametrize("threads", [1, 2, 3, 16])
def test_blocks_cover_every_row_once_evenly_and_spread_over_the_threads(height, width, threads):
    spans, names = _blocks(height, width, threads)
    assert [y for span in spans for y in range(*span)] == list(range(height))
    if not height:
        return
    sizes = [y1 - y0 for y0, y1 in spans]
    assert max(sizes) <= MAX_BLOCK_ROWS and max(sizes) - min(sizes) <= 1
    assert len(names) <= threads
    fewest = -(-height // MAX_BLOCK_ROWS)   # the row limit's
    if len(spans) > fewest:   # a block beyond the row limit's is worth its pixels
        assert min(sizes) * width >= MIN_BLOCK_PIXELS // 2
    # as few blocks as a multiple of the thread count allows, fewer only where rows or pixels run out
    multiple = threads * -(-height // (threads * MAX_BLOCK_ROWS))
    assert len(spans) <= multiple
    assert len(spans) in (multiple, height, fewest) or (len(spans) + 1) * MIN_BLOCK_PIXELS > height * width


def test_a_frame_of_few_pixels_runs_on_the_calling_thread():
    """80x45 (the reference's bench frame): one block, no thread pool started for it."""
    spans, names = _blocks(45, 80, 16)
    assert spans == [(0, 45)] and names == {threading.current_thread().name}
