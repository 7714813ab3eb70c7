"""What a computation will cost, estimated before any work, so that a typing slip (a 1000x1000
tiling, a density of 24,000 rays per cm2) is refused in a second instead of eating the
machine's memory for minutes.

The command line, the app and sweeps call the same functions: :func:`canopy_cost`,
:func:`leaves_cost`,
:func:`light_cost` and :func:`heatmap_cost` give :class:`Cost` estimates; :func:`check` refuses
what would not fit in the memory available (always) or what would take longer than
:data:`SLOW_SECONDS` (unless forced: the app asks, the command line takes ``--force``). The
constants were measured on the bundled example (docs/limits.md says how).
"""

from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from maizeviz.canopy.layout import CanopyLayout
from maizeviz.canopy.measures import check_cover_resolution
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import Leaf
from maizeviz.light.scene.rays import Rect, ray_count
from maizeviz.mesh.levels import DEVIATION_K, Level

#: Peak bytes per canopy triangle: the canopy arrays (28 at K = 4), its Embree scene (a float32
#: copy of the vertices, the indices, a compact BVH: about 54), per-triangle results and the
#: transients of building them. Measured (benchmarks/bench_field.py): 128 B at K = 4 on 900
#: plants (30.5 million triangles, periodic), the process's own 0.3 GB included; 345 B before
#: issue 30.
BYTES_PER_TRIANGLE = 160
#: Peak bytes per leaf triangle meshed and measured by ``maizeviz leaf`` (measured on the
#: bundled example: 272 B from K = 4 to K = 16, 3.2 million more triangles).
BYTES_PER_LEAF_TRIANGLE = 300
#: Peak bytes per surface point of the largest leaf's deviation measure (its sample and the
#: bounds of each point; measured: 46 B on a leaf of 10,000 x 3 points, 1.7 million of them).
BYTES_PER_DEVIATION_POINT = 64
#: Leaf triangles meshed and measured per second (measured there: about 1 million).
LEAF_TRIANGLES_PER_S = 1_000_000
#: Bytes per traced ray: origins, hits, heights, ground positions (measured: 48-55 B).
BYTES_PER_RAY = 64
#: Bytes per heatmap cell: histograms, the drawn mesh and the CSV line.
BYTES_PER_HEATMAP_CELL = 600
#: Rough speeds on one core of these machines, for the time estimate.
TRIANGLES_PER_S = 2_000_000              # meshing, placing and Embree building
#: Seconds of work per digitized leaf below the standard mesh, besides its triangles: gridding,
#: fitting, the reference mesh's area the widening aims at, the splitting (measured with the
#: compiled loops: 22 s of CPU for the 160,045 leaves of 10,000 plants at 36 triangles, read
#: chunk by chunk; 3 s per 14,400 leaves before them).
SECONDS_PER_SIMPLIFIED_LEAF = 1.5e-4
RAYS_PER_S = 3_000_000                   # tracing, all heights
#: Work longer than this (estimated seconds) needs a confirmation.
SLOW_SECONDS = 900.0
#: Share of the available memory one computation may plan to use.
MEMORY_SHARE = 0.8


class TooSlow(MaizevizError):
    """Work that fits in memory but is estimated to take longer than :data:`SLOW_SECONDS`:
    the command line runs it with ``--force``, the app after a confirmation. ``estimate``:
    the estimate in words, without the advice."""

    def __init__(self, message: str, quantity: str | None = None, estimate: str = "") -> None:
        super().__init__(message, quantity=quantity)
        self.estimate = estimate or message


@dataclass(frozen=True)
class Cost:
    """An estimate of one piece of work.

    Attributes
    ----------
    what : what is estimated, in words ("the canopy at K=4")
    quantity : the input that drives it (see :data:`maizeviz.errors.QUANTITIES`)
    count : how many items; unit : what they are ("triangles", "rays", "heatmap cells")
    bytes : peak memory, bytes
    seconds : rough run time on one core, s
    """

    what: str
    quantity: str
    count: int
    unit: str
    bytes: int
    seconds: float

    def describe(self) -> str:
        return (f"{self.what}: {self.count:,} {self.unit}, about {_size(self.bytes)} of memory "
                f"and {_duration(self.seconds)}")


def _size(n: float) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"                                      # pragma: no cover


def _duration(s: float) -> str:
    if s < 90:
        return f"{max(s, 1):.0f} s"
    if s < 5400:
        return f"{s / 60:.0f} min"
    return f"{s / 3600:.1f} h"


