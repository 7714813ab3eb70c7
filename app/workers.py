"""Jobs the window hands to threads (and, through them, to the core processes).

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
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from PySide6.QtCore import QObject, QThreadPool, Signal

from maizeviz_app.process import CoreProcess


@dataclass
class Job:
    """A unit of work: id, kind, what it is doing (for the status bar), a cancel flag."""

    id: int
    kind: str
    label: str
    runner: "JobRunner"
    cancel: threading.Event = field(default_factory=threading.Event)
    started: float = field(default_factory=time.perf_counter)

    def report(self, done: int, total: int) -> bool:
        """Progress from any thread; False once the job is cancelled (the work should stop)."""
        if self.cancel.is_set():
            return False
        self.runner._progress_from_thread(self, done, total)
        return not self.cancel.is_set()

    @property
    def cancelled(self) -> bool:
        return self.cancel.is_set()

    def check(self) -> None:
        """Raise InterruptedError if cancelled (between steps of a job)."""
        if self.cancel.is_set():
            raise InterruptedError(f"{self.kind} cancelled")


class JobRunner(QObject):
    """Runs jobs on superqt thread workers; see the module docstring.

    Signals (GUI thread): ``progressed(job id, kind, label, done, total)``, ``changed()`` when
    the set of running jobs changes.
    """

    progressed = Signal(int, str, str, int, int)
    changed = Signal()
    _progress_signal = Signal(int, int, int)

    def __init__(self, parent=None):
        super().__init__(parent)
        self._ids = itertools.count(1)
        self._current: dict[str, Job] = {}
        self._workers: set = set()
        self._closed = False
        self._lock = threading.Lock()
        self._progress_signal.connect(self._on_progress)
        #: The core processes: Embree work off the GIL (see maizeviz_app.process).
        self.cover_process = CoreProcess("cover")
        self.light_process = CoreProcess("light")

    # ------------------------------------------------------------------ running
    @property
    def closed(self) -> bool:
        return self._closed

    def running(self) -> list[Job]:
        """The latest job of each kind that has not finished."""
        return [j for j in self._current.values() if not j.cancelled]

    def current(self, kind: str) -> Job | None:
        return self._current.get(kind)

    def run(self, kind: str, label: str, func: Callable[..., Any], *args: Any,
            on_done: Callable[[Any], None],
            on_error: Callable[[BaseException], None] | None = None,
            supersede: bool = True) -> Job | None:
        """Run ``func(job, *args)`` on a worker thread; ``on_done(result)`` on the GUI thread
        if it is still the latest ``kind`` job when it returns. A result of None means the job
        stopped (cancelled) and calls nothing. Returns the job, or None after shutdown."""
        if self._closed:
            return None
        from superqt.utils import create_worker

        old = self._current.get(kind)
        if old is not None and supersede:
            old.cancel.set()
        job = Job(next(self._ids), kind, label, self)
        self._current[kind] = job

        def guarded(j: Job, *a: Any) -> Any:
            try:
                return func(j, *a)
            except InterruptedError:                  # superseded, cancelled or closing
                return None

        worker = create_worker(guarded, job, *args, _start_thread=False, _ignore_errors=True)

        def done(result: Any) -> None:
            if self._closed or self._current.get(kind) is not job or job.cancelled:
                return
            if result is None:
                return
            try:
                on_done(result)
            except Exception as exc:  # noqa: BLE001 - a slot must not let an exception escape
                describe_internal(exc)
                if on_error is not None:
                    on_error(exc)

        def error(exc: BaseException) -> None:
            if self._closed or self._current.get(kind) is not job or job.cancelled:
                return
            if on_error is not None:
                try:
                    on_error(exc)
                except Exception as exc2:  # noqa: BLE001 - a slot must not raise
                    describe_internal(exc2)

        def finished() -> None:
            self._workers.discard(worker)
            if self._current.get(kind) is job:
                del self._current[kind]
            if not self._closed:
                self.changed.emit()

        worker.returned.connect(done)
        worker.errored.connect(error)
        worker.finished.connect(finished)
        self._workers.add(worker)
        worker.start()
        self.changed.emit()
        return job

    def cancel(self, kind: str | None = None) -> None:
        """Cancel the running job of ``kind`` (all jobs when None); returns at once."""
        for k, job in list(self._current.items()):
            if kind is None or k == kind:
                job.cancel.set()
        self.changed.emit()

    # ------------------------------------------------------------------ progress
    def _progress_from_thread(self, job: Job, done: int, total: int) -> None:
        if self._closed:
            return
        try:
            self._progress_signal.emit(job.id, done, total)
        except RuntimeError:                           # the runner is gone: stop the job
            job.cancel.set()

    def _on_progress(self, job_id: int, done: int, total: int) -> None:
        if self._closed:
            return
        for job in self._current.values():
            if job.id == job_id and not job.cancelled:
                self.progressed.emit(job.id, job.kind, job.label, done, total)

    # ------------------------------------------------------------------ closing
    def shutdown(self, timeout_s: float = 10.0) -> bool:
        """Stop everything: no more results or progress, cancel every job, kill the core
        processes, wait (up to ``timeout_s``) for the threads. True if all stopped."""
        self._closed = True
        for job in self._current.values():
            job.cancel.set()
        self.cover_process.close()
        self.light_process.close()
        for worker in list(self._workers):
            try:
                worker.quit()
            except RuntimeError:
                pass
        ok = QThreadPool.globalInstance().waitForDone(int(timeout_s * 1000))
        if not ok:
            print("maizeviz: some work was still running when the window closed",
                  file=sys.stderr)
        return ok


def describe_internal(exc: BaseException) -> None:
    """Write an unexpected exception's traceback to stderr (the window shows one line)."""
    child = getattr(exc, "child_traceback", None)
    text = child or "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    print(f"maizeviz: internal error\n{text}", file=sys.stderr)
