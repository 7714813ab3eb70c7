"""Replay a points file through the simulator as a technician would digitize it."""

from __future__ import annotations

import time

import numpy as np

from maizeviz.io.points import read_points


def presses_of(path):
    """The points of a file in digitizing order: plant, leaf, row, col.

    Returns (ids (N, 4) int, xyz (N, 3) cm).
    """
    table = read_points(path)
    order = np.lexsort((table.ids[:, 3], table.ids[:, 2], table.ids[:, 1], table.ids[:, 0]))
    return table.ids[order], table.xyz[order]


def wait_for_recorder(sim, timeout: float | None = None) -> bool:
    """Block until a driver has put the stylus in point mode (its start-up is done)."""
    t0 = time.monotonic()
    while not any(c.startswith("e1,") for c in sim.commands):
        if timeout is not None and time.monotonic() - t0 > timeout:
            return False
        time.sleep(0.05)
    time.sleep(0.2)
    return True


def replay_points(sim, path, pace: float = 1.0, faults: bool = False, sway: bool = False,
                  say=print, wait: bool = True) -> int:
    """Press the stylus at every point of ``path``; ``say`` tells the technician the controls.

    With ``sway`` the reference receiver (station 2) moves and turns between presses while
    the points stay fixed to the plant. With ``faults`` garbage, a truncated record and a BIT
    error are injected, and the port vanishes before the last leaf. Returns presses made.
    """
    ids, xyz = presses_of(path)
    if wait:
        wait_for_recorder(sim)
    say(f"replaying {len(ids)} points from {path}")
    made = 0
    last_leaf = (int(ids[0, 0]), int(ids[0, 1])) if len(ids) else (-1, -1)
    last_leaf_start = int(np.flatnonzero(np.any(ids[:, :2] != ids[-1, :2], axis=1)).max() + 1) \
        if len(ids) and np.any(ids[:, :2] != ids[-1, :2]) else len(ids)
    for k, (key, p) in enumerate(zip(ids, xyz)):
        if sim.closed:
            break
        leaf = (int(key[0]), int(key[1]))
        if leaf != last_leaf:
            say("type p (next plant) in the recorder" if leaf[0] != last_leaf[0]
                else "type n (next leaf) in the recorder")
            time.sleep(max(pace, 0.4))
            last_leaf = leaf
        if faults and k == last_leaf_start:
            say("fault: the port vanishes")
            sim.vanish()
            return made
        if sway:
            t = 0.3 * k
            sim.move_reference([2.0 * np.sin(t), 1.5 * np.cos(t), 0.5 * np.sin(2 * t)],
                               [5.0 * np.sin(t), 2.0 * np.cos(t), 3.0 * np.sin(t)])
        if faults and k % 7 == 3:
            sim.inject(b"\x00\xff#noise#\r\n")
        if faults and k % 11 == 5:
            sim.inject(b"01   12.34  -5.6\r\n")
        if faults and k % 13 == 6:
            sim.set_error("x")
            while not sim.press(p, plant_frame=sway):
                time.sleep(0.05)
            sim.set_error(" ")
            say("fault: that press was out of the motion box; pressing again")
            time.sleep(max(pace, 0.34))
        while not sim.press(p, plant_frame=sway):
            if sim.closed:
                return made
            time.sleep(0.05)
        made += 1
        time.sleep(max(pace, 0.34))
    if not sim.closed:
        say("replay done: type q in the recorder")
    return made
