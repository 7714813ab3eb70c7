"""Rays per second: embreex's single rays against Embree's packets (maizeviz.mesh.packets),
nearest hits and occlusion, in the same run.

The bundled block tiled 3 x 3 at ``--level`` (K = 4: 2.68 million triangles), noon sun of
Beijing on 2005-08-01, ``--density`` rays per cm2 over the central tile. Sensor-plane rays: from
every sensor of the planes at 50, 100, 150 and 200 cm toward the sun, up to the canopy top (the
paths whose blocking is transmission). Each figure is the best of ``--repeat`` runs over all
of them, in Mrays/s:

- intersect1_*: embreex's ``EmbreeScene.run`` (``rtcIntersect1`` / ``rtcOccluded1``, one ray
  at a time): what maizeviz traced with before the packets ("today" in issue 20)
- packets_*: the C kernel's packets of 8 (``rtcIntersect8`` / ``rtcOccluded8``, coherent flag,
  2 x 4 tiles of the sensor grid)
- *_nearest: the nearest hit (triangle and distance); *_occluded: any hit (Embree's cheaper
  occlusion query)
- open: the whole canopy's scene in an open field; periodic_block: the periodic field traced
  through the block's scene (maizeviz.light.scene.tiling), segments wrapped in C
- bare_embree_occluded_*: bare Embree's ceiling for packets_occluded: the same packets (the
  same rays, 2 x 4 tiles) laid out in memory beforehand and traced by a C loop that only calls
  ``rtcOccluded8`` (``benchmarks/_bare_embree.c``, compiled here; skipped without a C
  compiler); packets_occluded_* can only come near it
- _1t / _2t: on 1 and 2 threads (chunks of 2^16 rays, ctypes and embreex release the GIL)
- speedup_*: ratios in this run (target: packets_occluded_2t >= 20 Mrays/s and >= 3 x
  intersect1_occluded_2t on 2 cores); of_bare_occluded_*: packets_occluded over
  bare_embree_occluded (1: the kernel costs nothing around Embree)
- sensor_answers_*: maizeviz's whole computation of one direction (``trace_direction``: the
  ground rays and the six default planes, each sensor's path answered by an occlusion query
  or, at this sun, by the first hit of the ray of the same family through it), in sensor
  answers (rays x 7 planes, the ground included) per second: open field with packets and with
  single rays, and the periodic field through the block

    python benchmarks/bench_rays.py [--json] [--level K4] [--density 16] [--repeat 5]
"""

from __future__ import annotations

import argparse
import ctypes
import os
import shutil
import subprocess
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from anchors import best, report

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.rays import Tracer, ray_grid
from maizeviz.light.sources.sun import sun_at
from maizeviz.light.trace.beam import sampler, trace_direction
from maizeviz.mesh import packets
from maizeviz.mesh.levels import parse_level
from maizeviz.mesh.raytrace import RayScene
from maizeviz.resources import example_points

CHUNK = 1 << 16
BARE_SOURCE = Path(__file__).with_name("_bare_embree.c")


def chunked(fn, n: int, threads: int):
    """fn(a, b) over chunks of the n rays on ``threads`` threads."""
    parts = [(a, min(a + CHUNK, n)) for a in range(0, n, CHUNK)]
    if threads == 1:
        return lambda: [fn(a, b) for a, b in parts]

    def run():
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(lambda ab: fn(*ab), parts))
    return run


