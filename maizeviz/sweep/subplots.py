"""A field too large for one machine, traced in sub-plots on Dask workers and merged.

The client reads only what places the plants: the survey of the points file (each plant's
stalk base and spread, :class:`~maizeviz.canopy.field.FieldLeaves`), the layout, the sample
rectangle's ray lattice cut into windows (:func:`maizeviz.light.trace.subplots.windows`). Each
window's part holds the plants within its reach (the window grown by the halo its rays need,
:func:`~maizeviz.light.trace.subplots.halo_cm`, and each plant's own spread); every plant is in
some part. Then, on the workers, in two rounds:

1. each part builds its plants' canopy from the points file (read plant by plant; the file
   must be where every worker sees it, as sweeps need) and keeps it; the parts' highest
   triangles give the whole canopy's top plane;
2. each part traces its window's rays through its canopy
   (:func:`~maizeviz.light.trace.subplots.trace_window`) and sends back its counts: per
   height the sensors that see the sun, per plant and leaf the rays whose first and second
   hits fall on it.

The counts summed are the whole field's (``tests/core/test_subplots.py``). Memory on a worker
follows its part: the field's halo at 30 deg from the zenith is about 1.5 m, so four parts of
a hectare each hold about 27 % of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from maizeviz.canopy.layout import CanopyLayout
from maizeviz.light.scene.rays import Rect, grid_shape
from maizeviz.light.trace.subplots import Window, WindowCounts, halo_cm, reach, windows
from maizeviz.mesh.levels import Level

#: A plant's triangles reach beyond its digitized points by at most this share of their
#: spread from the stalk (a NURBS surface between data points, a widened coarse mesh), cm.
SPREAD_SHARE, SPREAD_MARGIN_CM = 1.25, 5.0


@dataclass(frozen=True)
class Part:
    """One sub-plot: its window of the lattice and the placements (whole-layout indices)
    whose plants it builds."""

    window: Window
    placements: np.ndarray


def plan_parts(layout: CanopyLayout, spreads: dict[int, float], rect: Rect, density: float,
               parts: tuple[int, int], top_guess: float, toward: np.ndarray) -> list[Part]:
    """Cut the lattice of ``rect`` into ``parts`` windows and give each the placements within
    its reach; a placement within none goes to the nearest window (every plant is built
    once at least: the top plane is the whole canopy's). ``top_guess`` (cm) sizes the halo:
    the highest digitized point and a margin."""
    shape = grid_shape(rect, density)
    halo = halo_cm(top_guess, toward, rect, shape)
    xy = np.array([(p.x, p.y) for p in layout.placements])
    spread = np.array([SPREAD_SHARE * spreads[p.plant] + SPREAD_MARGIN_CM
                       for p in layout.placements])
    out: list[Part] = []
    placed = np.zeros(len(xy), bool)
    centres = []
    for w in windows(shape, parts):
        x0, y0, x1, y1 = reach(w.rect(rect, shape), halo)
        inside = (xy[:, 0] + spread >= x0) & (xy[:, 0] - spread <= x1) & \
            (xy[:, 1] + spread >= y0) & (xy[:, 1] - spread <= y1)
        placed |= inside
        out.append(Part(w, np.flatnonzero(inside)))
        wx0, wy0, wx1, wy1 = w.rect(rect, shape)
        centres.append(((wx0 + wx1) / 2, (wy0 + wy1) / 2))
    left = np.flatnonzero(~placed)
    if len(left):
        c = np.array(centres)
        near = np.argmin(((xy[left, None, :] - c[None]) ** 2).sum(axis=2), axis=1)
        for k, part in enumerate(out):
            mine = left[near == k]
            if len(mine):
                out[k] = Part(part.window, np.union1d(part.placements, mine))
    return out


def build_part(points: str, layout: CanopyLayout, placements: np.ndarray, level: Level,
               preserve_area: bool):
    """On a worker: the canopy of the placements ``placements`` of ``layout`` (their plants
    read from ``points``, plant by plant) and the whole layout's index of each."""
    from maizeviz.canopy.build import place_plants
    from maizeviz.canopy.field import FieldLeaves

    sub = replace(layout, placements=tuple(layout.placements[i] for i in placements))
    field = FieldLeaves(points, survey=False)        # the client surveyed it
    meshes = field.plant_meshes(level, preserve_area, {p.plant for p in sub.placements})
    return place_plants(meshes, sub, level.label), np.asarray(placements)


def part_top(part) -> float:
    """The highest leaf triangle of a built part (cm)."""
    canopy, _ = part
    return float(canopy.vertices[:, 2].max()) if canopy.n_triangles else -math.inf


def trace_part(part, window: Window, n_placements: int, rect: Rect, density: float,
               heights: tuple[float, ...], top: float, toward: np.ndarray,
               bounds: Rect) -> WindowCounts:
    """On a worker: a built part's window traced (see the module docstring)."""
    from maizeviz.light.trace.subplots import trace_window

    canopy, index = part
    return trace_window(canopy, index, n_placements, window, rect, density, heights, top,
                        toward, bounds)


def trace_field(client, field, layout: CanopyLayout, level: Level,
                toward: np.ndarray, rect: Rect, density: float,
                heights: tuple[float, ...], parts: tuple[int, int],
                preserve_area: bool = True, progress=None) -> tuple[WindowCounts, list[Part]]:
    """The field surveyed as ``field`` (:class:`~maizeviz.canopy.field.FieldLeaves`) placed by
    ``layout`` at ``level``, traced toward ``toward`` ((3,) unit vector) in ``parts``
    sub-plots on the Dask ``client``'s workers; the summed counts and the parts (see the
    module docstring)."""
    points = str(field.path)
    spreads = {p: field.spread(p) for p in field.bases}
    guess = field.highest + 10.0
    plan = plan_parts(layout, spreads, rect, density, parts, guess, toward)
    built = [client.submit(build_part, points, layout, p.placements, level, preserve_area,
                           pure=False) for p in plan]
    tops = client.gather([client.submit(part_top, b, pure=False) for b in built])
    top = max(tops) + 1.0
    if top > guess:                         # the halo was sized below the canopy: plan again
        raise RuntimeError(f"the canopy's top {top:.1f} cm is above the halo's {guess:.1f} cm")
    n_place = len(layout.placements)
    counts = [client.submit(trace_part, b, p.window, n_place, rect, density, tuple(heights),
                            top, np.asarray(toward, float), layout.bounds, pure=False)
              for b, p in zip(built, plan)]
    total = None
    for k, got in enumerate(client.gather(counts), start=1):
        total = got if total is None else total.add(got)
        if progress is not None:
            progress(k, len(counts))
    assert total is not None
    return total, plan
