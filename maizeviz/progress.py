"""Progress and cancellation of long work, the same for the command line, the app and sweeps.

A long core function takes ``progress: ProgressCallback | None``; it calls
``progress(done, total)`` as work advances, and stops with :class:`InterruptedError` when the
callback returns ``False`` (the app's Cancel button, a superseded slider move). Plain Python, so
a terminal bar, a Qt signal or a Dask task can drive it.
"""

from __future__ import annotations

from collections.abc import Callable

#: ``progress(done, total)``; returning ``False`` asks the work to stop.
ProgressCallback = Callable[[int, int], "bool | None"]


def report(progress: ProgressCallback | None, done: int, total: int, what: str) -> None:
    """Tell ``progress`` how far ``what`` has come; raise InterruptedError if it says stop."""
    if progress is not None and progress(done, total) is False:
        raise InterruptedError(f"{what} cancelled")


def scaled(progress: ProgressCallback | None, offset: int, total: int) -> ProgressCallback | None:
    """A callback for a sub-task whose steps are ``offset + done`` of ``total`` overall."""
    if progress is None:
        return None
    return lambda done, _sub_total: progress(offset + done, total)