def memory_available() -> int:
    """Bytes of memory available to a new computation (MemAvailable on Linux)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):              # pragma: no cover
        return 8 * 2**30


def leaf_triangles(rows, cols, tip_collapsed, level: Level):
    """Triangles of one leaf of an m x n point grid at ``level`` (an upper bound below the
    standard mesh); ints, or arrays of them leaf by leaf."""
    k = level.interp if level.interp is not None else 0
    a, b = (rows - 1) * (k + 1), (cols - 1) * (k + 1)
    full = 2 * a * b - b * np.asarray(tip_collapsed, dtype=np.int64)   # the tip's slivers
    if level.triangles is None:
        return full
    return np.minimum(min(level.triangles, 2**62), full)       # a budget past int64: no limit


def canopy_cost(leaves: Iterable[Leaf], placements: Mapping[int, int], level: Level,
                quantity: str = "tile") -> Cost:
    """The canopy of ``leaves`` at ``level`` with ``placements[plant]`` copies of each
    digitized plant standing in the field (set by the input ``quantity``: a tiling or a
    layout)."""
    per_plant: dict[int, int] = {}
    shapes = getattr(leaves, "shapes", None)          # a field's (FieldLeaves): arrays
    if shapes is not None:
        each = leaf_triangles(shapes.rows.astype(np.int64), shapes.cols.astype(np.int64),
                              shapes.tip, level)
        ids, at = np.unique(shapes.plant, return_inverse=True)
        per_plant = dict(zip(ids.tolist(), np.bincount(at, each).astype(np.int64).tolist()))
    for lf in leaves if shapes is None else ():
        m, n = lf.grid.shape
        per_plant[lf.plant] = per_plant.get(lf.plant, 0) + int(leaf_triangles(
            m, n, lf.grid.tip_collapsed, level))
    tris = int(sum(per_plant.get(p, 0) * count for p, count in placements.items()))
    plants = int(sum(placements.values()))
    placed = [p for p, count in placements.items() if count]
    leaves_meshed = int(np.isin(shapes.plant, placed).sum()) if shapes is not None else \
        sum(1 for lf in leaves if lf.plant in placements and placements[lf.plant])
    per_leaf = SECONDS_PER_SIMPLIFIED_LEAF if level.triangles is not None else 0.0
    return Cost(f"the canopy of {plants:,} plants at {level}", quantity, tris, "triangles",
                tris * BYTES_PER_TRIANGLE, tris / TRIANGLES_PER_S + leaves_meshed * per_leaf)


def leaves_cost(leaves: Sequence[Leaf], level: Level, quantity: str, batch: int,
                keep: bool = False) -> Cost:
    """Meshing and measuring ``leaves`` one at a time at ``level`` (``maizeviz leaf``): the
    meshes of ``batch`` leaves are held at once (of all of them when ``keep``, for an export).
    ``quantity`` is the input that chose the level ("interp", "triangles" or "level")."""
    tris = [int(leaf_triangles(*lf.grid.shape, lf.grid.tip_collapsed, level)) for lf in leaves]
    held = sum(tris) if keep else max((sum(tris[s:s + batch])
                                       for s in range(0, len(tris), batch)), default=0)
    # a leaf is measured whole, however many surface points it has (most leaves, a few
    # thousand, go MEASURE_POINTS at a time): the largest one's points add to the meshes
    points = max((deviation_points(*lf.grid.shape) for lf in leaves), default=0)
    return Cost(f"meshing {len(tris):,} leaves at {level}", quantity, sum(tris), "triangles",
                held * BYTES_PER_LEAF_TRIANGLE + points * BYTES_PER_DEVIATION_POINT,
                sum(tris) / LEAF_TRIANGLES_PER_S)


def deviation_points(rows: int, cols: int) -> int:
    """Surface points of an m x n leaf grid its deviation is measured at (K = 8, as
    :func:`maizeviz.mesh.levels.measure_leaves` samples it)."""
    return ((rows - 1) * (DEVIATION_K + 1) + 1) * ((cols - 1) * (DEVIATION_K + 1) + 1)


def layout_cost(leaves: Iterable[Leaf], layout: CanopyLayout, level: Level) -> Cost:
    """The canopy of ``leaves`` standing as ``layout`` places them, at ``level``."""
    return canopy_cost(leaves, dict(Counter(p.plant for p in layout.placements)), level,
                       layout.quantity)


def mesh_cost(triangles: int) -> Cost:
    """Tracing a canopy of ``triangles`` read from a mesh file (its scene and tables)."""
    return Cost(f"the mesh canopy of {triangles:,} triangles", "mesh", triangles, "triangles",
                triangles * BYTES_PER_TRIANGLE, triangles / TRIANGLES_PER_S)


def light_cost(rect: Rect, density: float, heights: int, directions: int = 1,
               triangles: int = 0) -> Cost:
    """Tracing ``directions`` parallel beams (the sun, sky directions, time steps) of rays at
    ``density`` per cm2 over ``rect`` (cm), measured at ``heights`` planes."""
    rays = ray_count(rect, density)                         # arithmetic only: no grid built
    work = rays * directions * (1 + max(heights, 1) / 2)
    what = "direct light" if directions == 1 else f"light from {directions:,} directions"
    return Cost(f"{what} at {density:g} rays per cm2", "density", rays * directions,
                "rays", rays * BYTES_PER_RAY + triangles * BYTES_PER_TRIANGLE // 4,
                work / RAYS_PER_S)


def light_costs(rect: Rect, density: float, heights: int, directions: int = 1,
                maps: int = 0, bin_cm: float = 5.0, triangles: int = 0) -> list[Cost]:
    """A light run as the command line and the app estimate it: its rays and its maps.

    Parameters
    ----------
    rect : (x0, y0, x1, y1) cm, the sample rectangle; density : rays per cm2
    heights : sensor planes; directions : beams traced (the sun, sky directions, time steps;
        at least 1 is counted)
    maps : results mapped (a transmission map per height each; 0: none); bin_cm : map bin, cm
    triangles : the canopy's, for the scene's memory (0: not counted)

    Returns
    -------
    list of Cost: the tracing, then the maps if any
    """
    costs = [light_cost(rect, density, heights, max(directions, 1), triangles)]
    if maps:
        costs.append(heatmap_cost(rect, bin_cm, heights * maps))
    return costs


def cover_cost(layout: CanopyLayout, resolution_cm: float) -> Cost:
    """Measuring the ground cover of ``layout``'s plot with one vertical ray per
    ``resolution_cm`` pixel (:func:`maizeviz.canopy.measures.ground_cover`)."""
    check_cover_resolution(resolution_cm)
    x0, y0, x1, y1 = layout.bounds
    rays = light_cost(layout.bounds, 1 / resolution_cm**2, 1)
    return replace(rays, what=f"the ground cover of the {(x1 - x0) / 100:g} x "
                              f"{(y1 - y0) / 100:g} m plot at {resolution_cm:g} cm",
                   quantity="field")


def heatmap_cost(rect: Rect, bin_cm: float, heights: int) -> Cost:
    """Transmission maps of ``rect`` (cm) in ``bin_cm`` bins at ``heights`` planes."""
    if not (math.isfinite(bin_cm) and bin_cm > 0):
        raise MaizevizError(f"the heatmap bin must be > 0 cm, got {bin_cm}",
                            quantity="heatmap_bin")
    x0, y0, x1, y1 = rect
    cells = math.ceil((x1 - x0) / bin_cm) * math.ceil((y1 - y0) / bin_cm)
    return Cost(f"transmission maps in {bin_cm:g} cm bins", "heatmap_bin", cells * heights,
                "heatmap cells", cells * BYTES_PER_HEATMAP_CELL, cells * heights * 2e-5)


#: Work estimated to take at least this long is announced before it starts (the command line
#: says the estimate on stderr).
SAY_SECONDS = 30.0


@dataclass(frozen=True)
class Estimate:
    """What a whole computation is estimated to cost: ``seconds`` of one core's work (its
    stages in turn), ``bytes`` at the peak (the largest stage's), and its largest part in
    words."""

    seconds: float
    bytes: int
    largest: str

    def describe(self) -> str:
        """``about 4 min and 6.0 GiB of memory (the largest part: ...)``."""
        return (f"about {_duration(self.seconds)} of work and {_size(self.bytes)} of memory "
                f"(the largest part: {self.largest})")


def check(stages: Iterable[Iterable[Cost]], force: bool = False,
          available: int | None = None) -> Estimate | None:
    """Refuse work that would not fit in memory, or that is slow unless ``force``.

    ``stages`` run one after the other (the levels of a comparison); the costs within a stage
    are held in memory together (a canopy and the rays traced through it).

    Raises
    ------
    MaizevizError
        One line naming the estimate, the limit and the input that drives it (``quantity``).
    TooSlow
        For work that fits but is slow; the message says it can be forced.

    Returns
    -------
    The estimate of the whole work (None for none), what the commands tell before long work.
    """
    stages = [list(s) for s in stages]
    costs = [c for s in stages for c in s]
    if not costs:
        return None
    limit = int(MEMORY_SHARE * (available if available is not None else memory_available()))
    for stage in stages:
        if sum(c.bytes for c in stage) > limit:
            worst = max(stage, key=lambda c: c.bytes)
            raise MaizevizError(f"{worst.describe()}; that is more than the {_size(limit)} of "
                                "memory this machine has available", quantity=worst.quantity)
    seconds = sum(c.seconds for c in costs)
    if seconds > SLOW_SECONDS and not force:
        worst = max(costs, key=lambda c: c.seconds)
        estimate = (f"{worst.describe()}: about {_duration(seconds)} in all, more than "
                    f"{_duration(SLOW_SECONDS)}")
        raise TooSlow(f"{estimate}; force it to run anyway", quantity=worst.quantity,
                      estimate=estimate)
    return Estimate(seconds, max(sum(c.bytes for c in stage) for stage in stages),
                    max(costs, key=lambda c: c.seconds).describe())
