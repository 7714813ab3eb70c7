"""Running a sweep on Dask (``dask.distributed``): a local cluster by default, or any scheduler.

Task granularity: one Dask task computes a *chunk* of one group, normally the whole group (all
suns, densities and periodic settings of one canopy, see :mod:`maizeviz.sweep.compute`). Inside
it the leaves are fitted once per file per worker (cached), and the canopy, its measures and its
Embree scene are built once and reused by every sun. Finer tasks (one per scenario) would rebuild
or ship the canopy to whichever worker Dask picks, and a 9 x 9 canopy's scene costs more than
many suns of tracing; coarser tasks are impossible (a scene cannot leave its process).

When there are fewer groups than twice the workers, groups are split into chunks of suns so
that every worker has work: each chunk rebuilds the group's canopy on its worker (a worker
running two chunks of a group reuses it from its cache), which pays when tracing dominates and
costs only CPU time otherwise. Tasks of finer levels are submitted with higher priority: the
longest tasks start first, so the last ones to finish are short.

Faults: a task whose worker dies is rescheduled by Dask on another worker (the local cluster's
nanny also restarts the dead worker); a task that raises is retried ``RETRIES`` times. A task
that still fails records its scenarios with status "failed" (retried by the next run); a
scenario with bad input is recorded with status "error" by the worker itself and costs nothing
else. Results are written as tasks finish (:class:`maizeviz.sweep.store.ResultStore`), so Ctrl-C
(futures cancelled, client and cluster closed) or a crash loses only the tasks in flight.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import os
import signal
import sys
import threading
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from maizeviz.errors import MaizevizError
from maizeviz.sweep import compute
from maizeviz.sweep.errors import SchedulerError
from maizeviz.sweep.store import ResultStore, now_iso

#: Times Dask reruns a task that raised (a worker dying is handled by Dask separately:
#: ``distributed.scheduler.allowed-failures``, 3 by default).
RETRIES = 2
#: Seconds between rebuilds of results.parquet / results.csv while a sweep runs.
FLUSH_EVERY_S = 30.0
#: Seconds to wait for an external scheduler before giving up.
CONNECT_TIMEOUT_S = 10.0
#: The longest wait for a scheduler, s: past an hour a scheduler that does not answer will not.
MAX_CONNECT_TIMEOUT_S = 3600.0


def check_connect_timeout(seconds: float) -> float:
    """Refuse a scheduler timeout that is not a number of seconds from 0.1 to
    :data:`MAX_CONNECT_TIMEOUT_S` (1e308 waited forever; NaN and -1 gave Dask's own
    messages)."""
    ok = isinstance(seconds, (int, float)) and not isinstance(seconds, bool) and \
        math.isfinite(seconds) and 0.1 <= seconds <= MAX_CONNECT_TIMEOUT_S
    if not ok:
        raise MaizevizError(f"the scheduler timeout must be from 0.1 to "
                            f"{MAX_CONNECT_TIMEOUT_S:g} s, got {seconds}",
                            quantity="connect_timeout")
    return float(seconds)
#: Dask settings of the local cluster. Our tasks are few and long, so the statistical profiler
#: (a thread sampling every worker's stack every 10 ms) and work stealing (tasks are queued on
#: the scheduler and handed out as workers free up) cost CPU for nothing, and the event-loop
#: health tick (20 ms) and memory monitor (100 ms) can be slower: measured here, an idle
#: 2-worker cluster then takes 2 % of a core instead of 16 %, which a 2-core laptop feels.
#: Dask also starts workers with MALLOC_TRIM_THRESHOLD_=65536, which pins glibc's mmap
#: threshold: every numpy array above 128 KiB is then mapped afresh and page-faulted, and the
#: same canopy and suns cost 20-40 % more CPU (system time) than in a plain process; the
#: variable is left unset, at the price of workers giving freed memory back to the system
#: less eagerly.
LOCAL_CONFIG = {"distributed.worker.profile.enabled": False,
                "distributed.scheduler.work-stealing": False,
                "distributed.admin.system-monitor.interval": "2s",
                "distributed.admin.tick.interval": "1s",
                "distributed.worker.memory.monitor-interval": "1s",
                "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@dataclass
class SweepOutcome:
    """What a run did. ``errors``: scenarios with bad input; ``failed``: scenarios whose task
    failed (worker died too often, internal error); both are in the results."""

    out: Path
    total: int
    already_done: int = 0
    computed: int = 0
    errors: int = 0
    failed: int = 0
    interrupted: bool = False
    seconds: float = 0.0
    tasks: int = 0
    cluster: dict = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        return not self.interrupted and self.already_done + self.computed == self.total


# --------------------------------------------------------------------------- the tasks
def plan_tasks(scenarios, n_workers: int) -> list[list]:
    """Scenarios to compute -> task chunks (each within one group), longest expected first.

    One chunk per group, unless there are fewer groups than ``2 n_workers``: then each group
    is split into up to ``ceil(2 n_workers / groups)`` chunks of consecutive scenarios.
    """
    groups: dict[str, list] = {}
    for s in scenarios:
        groups.setdefault(s.group_key, []).append(s)
    target = 2 * max(1, n_workers)
    split = 1 if len(groups) >= target else math.ceil(target / max(1, len(groups)))
    chunks = []
    for members in groups.values():
        k = min(split, len(members))
        size = math.ceil(len(members) / k)
        chunks += [members[i:i + size] for i in range(0, len(members), size)]
    # finer levels first (more triangles: longer canopy, scene and measure stages)
    chunks.sort(key=lambda c: (compute.level_order(c[0].level), -len(c)))
    return chunks


def run_chunk(scenarios) -> dict:
    """The Dask task: results of a chunk of one group, with the worker that ran it."""
    try:
        from distributed import get_worker

        worker = get_worker().address
    except (ImportError, ValueError):
        worker = f"local pid {os.getpid()}"
    return {"worker": worker, "results": compute.compute_scenarios(scenarios)}


# --------------------------------------------------------------------------- the cluster
def _has_dashboard() -> bool:
    return importlib.util.find_spec("bokeh") is not None


@contextmanager
def _sigint_ignored():
    """Worker processes started here ignore SIGINT: Ctrl-C on a terminal reaches the whole
    process group, and the driver, not each worker, should handle it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _worker_problem(client) -> str | None:
    """A line naming a worker without a usable maizeviz, or None."""
    import importlib.metadata as md

    import maizeviz

    try:
        versions = client.run(md.version, "maizeviz", on_error="return")
    except Exception as exc:                                    # noqa: BLE001 - any reply
        return f"cannot ask the workers for their maizeviz version ({type(exc).__name__})"
    mine = maizeviz.__version__.split(".")[:2]
    for addr, v in sorted(versions.items()):
        if not isinstance(v, str):
            return f"worker {addr} has no maizeviz installed: install it on every worker"
        if v.split(".")[:2] != mine:
            return (f"worker {addr} has maizeviz {v}, this machine {maizeviz.__version__}: "
                    "install the same version on every worker")
    return None


