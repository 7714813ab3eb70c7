"""What the model hands its work to, without Qt: a job, the runner protocol, and a runner that
runs each job at once in the caller's thread (scripts, headless tests).

The model's actions (:mod:`maizeviz_app.model`) describe work as ``func(job, *args)`` and
hand it to a runner with what to do with the result. In the window the runner is
:class:`maizeviz_app.workers.JobRunner` (a Qt thread pool; results come back to the GUI
thread); with no window it is :class:`InlineRunner`, so a script drives a whole study with
the same actions and the same core processes::

    runner = InlineRunner()
    model = StudyModel(runner=runner)
    model.open_points("plants.csv")      # loaded, then built at the level set, at once
    model.compute_light()
    runner.shutdown()
"""

from __future__ import annotations

import itertools
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from psygnal import Signal

from maizeviz_app.process import CoreProcess


@dataclass
class Job:
    """A unit of work: id, kind, what it is doing (for the status bar), a cancel flag."""

    id: int
    kind: str
    label: str
    runner: Any
    cancel: threading.Event = field(default_factory=threading.Event)
    started: float = field(default_factory=time.perf_counter)

    def report(self, done: int, total: int, text: str = "") -> bool:
        """Progress from any thread (``text``: what is being done, e.g. "time step 7 of 29";
        else the job's label); False once the job is cancelled (the work should stop)."""
        if self.cancel.is_set():
            return False
        self.runner._progress_from_thread(self, done, total, text)
        return not self.cancel.is_set()

    @property
    def cancelled(self) -> bool:
        return self.cancel.is_set()

    def check(self) -> None:
        """Raise InterruptedError if cancelled (between steps of a job)."""
        if self.cancel.is_set():
            raise InterruptedError(f"{self.kind} cancelled")


class JobTable:
    """The latest job of each kind (``_current``), shared by the runners."""

    _current: dict[str, Job]
    _closed: bool

    @property
    def closed(self) -> bool:
        return self._closed

    def running(self) -> list[Job]:
        """The latest job of each kind that has not finished."""
        return [j for j in self._current.values() if not j.cancelled]

    def current(self, kind: str) -> Job | None:
        return self._current.get(kind)


class Runner(Protocol):
    """What the model needs of a runner (:class:`InlineRunner`, ``workers.JobRunner``)."""

    cover_process: CoreProcess
    light_process: CoreProcess

    @property
    def closed(self) -> bool: ...

    def run(self, kind: str, label: str, func: Callable[..., Any], *args: Any,
            on_done: Callable[[Any], None],
            on_error: Callable[[BaseException], None] | None = None,
            supersede: bool = True) -> Job | None: ...

    def running(self) -> list[Job]: ...

    def current(self, kind: str) -> Job | None: ...

    def cancel(self, kind: str | None = None) -> None: ...


class InlineRunner(JobTable):
    """Runs each job at once, in the calling thread, with the core processes of the window
    (Embree work in children). ``on_done`` or ``on_error`` is called before :meth:`run`
    returns; an InterruptedError (a cancelled job) calls neither.

    Signals: ``progressed(job id, kind, text, done, total)``, ``changed()``.
    """

    progressed = Signal(int, str, str, int, int)
    changed = Signal()

    def __init__(self) -> None:
        self._ids = itertools.count(1)
        self._current: dict[str, Job] = {}
        self._closed = False
        self.cover_process = CoreProcess("cover")
        self.light_process = CoreProcess("light")
        #: every job run, in order (kind, label): what a script or test can check
        self.log: list[tuple[str, str]] = []

    def run(self, kind: str, label: str, func: Callable[..., Any], *args: Any,
            on_done: Callable[[Any], None],
            on_error: Callable[[BaseException], None] | None = None,
            supersede: bool = True) -> Job | None:
        if self._closed:
            return None
        job = Job(next(self._ids), kind, label, self)
        outer = self._current.get(kind)
        self._current[kind] = job
        self.log.append((kind, label))
        self.changed.emit()
        try:
            result, exc = func(job, *args), None
        except InterruptedError:
            return job
        except Exception as e:  # noqa: BLE001 - handed to on_error, as the window's runner
            result, exc = None, e
        finally:
            if self._current.get(kind) is job:
                if outer is not None:
                    self._current[kind] = outer
                else:
                    del self._current[kind]
            self.changed.emit()
        if exc is None:
            on_done(result)
        elif on_error is not None:
            on_error(exc)
        else:
            raise exc
        return job

    def cancel(self, kind: str | None = None) -> None:
        for k, job in list(self._current.items()):
            if kind is None or k == kind:
                job.cancel.set()

    def _progress_from_thread(self, job: Job, done: int, total: int, text: str = "") -> None:
        self.progressed.emit(job.id, job.kind, text or job.label, done, total)

    def shutdown(self, timeout_s: float = 10.0) -> bool:
        """Kill the core processes; no job runs afterwards."""
        self._closed = True
        self.cover_process.close()
        self.light_process.close()
        return True


def describe_internal(exc: BaseException) -> None:
    """Write an unexpected exception's traceback to stderr (the window shows one line)."""
    child = getattr(exc, "child_traceback", None)
    text = child or "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    print(f"maizeviz: internal error\n{text}", file=sys.stderr)
