"""Jobs the app hands to threads (and, through them, to the core processes): the one worker
system of the app. The window's runner uses Qt's global pool; a panel that needs its own
ordering (the digitizer's connection, the growing plant's one-leaf-at-a-time meshing) gives its
runner a pool of its own.

Jobs run on a Qt thread pool as plain QRunnables started at once, and their results
come back through the runner's own queued signal. (superqt's ``create_worker`` starts a worker
from a 1 ms timer when an event loop runs, so a job asked for just before the window closed
could start after it; and its queued ``returned`` is lost when the worker object is deleted
first. Both made closing racy: issue 9's "Signal source has been deleted".)

Each job has an id, a kind (``load``, ``build``, ``light``...), a cancel flag and a progress
channel. A newer job of the same kind supersedes the running one (its result is dropped: the
window only takes results from the latest job of each kind, as napari's async slicing drops
stale slices). Work that builds Embree scenes runs in :class:`~maizeviz_app.process.CoreProcess`
children, killed on cancel, so Cancel takes effect within a poll interval (50 ms).

After :meth:`JobRunner.shutdown` (the window is closing) no result, error or progress reaches
the window any more, and nothing new starts: a result already queued when the window closed
is dropped instead of starting a build on a closed window.
"""

from __future__ import annotations

import itertools
import sys
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, QRunnable, QThreadPool, Signal

from maizeviz_app.process import CoreProcess
from maizeviz_app.runner import Job, JobTable, describe_internal  # noqa: F401 - the app's names


class JobRunner(QObject, JobTable):
    """Runs jobs on the thread pool; see the module docstring.

    Signals (GUI thread): ``progressed(job id, kind, text, done, total)`` (text: what the job
    is doing now, or its label), ``changed()`` when the set of running jobs changes.
    """

    progressed = Signal(int, str, str, int, int)
    changed = Signal()
    _progress_signal = Signal(int, int, int, str)
    _delivered = Signal(int, object, object)

    def __init__(self, parent=None, pool: QThreadPool | None = None):
        super().__init__(parent)
        self.pool = pool if pool is not None else QThreadPool.globalInstance()
        self._ids = itertools.count(1)
        self._current: dict[str, Job] = {}
        self._handlers: dict[int, tuple] = {}
        self._tasks: dict[int, QRunnable] = {}
        self._closed = False
        self._progress_signal.connect(self._on_progress)
        # results come back through the runner's own signal (queued to the GUI thread), so a
        # result that arrives after shutdown is seen, and dropped, here
        self._delivered.connect(self._on_delivered)
        #: The core processes: Embree work off the GIL (see maizeviz_app.process).
        self.cover_process = CoreProcess("cover")
        self.light_process = CoreProcess("light")

    # ------------------------------------------------------------------ running
    def run(self, kind: str, label: str, func: Callable[..., Any], *args: Any,
            on_done: Callable[[Any], None],
            on_error: Callable[[BaseException], None] | None = None,
            supersede: bool = True) -> Job | None:
        """Run ``func(job, *args)`` on a worker thread; ``on_done(result)`` on the GUI thread
        if it is still the latest ``kind`` job when it returns (an InterruptedError from
        ``func`` means it stopped: nothing is called). Returns the job, or None after
        shutdown."""
        if self._closed:
            return None
        old = self._current.get(kind)
        if old is not None and supersede:
            old.cancel.set()
        job = Job(next(self._ids), kind, label, self)
        self._current[kind] = job
        self._handlers[job.id] = (kind, on_done, on_error)
        delivered = self._delivered

        def guarded() -> None:
            exc: BaseException | None
            try:
                result, exc = func(job, *args), None
            except InterruptedError:                  # superseded, cancelled or closing
                result, exc = None, InterruptedError()
            except Exception as e:  # noqa: BLE001 - handed to the GUI thread
                result, exc = None, e
            try:
                delivered.emit(job.id, result, exc)
            except RuntimeError:                      # the runner is gone
                pass

        task = _Task(guarded)
        self._tasks[job.id] = task
        self.pool.start(task)
        self.changed.emit()
        return job

    def _on_delivered(self, job_id: int, result: Any, exc: BaseException | None) -> None:
        self._tasks.pop(job_id, None)
        kind, on_done, on_error = self._handlers.pop(job_id, (None, None, None))
        job = self._current.get(kind) if kind is not None else None
        if job is not None and job.id == job_id:
            del self._current[kind]
            if not self._closed:
                self.changed.emit()
        else:
            job = None                                # superseded by a newer job
        if self._closed or job is None or job.cancelled or isinstance(exc, InterruptedError):
            return
        try:
            if exc is None:
                if on_done is not None:
                    on_done(result)
            elif on_error is not None:
                on_error(exc)
        except Exception as exc2:  # noqa: BLE001 - a slot must not let an exception escape
            describe_internal(exc2)
            if exc is None and on_error is not None:
                try:
                    on_error(exc2)
                except Exception as exc3:  # noqa: BLE001
                    describe_internal(exc3)

    def cancel(self, kind: str | None = None) -> None:
        """Cancel the running job of ``kind`` (all jobs when None); returns at once."""
        for k, job in list(self._current.items()):
            if kind is None or k == kind:
                job.cancel.set()
        self.changed.emit()

    # ------------------------------------------------------------------ progress
    def _progress_from_thread(self, job: Job, done: int, total: int, text: str = "") -> None:
        if self._closed:
            return
        try:
            self._progress_signal.emit(job.id, done, total, text)
        except RuntimeError:                           # the runner is gone: stop the job
            job.cancel.set()

    def _on_progress(self, job_id: int, done: int, total: int, text: str) -> None:
        if self._closed:
            return
        for job in self._current.values():
            if job.id == job_id and not job.cancelled:
                self.progressed.emit(job.id, job.kind, text or job.label, done, total)

    # ------------------------------------------------------------------ closing
    def shutdown(self, timeout_s: float = 10.0) -> bool:
        """Stop everything: no more results or progress, cancel every job, kill the core
        processes, wait (up to ``timeout_s``) for the threads. True if all stopped."""
        self._closed = True
        self._handlers.clear()
        for job in self._current.values():
            job.cancel.set()
        self.cover_process.close()
        self.light_process.close()
        ok = self.pool.waitForDone(int(timeout_s * 1000))
        if not ok:
            print("maizeviz: some work was still running when the window closed",
                  file=sys.stderr)
        return ok


class _Task(QRunnable):
    """A function on the thread pool (kept alive by the runner until its result is back)."""

    def __init__(self, fn: Callable[[], None]):
        super().__init__()
        self.setAutoDelete(False)
        self._fn = fn

    def run(self) -> None:
        self._fn()