def describe_cluster(client, kind: str) -> dict:
    """Scheduler address, workers, threads, memory and dashboard of a client's cluster."""
    import distributed

    info = client.scheduler_info()
    workers = info.get("workers", {})
    return {"kind": kind, "scheduler": info.get("address"), "workers": len(workers),
            "threads": sum(w.get("nthreads", 0) for w in workers.values()),
            "memory_bytes": sum(w.get("memory_limit", 0) or 0 for w in workers.values()),
            "dashboard": client.dashboard_link if _has_dashboard() else None,
            "distributed": distributed.__version__}


def max_local_workers() -> int:
    """Most worker processes of a local cluster: 4 a core (at least 8). The tracing is CPU
    bound, so more only share the cores; 100,000 asked started processes for minutes."""
    return max(8, 4 * (os.cpu_count() or 1))


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None,
                connect_timeout: float = CONNECT_TIMEOUT_S):
    """A Dask client: on ``scheduler`` (``tcp://host:8786``), else on a new LocalCluster of
    ``workers`` processes (default: one per core) with one thread each. Closed on exit.

    Raises
    ------
    SchedulerError
        The scheduler does not answer within ``connect_timeout`` s, or a worker lacks maizeviz.
    """
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise SchedulerError(f"sweeps need dask.distributed ({exc}): pip install "
                             "'dask[distributed]' pyarrow tqdm") from None
    cluster = None
    if scheduler:
        connect_timeout = check_connect_timeout(connect_timeout)
        try:
            client = Client(scheduler, timeout=connect_timeout)
        except Exception as exc:                                # noqa: BLE001 - one line
            reason = (" ".join(str(exc).split()) if isinstance(exc, (OSError, TimeoutError,
                                                                    ValueError))
                      else f"not a Dask scheduler? {type(exc).__name__}")
            raise SchedulerError(f"cannot reach the Dask scheduler at {scheduler} within "
                                 f"{connect_timeout:g} s ({reason})") from None
        problem = _worker_problem(client)
        if problem:
            client.close()
            raise SchedulerError(problem)
        kind = "scheduler"
    else:
        n = workers or os.cpu_count() or 1
        most = max_local_workers()
        if not 1 <= n <= most:
            raise SchedulerError(f"--workers must be from 1 to {most} on this machine (4 a "
                                 f"core of its {os.cpu_count() or 1}; a process each), got {n:,}")
        try:
            with _sigint_ignored(), dask.config.set(LOCAL_CONFIG):
                cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                       dashboard_address=":0",   # a free port, no clash
                                       silence_logs=logging.CRITICAL)
            client = Client(cluster)
        except Exception as exc:                                # noqa: BLE001 - one line
            if cluster is not None:
                cluster.close()
            raise SchedulerError(f"cannot start a local Dask cluster of {n} workers "
                                 f"({type(exc).__name__}: {' '.join(str(exc).split())})") from None
        kind = "LocalCluster"
    try:
        yield client, kind
    finally:
        try:
            client.close()
        finally:
            if cluster is not None:
                cluster.close()


