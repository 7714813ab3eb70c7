"""A scripted technician on a simulated FASTRAK, in a process of its own: the load test of a
recorder (``tests/gui/test_digitizer_load.py``, ``benchmarks/bench_gui.py``) and a way to
train on the app without a unit.

It opens a :class:`~maizeviz.digitizer.simulator.FastrakSimulator` (a real pty), waits for a
recorder to configure it, then presses the stylus at each point of a plan at a human pace.
Before a point of another leaf or plant it asks for the control (``n`` or ``p``) and waits
until it is confirmed, as a technician looks at the band before pressing on. It speaks one
line per event on standard output and reads confirmations on standard input:

- ``port PATH``: the pty to record from
- ``control KEY``: press KEY (``n``, ``p``) in the recorder, then write a line to standard input
- ``pressed K T``: press K (0-based) was accepted by the unit at ``time.time()`` T
- ``done``: every press was made

    python -m maizeviz.digitizer.technician [N] [PACE_MIN] [PACE_MAX] [SEED]
"""

from __future__ import annotations

import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable

import numpy as np

from maizeviz.digitizer.replay import wait_for_recorder
from maizeviz.digitizer.simulator import FastrakSimulator

#: Points per cross-section and cross-sections per leaf of the plan.
COLS, ROWS = 5, 5
#: Leaves per plant of the plan.
LEAVES = 4


def plan(n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """``n`` presses in digitizing order: plants of :data:`LEAVES` leaves, each
    :data:`ROWS` cross-sections of :data:`COLS` points.

    Returns
    -------
    ids : (n, 4) int, plant, leaf, row, col
    xyz : (n, 3) float64, cm; consecutive points of a leaf 3 cm apart across a section and
        about 15 cm from one section to the next (no jump to report)
    """
    per_leaf = COLS * ROWS
    k = np.arange(n)
    leaf_index, within = np.divmod(k, per_leaf)
    plant, leaf = np.divmod(leaf_index, LEAVES)
    row, col = np.divmod(within, COLS)
    ids = np.stack([plant + 1, leaf + 1, row, col], axis=1)
    xyz = np.stack([100.0 * plant + 8.0 * row,
                    -6.0 + 3.0 * col + 5.0 * (leaf % 2),
                    20.0 + 15.0 * leaf + 2.0 * row], axis=1)
    return ids, xyz


def run(n: int = 200, pace=(0.35, 0.5), seed: int = 0, out=sys.stdout, confirm=sys.stdin) -> int:
    """Press the plan's ``n`` points; returns the presses made."""
    ids, xyz = plan(n)
    rng = np.random.default_rng(seed)

    def say(line: str) -> None:
        print(line, file=out, flush=True)

    with FastrakSimulator(noise_cm=0.0) as sim:
        say(f"port {sim.path}")
        wait_for_recorder(sim)
        made = 0
        for k in range(n):
            if k and ids[k, 0] != ids[k - 1, 0] or k and ids[k, 1] != ids[k - 1, 1]:
                say(f"control {'p' if ids[k, 0] != ids[k - 1, 0] else 'n'}")
                if not confirm.readline():
                    return made                          # nobody is there any more
            while not sim.press(xyz[k]):                 # within the unit's 333 ms: again
                if sim.closed:
                    return made
                time.sleep(0.02)
            say(f"pressed {k} {time.time():.4f}")
            made += 1
            time.sleep(float(rng.uniform(*pace)))
        say("done")
        confirm.readline()                               # keep the port until told
    return made


class Technician:
    """The scripted technician's process, seen from the recorder's side (tests, benchmarks).

    Parameters
    ----------
    n : presses
    pace : (min, max) seconds between presses, drawn uniformly
    """

    def __init__(self, n: int = 200, pace=(0.35, 0.5), seed: int = 0):
        self.n = n
        self.ids, self.xyz = plan(n)
        self.pressed: dict[int, float] = {}
        self.done = False
        self._lines: queue.Queue = queue.Queue()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "maizeviz.digitizer.technician", str(n), str(pace[0]),
             str(pace[1]), str(seed)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            text=True, bufsize=1)
        self._reader = threading.Thread(target=self._pump, name="technician-out", daemon=True)
        self._reader.start()
        self.port = ""

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._lines.put(line.split())
        self._lines.put(None)

    def wait_port(self, timeout: float = 60.0) -> str:
        """The pty path, once the simulator is open."""
        words = self._lines.get(timeout=timeout)
        if not words or words[0] != "port":
            raise RuntimeError(f"the technician did not start: {words}")
        self.port = words[1]
        return self.port

    def follow(self, control: Callable[[str], None], where: Callable[[], tuple[int, int]],
               points: Callable[[], int], wait: Callable[[float], None],
               timeout: float = 600.0) -> None:
        """Run the session: pass each control on (``control(key)``), confirm it once
        ``where()`` (plant, leaf of the next point, as the recording shows it) has moved, and
        return once every press was made and ``points()`` counts them all, or at ``timeout``
        seconds. ``wait(s)`` lets the caller's event loop run."""
        deadline = time.monotonic() + timeout
        asked: tuple[int, int] | None = None
        while time.monotonic() < deadline:
            wait(0.02)
            while True:
                try:
                    words = self._lines.get_nowait()
                except queue.Empty:
                    break
                if words is None or words[0] == "done":
                    self.done = True
                elif words[0] == "control":
                    asked = where()
                    control(words[1])
                elif words[0] == "pressed":
                    self.pressed[int(words[1])] = float(words[2])
            if asked is not None and where() != asked:
                self.confirm()
                asked = None
            if self.done and points() >= len(self.pressed):
                return

    def confirm(self) -> None:
        """Tell the technician to go on."""
        try:
            assert self.proc.stdin is not None
            self.proc.stdin.write("ok\n")
            self.proc.stdin.flush()
        except (OSError, ValueError):
            pass

    def close(self) -> None:
        """End the technician (its simulator, so its port) and wait for it."""
        self.confirm()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self._reader.join(5)


if __name__ == "__main__":
    a = sys.argv[1:]
    run(int(a[0]) if a else 200, (float(a[1]) if len(a) > 1 else 0.35,
                                  float(a[2]) if len(a) > 2 else 0.5),
        int(a[3]) if len(a) > 3 else 0)
