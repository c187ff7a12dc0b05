"""The decode-ahead reader: every item in order, errors where the caller reads, a clean stop."""

from __future__ import annotations

import threading

import pytest

from badminton_gui.io.prefetch import PrefetchingReader


class CountingSource:
    """Yields 0..n-1, then None; can fail at a given item; records close()."""

    def __init__(self, n: int, fail_at: int | None = None) -> None:
        self.n, self.fail_at, self.i = n, fail_at, 0
        self.closed = False
        self.name = "counting"
        self.read_threads: set[str] = set()

    def read(self):
        self.read_threads.add(threading.current_thread().name)
        if self.fail_at is not None and self.i == self.fail_at:
            raise OSError("the disk went away")
        if self.i >= self.n:
            return None
        self.i += 1
        return self.i - 1

    def close(self) -> None:
        self.closed = True


def test_every_item_in_order_then_none():
    source = CountingSource(50)
    reader = PrefetchingReader(source, depth=3)
    got = []
    while (item := reader.read()) is not None:
        got.append(item)
    assert got == list(range(50))
    assert reader.read() is None          # stays at the end
    assert reader.name == "counting"      # attributes are the wrapped source's
    assert source.read_threads == {"prefetch"}
    reader.close()
    assert source.closed


def test_reader_error_is_raised_in_the_caller_after_the_good_items():
    reader = PrefetchingReader(CountingSource(10, fail_at=4), depth=2)
    assert [reader.read() for _ in range(4)] == [0, 1, 2, 3]
    with pytest.raises(OSError, match="disk went away"):
        reader.read()
    assert reader.read() is None
    reader.close()


def test_close_while_the_reader_waits_on_a_full_queue():
    source = CountingSource(10_000)
    reader = PrefetchingReader(source, depth=2)
    assert reader.read() == 0
    reader.close()                         # must not hang on the blocked put
    assert source.closed
    assert source.i < 100                  # it read ahead only by the queue's depth
