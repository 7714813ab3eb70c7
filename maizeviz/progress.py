"""Progress and cancellation of long work, the same for the command line, the app and sweeps.

A long core function takes ``progress: ProgressCallback | None``; it calls
``progress(done, total)`` as work advances, and stops with :class:`InterruptedError` when the
callback returns ``False`` (the app's Cancel button, a superseded slider move). Plain Python, so
a terminal bar, a Qt signal or a Dask task can drive it. :func:`ordered_map` runs the parts of
such work on threads (Embree releases the GIL), in order, reporting and cancelling alike.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

#: ``progress(done, total)``; returning ``False`` asks the work to stop.
ProgressCallback = Callable[[int, int], "bool | None"]

T = TypeVar("T")
R = TypeVar("R")


def report(progress: ProgressCallback | None, done: int, total: int, what: str) -> None:
    """Tell ``progress`` how far ``what`` has come; raise InterruptedError if it says stop."""
    if progress is not None and progress(done, total) is False:
        raise InterruptedError(f"{what} cancelled")


def scaled(progress: ProgressCallback | None, offset: int, total: int) -> ProgressCallback | None:
    """A callback for a sub-task whose steps are ``offset + done`` of ``total`` overall."""
    if progress is None:
        return None
    return lambda done, _sub_total: progress(offset + done, total)


def ordered_map(fn: Callable[[T], R], items: Sequence[T], threads: int = 1,
                done: Callable[[int], None] | None = None,
                stop: threading.Event | None = None) -> Iterator[R]:
    """``fn`` over ``items`` on ``threads`` threads, results yielded in the items' order.

    Parameters
    ----------
    fn : callable of one item; it may check ``stop`` to give up early
    items : sequence of the work's parts (chunks of rays, directions)
    threads : int >= 1; 1 runs in the caller's thread, with no pool
    done : ``done(k)`` after the k-th result is yielded (k = 1 .. len(items)); it may raise
        (InterruptedError, from :func:`report`) to stop
    stop : set when the map ends early (an error, a cancel, the caller closing the
        generator), so that parts already running can stop; made here when None

    Yields
    ------
    ``fn(item)`` for each item, in order. Parts not yet started when the map ends early are
    cancelled; the first error raised by a part is raised here.
    """
    stop = threading.Event() if stop is None else stop
    if threads <= 1 or len(items) <= 1:
        for k, item in enumerate(items, 1):
            yield fn(item)
            if done is not None:
                done(k)
        return
    with ThreadPoolExecutor(max_workers=threads) as pool:
        futures = [pool.submit(fn, item) for item in items]
        try:
            for k, f in enumerate(futures, 1):
                yield f.result()
                if done is not None:
                    done(k)
        except BaseException:   # GeneratorExit too: the caller stopped reading
            stop.set()
            for f in futures:
                f.cancel()
            raise