# ------------------------------------------------------------------------------ progress
class _Progress:
    """A tqdm bar (done/total, rate, ETA) on a terminal, else a line every 10 s (``bar``
    None); always the bar (True); nothing (False)."""

    def __init__(self, total: int, initial: int, bar: bool | None, say):
        self.say = say if bar is not False else (lambda _msg: None)
        self.total = total
        self.done = initial
        self.t0 = time.monotonic()
        self.last = self.t0
        self.initial = initial
        self.bar = None
        if bar is None:
            bar = sys.stderr.isatty()
        if bar:
            import shutil

            from tqdm import tqdm

            size = shutil.get_terminal_size((0, 0))
            sized = size.columns > 0 and size.lines > 0     # a pty may have no size: tqdm
            self.bar = tqdm(total=total, initial=initial, unit="scenario", file=sys.stderr,
                            dynamic_ncols=sized, ncols=None if sized else 100,   # would hide
                            nrows=None if sized else 50, smoothing=0.1, desc="sweep")

    def update(self, n: int, bad: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(n)
            if bad:
                self.bar.set_postfix_str(f"{bad} in error")
            return
        now = time.monotonic()
        if now - self.last >= 10.0 or self.done == self.total:
            self.last = now
            rate = (self.done - self.initial) / max(now - self.t0, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            self.say(f"sweep: {self.done}/{self.total} scenarios, {rate:.2f}/s, "
                     f"ETA {eta:.0f} s{f', {bad} in error' if bad else ''}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# ------------------------------------------------------------------------------- the run
class _CtrlC:
    """Ctrl-C raises KeyboardInterrupt as usual, except while a result is being recorded:
    then it is held until the part file and the counts agree, so that what the run says it
    kept is exactly what is on disk."""

    def __init__(self):
        self.depth = 0
        self.pending = False
        self.asked = False
        self.old = None

    def _handler(self, signum, frame):
        self.asked = True
        if self.depth:
            self.pending = True
        else:
            # raised wherever the main thread is; inside a finalizer (distributed's
            # Future.__del__) Python ignores it, so the driving loop also polls ``asked``
            raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed (and not yet raised where it
        counts)."""
        if self.asked:
            raise KeyboardInterrupt

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self.old = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc):
        if self.old is not None:
            signal.signal(signal.SIGINT, self.old)
        return False

    @contextmanager
    def held(self):
        self.depth += 1
        try:
            yield
        finally:
            self.depth -= 1
            if self.pending and not self.depth:
                self.pending = False
                raise KeyboardInterrupt


def _failure(exc: BaseException | None) -> str:
    if exc is None:
        return "the task was cancelled (the scheduler restarted or lost it)"
    name = type(exc).__name__
    if name == "KilledWorker":
        return ("the workers computing it died repeatedly (out of memory? see the worker "
                "logs)")
    return f"internal error: {name}: {' '.join(str(exc).split())}"[:500]


def run_sweep(spec, out, *, workers: int | None = None, scheduler: str | None = None,
              connect_timeout: float = CONNECT_TIMEOUT_S, resume: bool = True,
              force: bool = False, client=None, progress: bool | None = None, say=None,
              on_result=None) -> SweepOutcome:
    """Compute every scenario of ``spec`` not yet in ``out``; results written as they finish.

    Parameters
    ----------
    spec : SweepSpec
    out : folder of the results (see :mod:`maizeviz.sweep.store`)
    workers, scheduler, connect_timeout : the cluster (see :func:`dask_client`); ignored when
        ``client`` (an open ``distributed.Client``, left open) is given
    resume, force : see :class:`~maizeviz.sweep.store.ResultStore`
    progress : True / False for the bar; None: when stderr is a terminal
    say : callable(str) for messages (default: stderr)
    on_result : callable(outcome) after each task's results are on disk

    Returns
    -------
    SweepOutcome; ``interrupted`` after Ctrl-C (KeyboardInterrupt is not raised again).

    Raises
    ------
    SweepStoreError, SchedulerError
    """
    say = say or (lambda m: print(m, file=sys.stderr, flush=True))
    store = ResultStore(out, spec, resume=resume, force=force)
    done = store.done_keys()
    todo = [s for s in spec.scenarios if s.key not in done]
    outcome = SweepOutcome(Path(out), len(spec.scenarios), len(done))
    t0 = time.perf_counter()
    if not todo:
        say(f"all {len(spec.scenarios)} scenarios are already in {out}")
        store.flush()
        return outcome
    if done:
        say(f"resuming: {len(done)} of {len(spec.scenarios)} scenarios already in {out}")

    own = client is None
    ctx = dask_client(workers, scheduler, connect_timeout) if own else _given(client)
    run = None
    bar = None
    ctrl_c = _CtrlC()
    try:
        with ctrl_c, ctx as (cl, kind):
            outcome.cluster = describe_cluster(cl, kind)
            if outcome.cluster["dashboard"]:
                say(f"Dask dashboard: {outcome.cluster['dashboard']}")
            if not outcome.cluster["workers"]:
                say("warning: the scheduler has no workers yet; the tasks wait for some")
            n_workers = max(1, outcome.cluster["workers"])
            chunks = plan_tasks(todo, n_workers)
            outcome.tasks = len(chunks)
            run = store.start_run(dict(outcome.cluster, tasks=len(chunks),
                                       **compute.describe_core()))
            bar = _Progress(len(spec.scenarios), len(done), progress, say)
            _drive(cl, chunks, store, outcome, bar, on_result, ctrl_c)
    except KeyboardInterrupt:
        outcome.interrupted = True
    finally:
        if bar is not None:
            bar.close()
        outcome.seconds = time.perf_counter() - t0
        if run is not None:
            store.flush()
            run.update(finished=now_iso(), computed=outcome.computed, errors=outcome.errors,
                       failed=outcome.failed, interrupted=outcome.interrupted,
                       seconds=outcome.seconds)
            store.write_info()
    if outcome.interrupted:
        on_disk = outcome.already_done + outcome.computed
        say(f"interrupted: {on_disk} of {outcome.total} scenarios are in {out}; run the same "
            "command again to compute the rest")
    return outcome


@contextmanager
def _given(client):
    yield client, "given client"


def _completed(pending, ctrl_c, poll_s: float = 0.05):
    """The futures of ``pending`` (a distributed ``as_completed``) as they finish, polled so
    that a Ctrl-C whose KeyboardInterrupt was lost in a finalizer still stops the run."""
    while not pending.is_empty():
        ctrl_c.check()
        ready = pending.next_batch(block=False)
        if not ready:
            time.sleep(poll_s)
            continue
        for fut in ready:
            ctrl_c.check()
            yield fut


def _drive(client, chunks, store, outcome, bar, on_result, ctrl_c) -> None:
    """Submit the chunks and record their results as they complete."""
    from distributed import as_completed

    run_id = uuid.uuid4().hex[:8]
    futures = {}
    for i, chunk in enumerate(chunks):
        key = f"maizeviz-sweep-{chunk[0].group_key[:10]}-{i}-{run_id}"
        fut = client.submit(run_chunk, chunk, key=key, retries=RETRIES,
                            priority=len(chunks) - i)
        futures[fut] = chunk
    last_flush = time.monotonic()
    try:
        for fut in _completed(as_completed(list(futures)), ctrl_c):
            chunk = futures.pop(fut)
            if fut.status == "finished":
                res = fut.result()
                for s, r in zip(chunk, res["results"]):
                    with ctrl_c.held():
                        store.add(s, r, res["worker"])
                        if r["status"] == "failed":        # retried by the next run
                            outcome.failed += 1
                        else:
                            outcome.computed += 1
                            outcome.errors += r["status"] == "error"
            else:
                msg = _failure(fut.exception() if fut.status == "error" else None)
                for s in chunk:
                    with ctrl_c.held():
                        store.add(s, {"status": "failed", "error": msg})
                        outcome.failed += 1
            del fut
            bar.update(len(chunk), outcome.errors + outcome.failed)
            if on_result is not None:
                on_result(outcome)
            if time.monotonic() - last_flush > FLUSH_EVERY_S:
                with ctrl_c.held():
                    store.flush()
                last_flush = time.monotonic()
    except BaseException:
        client.cancel(list(futures))
        raise
