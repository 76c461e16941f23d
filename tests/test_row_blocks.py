"""Row blocks on threads: every row in exactly one block, blocks of bounded and even size."""

import threading

import pytest

from vlref.row_blocks import MAX_BLOCK_ROWS, in_row_blocks


@pytest.mark.parametrize("height", [0, 1, 7, MAX_BLOCK_ROWS, MAX_BLOCK_ROWS + 1, 1080, 2161])
@pytest.mark.parametrize("threads", [1, 2, 3, 16])
def test_blocks_cover_every_row_once_evenly_and_spread_over_the_threads(height, threads):
    spans, names, lock = [], set(), threading.Lock()

    def record(y0, y1):
        with lock:
            spans.append((y0, y1))
            names.add(threading.current_thread().name)

    in_row_blocks(height, record, threads)
    spans.sort()
    assert [y for span in spans for y in range(*span)] == list(range(height))
    if height:
        sizes = [y1 - y0 for y0, y1 in spans]
        assert max(sizes) <= MAX_BLOCK_ROWS and max(sizes) - min(sizes) <= 1
        # as few blocks as a multiple of the thread count allows (fewer only where rows run out)
        assert len(spans) == min(height, threads * -(-height // (threads * MAX_BLOCK_ROWS)))
        assert len(names) <= threads
