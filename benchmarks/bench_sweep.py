"""A sweep on Dask against the same scenarios in a plain loop: overhead and speedup.

24 scenarios on the bundled 3x3 block: 4 mesh levels (K4, standard, 36, 8) x 6 suns, periodic
field, transmission at 6 heights. They are computed three ways, each from cold caches:

- ``serial_seconds``: a plain loop over the groups in this process (``compute_scenarios``);
- ``seconds_1_worker``: ``run_sweep`` on a LocalCluster of 1 worker process;
- ``seconds_2_workers``: the same on 2 worker processes.

Cluster start-up is not counted (workers are started and have imported maizeviz before the
clock starts); writing the results is. ``speedup`` = 1 worker / 2 workers; ``overhead_per_
task_s`` = (1 worker - serial) / Dask tasks. With ``--repeat`` the best of each is kept (shared,
noisy machines); the anchor (a fixed numpy workload) is measured in the same run.

Wall times on a machine other jobs keep busy say little about Dask, so CPU seconds are reported
too (``cpu``): the 1-worker run's CPU (workers, and this process: client, scheduler, nannies)
over the loop's is the overhead, and the 1-worker run's worker CPU over the busiest worker's in
the 2-worker run is the speedup two free cores would give (``speedup_on_free_cores``). Each
repeat runs the loop and the 1-worker sweep back to back, so the two see about the same load:
``paired`` gives each repeat's 1-worker / serial ratios (wall and CPU) and their medians, the
figure to read on a shared machine (the best-of wall times pair a quiet moment of one with a
busy moment of the other).
Targets: speedup >= 1.6 on 2 cores; the 1-worker sweep within 5 % of the serial loop.

    python benchmarks/bench_sweep.py [--json] [--tile 1x1] [--density 32] [--repeat 1]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import statistics
import tempfile
import time
from pathlib import Path

from anchors import matmul_anchor

from maizeviz.sweep import compute
from maizeviz.sweep.run import LOCAL_CONFIG, plan_tasks, run_sweep
from maizeviz.sweep.spec import load_spec
from maizeviz.sweep.store import read_results

ROOT = Path(__file__).resolve().parents[1]
SUNS = [(20, 180), (30, 135), (40, 225), (50, 90), (60, 270), (35, 160)]
LEVELS = ["K4", "standard", "36", "8"]


def write_spec(folder: Path, points: str, tile: str, density: float) -> Path:
    suns = ", ".join(f"{{zenith = {z}, azimuth = {a}}}" for z, a in SUNS)
    text = (f'[canopy]\npoints = ["{points}"]\ntile = ["{tile}"]\n'
            f"level = {json.dumps(LEVELS)}\n"
            f"[light]\nsun = [{suns}]\ndensity = [{density}]\n"
            "heights = [0, 50, 100, 150, 200, 225]\nperiodic = true\n")
    path = folder / "bench.toml"
    path.write_text(text)
    return path


def serial(spec) -> tuple[float, float, dict]:
    """Wall and CPU seconds of the plain loop, and the transmissions by scenario key."""
    compute.clear_caches()
    c0, t0 = time.process_time(), time.perf_counter()
    out = {}
    for group in spec.groups():
        for r in compute.compute_scenarios(group):
            out[r["key"]] = r["transmission"]
    return time.perf_counter() - t0, time.process_time() - c0, out


def on_cluster(client, spec, out: Path) -> tuple[float, float, list, dict]:
    """Wall seconds of the sweep, CPU seconds of this process (client, scheduler, nannies),
    CPU seconds of each worker, and the transmissions by scenario key."""
    client.run(compute.clear_caches)
    w0 = client.run(time.process_time)
    c0, t0 = time.process_time(), time.perf_counter()
    outcome = run_sweep(spec, out, client=client, progress=False, resume=False,
                        say=lambda _m: None)
    seconds, driver = time.perf_counter() - t0, time.process_time() - c0
    w1 = client.run(time.process_time)
    assert outcome.complete and outcome.errors == 0 and outcome.failed == 0, outcome
    rows = read_results(out)
    got = {}
    for r in rows:
        got.setdefault(r["scenario"], []).append(r["transmission"])
    return seconds, driver, sorted(w1[w] - w0[w] for w in w0), got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--points", default=str(ROOT / "maizeviz" / "resources" / "block3x3.csv"))
    ap.add_argument("--tile", default="1x1", help="tiling of the block (default 1x1)")
    ap.add_argument("--density", type=float, default=32.0,
                    help="rays per cm2 (default 32: tracing about half the work)")
    ap.add_argument("--repeat", type=int, default=1, help="best of N (default 1)")
    args = ap.parse_args()
    import dask
    import pyarrow.parquet  # noqa: F401  - imported once here, not inside the first timing
    from distributed import Client, LocalCluster

    logging.getLogger("distributed").setLevel(logging.ERROR)
    tmp = Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    spec = load_spec(write_spec(tmp, str(Path(args.points).resolve()), args.tile, args.density))
    clusters = {}
    for n in (1, 2):
        with dask.config.set(LOCAL_CONFIG):                 # as maizeviz sweep starts it
            cl = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                              dashboard_address=":0", silence_logs=logging.CRITICAL)
        client = Client(cl)
        client.run(__import__, "maizeviz.sweep.compute")
        clusters[n] = (cl, client)
    best = {"serial": float("inf"), 1: float("inf"), 2: float("inf")}
    cpu = {"serial": float("inf"), 1: None, 2: None}
    same = True
    paired: list[tuple[float, float]] = []           # (wall, CPU) 1 worker / serial, per repeat
    load = [os.getloadavg()[0]]
    anchor_s = min(matmul_anchor() for _ in range(3))
    try:
        for i in range(args.repeat):
            s, c, ref = serial(spec)
            best["serial"] = min(best["serial"], s)
            cpu["serial"] = min(cpu["serial"], c)
            for n in (1, 2):
                t, driver, workers, got = on_cluster(clusters[n][1], spec, tmp / f"out{n}_{i}")
                if n == 1:
                    paired.append((t / s, (driver + sum(workers)) / c))
                if t < best[n]:
                    best[n] = t
                    cpu[n] = {"driver": driver, "workers": workers}
                same &= all(got[k] == ref[k] for k in ref)
        tasks = {n: len(plan_tasks(spec.scenarios, n)) for n in (1, 2)}
    finally:
        for cl, client in clusters.values():
            client.close()
            cl.close()
    load.append(os.getloadavg()[0])
    one_cpu = cpu[1]["driver"] + sum(cpu[1]["workers"])
    out = {"scenarios": len(spec.scenarios), "groups": len(spec.groups()),
           "tasks": tasks[2], "tile": args.tile, "density": args.density,
           "rays_per_scenario": compute.group_costs(spec.groups()[0])[2].count,
           "seconds_1_worker": best[1], "seconds_2_workers": best[2],
           "speedup": best[1] / best[2], "speedup_vs_serial": best["serial"] / best[2],
           "overhead_per_task_s": (best[1] - best["serial"]) / tasks[1],
           "one_worker_over_serial": best[1] / best["serial"],
           "serial_seconds": best["serial"], "serial_over_anchor": best["serial"] / anchor_s,
           "anchor_s": anchor_s, "repeat": args.repeat, "identical_results": same,
           # CPU seconds do not depend on what else the machine runs: the Dask run's CPU
           # over the loop's is its overhead; the busiest worker's CPU bounds the speedup
           # two free cores would give
           "cpu": {"serial_s": cpu["serial"], "one_worker_s": one_cpu,
                   "one_worker_over_serial": one_cpu / cpu["serial"],
                   "one_worker_worker_s": sum(cpu[1]["workers"]),
                   "one_worker_driver_s": cpu[1]["driver"],
                   "two_workers_each_s": cpu[2]["workers"],
                   "two_workers_driver_s": cpu[2]["driver"],
                   "speedup_on_free_cores": sum(cpu[1]["workers"]) / max(cpu[2]["workers"])},
           "paired": {"one_worker_over_serial_wall": [p[0] for p in paired],
                      "one_worker_over_serial_cpu": [p[1] for p in paired],
                      "median_wall": statistics.median(p[0] for p in paired),
                      "median_cpu": statistics.median(p[1] for p in paired)},
           "load_average": load,
           "scene_reuse": compute.describe_core()["scene_reuse"],
           "targets": {"speedup": 1.6, "one_worker_over_serial": 1.05}}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(f"{out['scenarios']} scenarios in {out['groups']} groups, "
              f"{out['rays_per_scenario']:,} rays each: serial {best['serial']:.2f} s, "
              f"1 worker {best[1]:.2f} s "
              f"({out['one_worker_over_serial']:.2f}x serial, {out['overhead_per_task_s']:+.3f} s "
              f"per task), 2 workers {best[2]:.2f} s (speedup {out['speedup']:.2f}); "
              f"paired 1 worker / serial: median {out['paired']['median_wall']:.3f} wall, "
              f"{out['paired']['median_cpu']:.3f} CPU; results identical: {same}")


if __name__ == "__main__":
    main()
