"""A child process for the core's work that holds the GIL: Embree scenes.

embreex builds its triangle buffers in a loop over Python-level array indexing and commits the
scene without releasing the GIL: on the 2.7 M-triangle K = 4 canopy that is seconds during
which no other Python thread of the process runs, the GUI thread included. So the work that
builds an Embree scene (ground cover, light) runs in a child process; the GUI process only
waits on a pipe, which releases the GIL.

- Children are forked from a ``forkserver`` that has imported the core once (no Qt in it), so
  a new child starts in milliseconds and a killed one costs nothing to replace.
- :meth:`CoreProcess.call` sends the canopy (once per canopy: the child keeps the last one and
  its Embree scene, so a second light run on the same canopy skips the scene build), then the
  request; it relays the child's progress (done, total and what is being done: "sky direction
  12 of 46") and checks for cancellation every 50 ms. Cancelling
  kills the child, which stops any work at once, whatever it is doing.
- Arrays travel out of band (pickle protocol 5 buffers written straight to the pipe), so the
  GUI process never copies a whole canopy while holding the GIL.

No Qt here: the process is driven from a worker thread.
"""

from __future__ import annotations

import multiprocessing as mp
import pickle
import struct
import threading
import traceback
from collections.abc import Callable
from typing import Any, Protocol

#: Modules the forkserver imports once, so children start with the core loaded.
PRELOAD = ["maizeviz_app.jobs"]
#: Seconds between checks for cancellation while waiting on the child.
POLL_S = 0.05


class Ticket(Protocol):
    """What :meth:`CoreProcess.call` needs from a job: progress out, cancellation in."""

    cancel: threading.Event

    def report(self, done: int, total: int, text: str = "") -> bool: ...


class ChildFailed(RuntimeError):
    """The child died or broke its pipe (not a cancellation)."""


def send(conn, obj: Any) -> None:
    """Pickle ``obj`` with its large buffers out of band; each buffer goes to the pipe as is."""
    buffers: list[pickle.PickleBuffer] = []
    head = pickle.dumps(obj, protocol=5, buffer_callback=buffers.append)
    conn.send_bytes(struct.pack("<I", len(buffers)) + head)
    for b in buffers:
        conn.send_bytes(b.raw())


def recv(conn) -> Any:
    head = conn.recv_bytes()
    (n,) = struct.unpack("<I", head[:4])
    buffers = [conn.recv_bytes() for _ in range(n)]
    return pickle.loads(memoryview(head)[4:], buffers=buffers)


def _context():
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(PRELOAD)
    return ctx


def serve(conn) -> None:
    """The child's loop: keep the last canopy and its scene, run requests, report progress."""
    from maizeviz_app import jobs

    state: dict[str, Any] = {}
    while True:
        try:
            msg = recv(conn)
        except (EOFError, OSError):
            return
        if msg[0] == "canopy":
            state.clear()
            state["canopy"] = msg[1]
            continue
        _, op, args = msg

        def progress(done: int, total: int, text: str = "") -> bool:
            send(conn, ("progress", done, total, text))
            return True

        try:
            value = jobs.OPS[op](state, progress, *args)
        except Exception as exc:  # noqa: BLE001 - everything goes back to the parent
            quantity = getattr(exc, "quantity", None)
            send(conn, ("error", type(exc).__module__, type(exc).__name__, str(exc), quantity,
                        traceback.format_exc()))
        else:
            send(conn, ("ok", value))


