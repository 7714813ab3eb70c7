"""Does the FASTRAK reader keep up? Paced 120 Hz output and an unpaced flood, through a pty.

The simulator runs in a child process (so its CPU is not counted) and writes records to a
pseudo-terminal; maizeviz's FastrakPort reader (pyserial + RecordParser, the code
``maizeviz record`` uses) reads them in this process. For each phase: records written,
records parsed, records lost (target 0), records per second and the reader's CPU share of one
core (process CPU time / wall time). The anchor is the device's own maximum: 120 records/s.

    python benchmarks/bench_serial.py [--json] [--seconds 10]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import time

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.protocol import Garbled, Record


def device(conn, seconds):
    from maizeviz.digitizer.simulator import FastrakSimulator

    sim = FastrakSimulator(noise_cm=0.08)
    conn.send(sim.path)
    cmd = conn.recv()                                  # the driver is configured
    sim.commands.clear()
    if cmd == "paced":
        sim.continuous = True                          # as after 'C': 120 Hz, one station
        time.sleep(seconds)
        sim.continuous = False
        time.sleep(0.2)
        conn.send(sim.records_sent)
    else:
        sent = sim.flood(seconds)
        time.sleep(0.5)
        conn.send(sent)
    conn.recv()
    sim.close()


def phase(kind, seconds):
    parent, child = mp.Pipe()
    proc = mp.get_context("fork").Process(target=device, args=(child, seconds))
    proc.start()
    path = parent.recv()
    port = FastrakPort(path, answer_timeout=1.0)
    port.configure((1,))                               # output list 2,4,16,1: 49-byte records
    counts = {"records": 0, "garbled": 0}

    def on_event(ev):
        if isinstance(ev, Record):
            counts["records"] += 1
        elif isinstance(ev, Garbled):
            counts["garbled"] += 1

    port.start_reader(on_event)
    cpu0, t0 = os.times(), time.perf_counter()
    parent.send(kind)
    sent = parent.recv()
    deadline = time.perf_counter() + 5
    while counts["records"] + counts["garbled"] < sent and time.perf_counter() < deadline:
        time.sleep(0.01)
    wall = time.perf_counter() - t0
    cpu1 = os.times()
    port.close()
    parent.send("done")
    proc.join(timeout=10)
    cpu = (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system)
    return {"phase": kind, "seconds": wall, "records_sent": sent, "records_parsed": counts["records"],
            "garbled": counts["garbled"], "lost": sent - counts["records"],
            "records_per_s": counts["records"] / wall, "cpu_share": cpu / wall,
            "over_device_max": counts["records"] / wall / 120.0}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args()
    out = {"phases": [phase("paced", args.seconds), phase("flood", args.seconds)],
           "targets": {"lost": 0}}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for p in out["phases"]:
            print(f"{p['phase']:>6}: {p['records_parsed']:,} of {p['records_sent']:,} records "
                  f"parsed, {p['lost']} lost, {p['records_per_s']:,.0f} records/s "
                  f"({p['over_device_max']:,.0f}x the device maximum), CPU {p['cpu_share']:.0%} "
                  "of one core")


if __name__ == "__main__":
    main()
