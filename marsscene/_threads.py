"""Helper threads for big terrains: when to use them, and a bounded background producer.

pxr's Python bindings hold the GIL while they copy arrays and write layers, but numpy and
Pillow release it for their large operations, so a second thread that only runs numpy/Pillow
(never pxr) keeps the second core busy while the main thread authors USD. The same test
(:func:`worth_a_thread`) gates the other helpers: crater batches (``craters.stamp``) and the
focus rocks of level-of-detail worlds (``pipeline.lod``).

One rule keeps this safe: **every pxr module is imported before such a thread starts.**
Importing a pxr extension module runs its static initialisers inside ``dlopen`` (holding the
dynamic loader's lock) and those wait for the GIL; a numpy call in another thread that holds
the GIL can meanwhile ask for the loader's lock (numpy's temporary elision walks the stack with
``backtrace``), and the two wait for each other forever. The USD writer imports all of its pxr
modules before it starts one (``marsscene.export.usd._import_authors``).
"""

from __future__ import annotations

import queue
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

__all__ = ["THREADED_MIN_POSTS", "ordered_map", "prefetch", "worth_a_thread"]

#: Terrains with fewer posts are written on one thread: their textures and tiles take tens of
#: milliseconds, and in a sweep every core already runs a cell of its own, so a helper thread
#: only adds GIL hand-offs (measured: a 16-cell sweep of 200 m scenes, 0.64 M posts each).
THREADED_MIN_POSTS = 1 << 21

T = TypeVar("T")
R = TypeVar("R")

_DONE = object()


def worth_a_thread(n_posts: int) -> bool:
    """Whether a terrain of ``n_posts`` posts is built and written with helper threads."""
    return n_posts >= THREADED_MIN_POSTS


def ordered_map(fn: Callable[[T], R], items: Iterable[T], *, workers: int, window: int,
                name: str = "marsscene-map") -> Iterator[R]:
    """``map(fn, items)`` on ``workers`` threads, yielded in order, at most ``window`` results
    computed ahead (memory stays bounded). For work that releases the GIL (Pillow, zlib, zstd,
    numpy). An exception is re-raised at its item; leaving the loop early cancels the rest."""
    if workers <= 1:
        yield from map(fn, items)
        return
    pending: deque[Future[R]] = deque()
    with ThreadPoolExecutor(workers, thread_name_prefix=name) as pool:
        try:
            for item in items:
                pending.append(pool.submit(fn, item))
                if len(pending) >= window:
                    yield pending.popleft().result()
            while pending:
                yield pending.popleft().result()
        finally:
            for f in pending:
                f.cancel()


def prefetch(items: Iterable[T], *, depth: int = 2, name: str = "marsscene-prefetch"
             ) -> Iterator[T]:
    """Yield ``items`` in order, produced by a background thread up to ``depth`` items ahead.

    An exception raised while producing an item is re-raised here, at that item. Closing the
    returned generator early (``break``, an exception in the consumer) stops the producer and
    joins it, so no thread outlives the loop.
    """
    buf: queue.Queue[object] = queue.Queue(maxsize=max(1, depth))
    stop = threading.Event()

    def produce() -> None:
        try:
            for item in items:
                while not stop.is_set():
                    try:
                        buf.put(item, timeout=0.05)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
        except BaseException as err:  # handed to the consumer, raised there
            buf.put(_Raised(err))
            return
        buf.put(_DONE)

    worker = threading.Thread(target=produce, name=name, daemon=True)
    worker.start()
    try:
        while True:
            got = buf.get()
            if got is _DONE:
                return
            if isinstance(got, _Raised):
                raise got.err
            yield got  # type: ignore[misc]
    finally:
        stop.set()
        while worker.is_alive():  # unblock a producer waiting on a full queue
            try:
                buf.get_nowait()
            except queue.Empty:
                worker.join(0.05)


class _Raised:
    __slots__ = ("err",)

    def __init__(self, err: BaseException) -> None:
        self.err = err