class CoreProcess:
    """One child process running core operations one at a time (see the module docstring).

    Thread-safe: calls from several threads queue on a lock; a cancelled caller that is
    still waiting for the lock leaves the queue without disturbing the running call.
    """

    def __init__(self, name: str):
        self.name = name
        self._lock = threading.Lock()
        self._proc: Any = None
        self._conn: Any = None
        self._key: object = None
        self._closed = False

    # ------------------------------------------------------------------ life cycle
    def start(self) -> None:
        """Start the child now (the forkserver too, the first time): a few seconds once per
        session, done early so the first real call does not wait."""
        with self._lock:
            self._ensure()

    def _ensure(self) -> None:
        if self._closed:
            raise InterruptedError("closing")
        if self._proc is not None and self._proc.is_alive():
            return
        ctx = _context()
        parent, child = ctx.Pipe()
        proc = ctx.Process(target=serve, args=(child,), name=f"maizeviz-{self.name}",
                           daemon=True)
        proc.start()
        child.close()
        self._proc, self._conn, self._key = proc, parent, None
        if self._closed:                       # closed while the child was starting
            self._kill()
            raise InterruptedError("closing")

    def _kill(self) -> None:
        proc, conn = self._proc, self._conn
        self._proc = self._conn = self._key = None
        if proc is not None:
            proc.kill()
            proc.join(2)
        if conn is not None:
            conn.close()

    def close(self) -> None:
        """Kill the child (whatever it is doing) and refuse further calls."""
        self._closed = True
        self._kill_now()

    def _kill_now(self) -> None:
        # a kill must not wait for the lock: the caller holding it is the one to stop
        proc = self._proc
        if proc is not None:
            try:
                proc.kill()
            except (OSError, ValueError, AttributeError):
                pass

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc is not None else None

    # ------------------------------------------------------------------ calls
    def call(self, op: str, key: object, canopy: Any, args: tuple, ticket: Ticket) -> Any:
        """Run ``jobs.OPS[op](state, progress, *args)`` in the child on ``canopy``.

        ``key`` identifies the canopy: the child keeps the last one (and what it built from
        it), so the canopy is sent only when the key changes.

        Raises
        ------
        InterruptedError
            The ticket was cancelled (the child was killed if it was working for it).
        Exception
            What the operation raised: a MaizevizError keeps its message and quantity.
        """
        while not self._lock.acquire(timeout=POLL_S):
            if ticket.cancel.is_set() or self._closed:
                raise InterruptedError(f"{op} cancelled")
        try:
            if ticket.cancel.is_set():
                raise InterruptedError(f"{op} cancelled")
            self._ensure()
            try:
                if self._key != key:
                    send(self._conn, ("canopy", canopy))
                    self._key = key
                send(self._conn, ("call", op, args))
                return self._wait(op, ticket)
            except (EOFError, OSError, BrokenPipeError) as exc:
                cancelled = ticket.cancel.is_set() or self._closed
                self._kill()
                if cancelled:
                    raise InterruptedError(f"{op} cancelled") from None
                raise ChildFailed(f"the {self.name} process stopped unexpectedly ({exc})") from None
        finally:
            self._lock.release()

    def _wait(self, op: str, ticket: Ticket) -> Any:
        conn = self._conn
        while True:
            if ticket.cancel.is_set() or self._closed:
                self._kill()
                raise InterruptedError(f"{op} cancelled")
            if not conn.poll(POLL_S):
                continue
            msg = recv(conn)
            if msg[0] == "progress":
                if not ticket.report(msg[1], msg[2], msg[3]):
                    self._kill()
                    raise InterruptedError(f"{op} cancelled")
            elif msg[0] == "ok":
                return msg[1]
            else:
                raise _rebuild(*msg[1:])


def _rebuild(module: str, name: str, message: str, quantity: str | None,
             trace: str) -> BaseException:
    """The child's exception, as close to the original as is safe to rebuild."""
    from maizeviz.errors import MaizevizError

    if module.startswith("maizeviz"):
        exc: BaseException = MaizevizError(message, quantity=quantity)
    elif name == "InterruptedError":
        exc = InterruptedError(message)
    elif name == "MemoryError":
        exc = MemoryError(message)
    else:
        exc = ChildFailed(f"{name}: {message}")
    exc.child_traceback = trace  # type: ignore[attr-defined]
    return exc


Op = Callable[..., Any]
