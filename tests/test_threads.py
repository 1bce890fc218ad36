"""The background producer the USD writer overlaps with pxr: order, errors, early exit."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from marsscene._threads import prefetch


def _live(name: str) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == name and t.is_alive()]


def test_items_come_in_order_and_the_producer_runs_ahead() -> None:
    made: list[int] = []

    def items() -> Iterator[int]:
        for i in range(20):
            made.append(i)
            yield i

    got = []
    for item in prefetch(items(), depth=3, name="t-order"):
        if item == 0:
            deadline = time.monotonic() + 5.0
            while len(made) < 4 and time.monotonic() < deadline:  # 3 queued + 1 in hand
                time.sleep(0.005)
            assert len(made) >= 4  # produced ahead of the consumer, bounded by depth
            assert len(made) <= 5
        got.append(item)
    assert got == list(range(20))
    assert not _live("t-order")


def test_a_producer_error_is_raised_at_its_item() -> None:
    def items() -> Iterator[int]:
        yield 1
        yield 2
        raise ValueError("tile 3 failed")

    got = []
    with pytest.raises(ValueError, match="tile 3 failed"):
        for item in prefetch(items(), name="t-error"):
            got.append(item)
    assert got == [1, 2]
    assert not _live("t-error")


def test_leaving_the_loop_early_stops_and_joins_the_producer() -> None:
    produced: list[int] = []

    def endless() -> Iterator[int]:
        i = 0
        while True:
            produced.append(i)
            yield i
            i += 1

    for item in prefetch(endless(), depth=2, name="t-early"):
        if item == 5:
            break
    assert not _live("t-early")
    assert len(produced) <= 5 + 1 + 2 + 1  # stopped within a queue's length of the consumer


def test_ordered_map_keeps_order_and_bounds_the_window() -> None:
    """Results come in input order whatever finishes first, and never more than ``window``
    items are computed ahead of the consumer."""
    import random

    from marsscene._threads import ordered_map

    started: list[int] = []
    lock = threading.Lock()
    rnd = random.Random(3)
    delays = [rnd.uniform(0.0, 0.004) for _ in range(60)]

    def work(i: int) -> int:
        with lock:
            started.append(i)
        time.sleep(delays[i])
        return i * i

    out = []
    for i, value in enumerate(ordered_map(work, range(60), workers=3, window=5)):
        with lock:
            assert len(started) <= i + 5
        out.append(value)
    assert out == [i * i for i in range(60)]


def test_ordered_map_raises_at_the_failing_item() -> None:
    from marsscene._threads import ordered_map

    def work(i: int) -> int:
        if i == 7:
            raise ValueError("seven")
        return i

    got = []
    with pytest.raises(ValueError, match="seven"):
        for v in ordered_map(work, range(20), workers=2, window=4):
            got.append(v)
    assert got == list(range(7))