def tile_order(n: int, row: int, th: int = 2, tw: int = 4) -> np.ndarray:
    """Ray indices (P, 8) of the packets maizeviz.mesh.packets forms from n rays laid out
    row rays a row: th x tw tiles, tiles along the row, then the next th rows; -1 pads."""
    r0, c0 = np.meshgrid(np.arange(0, -(-n // row), th), np.arange(0, row, tw), indexing="ij")
    a, b = np.divmod(np.arange(th * tw), tw)
    col = c0.reshape(-1, 1) + b
    idx = (r0.reshape(-1, 1) + a) * row + col
    idx[(col >= row) | (idx >= n)] = -1
    return idx[(idx >= 0).any(axis=1)]


def bare_embree(scene: RayScene, org32: np.ndarray, direction: np.ndarray, len32: np.ndarray,
                row: int):
    """(reset, trace(a, b)) for bare Embree on the rays' packets (``_bare_embree.c``): reset
    lays the packets out again (untimed), trace(a, b) traces those of rays [a, b) (a and b
    multiples of 8); None without a C compiler or the packet kernel."""
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    k = packets.kernel()
    if cc is None or k is None or not scene.packets:
        return None
    so = Path(tempfile.mkdtemp()) / "_bare_embree.so"
    if subprocess.run([cc, "-O2", "-shared", "-fPIC", str(BARE_SOURCE), "-o", str(so)],
                      capture_output=True).returncode != 0:
        return None
    lib = ctypes.CDLL(str(so))
    p, i64 = ctypes.c_void_p, ctypes.c_int64
    lib.bare_prepare.argtypes = [i64, p, p, p, p, p, p]
    lib.bare_occluded8.argtypes = [p, p, i64, p, p]
    idx = np.ascontiguousarray(tile_order(len(org32), row), dtype=np.int64)
    npk = len(idx)
    raw = np.zeros(npk * 96 + 16, np.float32)          # 96 floats a packet, 64-byte aligned
    buf = raw[(-raw.ctypes.data % 64) // 4:][:npk * 96]
    valid_raw = np.zeros(npk * 8 + 16, np.int32)
    valid = valid_raw[(-valid_raw.ctypes.data % 64) // 4:][:npk * 8]
    d = np.ascontiguousarray(direction, dtype=np.float32).reshape(3)

    def reset():
        lib.bare_prepare(npk, idx.ctypes.data, org32.ctypes.data, d.ctypes.data,
                         len32.ctypes.data, buf.ctypes.data, valid.ctypes.data)

    def trace(a, b):
        lib.bare_occluded8(k.occluded[8], scene._handle, (b - a) // 8,
                           valid[a:].ctypes.data, buf[a // 8 * 96:].ctypes.data)

    def blocked():
        out = np.zeros(len(org32), bool)
        sel = idx >= 0
        out[idx[sel]] = buf.reshape(npk, 12, 8)[:, 8, :][sel] < 0
        return out
    return reset, trace, blocked, npk * 8


def best_reset(fn, reset, repeat: int) -> float:
    """Shortest of ``repeat`` timed calls of ``fn()``, each after an untimed ``reset()``."""
    out = []
    for _ in range(repeat):
        reset()
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def _bare_rates(packed, org32, s, dirs, len32, ny: int, repeat: int) -> dict[str, float]:
    """bare_embree_occluded_1t and _2t, Mrays/s (nothing where no C compiler is found)."""
    bare = bare_embree(packed, org32, s, len32, ny)
    if bare is None:
        return {}
    n = len(org32)
    reset, trace, blocked, n_lanes = bare
    reset()
    trace(0, n_lanes)
    assert np.array_equal(blocked(), packed.occluded(org32, dirs[:1], len32, row=ny))
    rates = {}
    for threads in (1, 2):
        secs = best_reset(chunked(trace, n_lanes, threads), reset, repeat)
        rates[f"bare_embree_occluded_{threads}t"] = round(n / secs / 1e6, 2)
    return rates


def _ratios(out: dict) -> dict[str, float]:
    """speedup_* (packets over single rays) and of_bare_occluded_* (packets over bare
    Embree), from the rates in ``out``."""
    ratios = {}
    for q in ("occluded", "nearest"):
        for t in ("1t", "2t"):
            ratios[f"speedup_{q}_{t}"] = round(out[f"packets_{q}_{t}"]
                                               / out[f"intersect1_{q}_{t}"], 2)
    for t in ("1t", "2t"):
        if f"bare_embree_occluded_{t}" in out:
            ratios[f"of_bare_occluded_{t}"] = round(out[f"packets_occluded_{t}"]
                                                    / out[f"bare_embree_occluded_{t}"], 2)
    return ratios


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--level", default="K4")
    ap.add_argument("--density", type=float, default=16.0)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    leaves = read_leaves(example_points()).leaves
    canopy = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level(args.level))
    sun = sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai")
    s = sun.direction()
    rect = canopy.layout.centre_bounds
    top = float(canopy.vertices[:, 2].max()) + 1.0
    ground, _ = ray_grid(rect, args.density)
    ny = int(round((rect[3] - rect[1]) * np.sqrt(args.density)))
    planes = (50.0, 100.0, 150.0, 200.0)
    org = np.concatenate([np.column_stack([ground, np.full(len(ground), h)]) for h in planes])
    length = np.concatenate([np.full(len(ground), (top - h) / s[2]) for h in planes])
    org32, len32 = org.astype(np.float32), length.astype(np.float32)
    dirs = np.tile(s.astype(np.float32), (len(org), 1))
    n = len(org)

    single = RayScene(canopy.vertices, canopy.faces, packets=False)
    packed = RayScene(canopy.vertices, canopy.faces)
    if not packed.packets:
        raise SystemExit("the packet kernel is not available here (no C compiler?)")
    block = light_scene(canopy, periodic=True)
    wrapped = Tracer(block, s, canopy.layout.bounds, True)

    def single_occ(a, b):
        single._scene.run(org32[a:b], dirs[a:b], dists=len32[a:b].copy(), query="OCCLUDED")

    def single_near(a, b):
        single._scene.run(org32[a:b], dirs[a:b], dists=len32[a:b].copy(), output=True)

    def packed_occ(a, b):
        packed.occluded(org32[a:b], dirs[:1], len32[a:b], row=ny)

    def packed_near(a, b):
        packed.first_hit(org32[a:b], dirs[:1], len32[a:b], row=ny)

    def block_occ(a, b):
        wrapped.occluded(org[a:b], length[a:b], row=ny)

    def block_near(a, b):
        wrapped.trace(org[a:b], length[a:b], row=ny)

    # the same answers, ray for ray (tests/core/test_packets.py checks it at length)
    ref = single.occluded(org32[:CHUNK], dirs[:CHUNK], len32[:CHUNK])
    assert np.array_equal(ref, packed.occluded(org32[:CHUNK], dirs[:1], len32[:CHUNK], row=ny))
    out: dict[str, object] = {"triangles": canopy.n_triangles, "level": args.level,
                              "block_triangles": block.n_triangles, "rays": n,
                              "cores": os.cpu_count()}
    for name, fn in (("intersect1_occluded", single_occ), ("intersect1_nearest", single_near),
                     ("packets_occluded", packed_occ), ("packets_nearest", packed_near),
                     ("periodic_block_occluded", block_occ),
                     ("periodic_block_nearest", block_near)):
        for threads in (1, 2):
            out[f"{name}_{threads}t"] = round(n / best(chunked(fn, n, threads), args.repeat)
                                              / 1e6, 2)
    out.update(_bare_rates(packed, org32, s, dirs, len32, ny, args.repeat))
    heights = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)
    for name, sc, periodic in (("open_packets", packed, False), ("open_single_rays", single, False),
                               ("periodic_block", block, True)):
        smp = sampler(canopy, sc, rect, args.density, heights, periodic)
        answers = smp.n * (len(heights) + 1)
        for threads in (1, 2):
            secs = best(lambda smp=smp, threads=threads: trace_direction(smp, s,
                                                                           threads=threads),
                        args.repeat)
            out[f"sensor_answers_{name}_{threads}t"] = round(answers / secs / 1e6, 2)
    out.update(_ratios(out))
    out["targets"] = {"packets_occluded_2t": 20.0, "speedup_occluded_2t": 3.0}
    report(out, args.json)


if __name__ == "__main__":
    main()
