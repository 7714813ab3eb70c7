"""The selected plant or leaf, and what the window says of it; no Qt.

One :class:`Selection` per study (in the model): a click on a leaf in the 3D view selects that
leaf, a row of the plants table selects that plant, and both views follow it (napari's layer
``selected_data`` works the same way: a set that says when it changes, and views that mirror
it). :func:`describe` puts a selection into words with the numbers of the tables: the plant,
the leaf, the level, the leaf's area and the light each result shown gave it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from psygnal import Signal


class Selection:
    """What is selected: the placement ``placement`` (from 0; -1: nothing; the tables' stand
    is ``placement + 1``) and its ``leaf`` (rank from 1; 0: the stalk; -1: the whole plant).

    Signals: ``changed(placement, leaf)``, once per change (both at once)."""

    changed = Signal(int, int)

    def __init__(self) -> None:
        self.placement = -1
        self.leaf = -1

    def select(self, placement: int, leaf: int = -1) -> None:
        """Select placement ``placement``'s ``leaf`` (-1: the whole plant; a negative
        ``placement``: nothing)."""
        placement, leaf = int(placement), int(leaf)
        if placement < 0:
            placement, leaf = -1, -1
        if (placement, leaf) != (self.placement, self.leaf):
            self.placement, self.leaf = placement, leaf
            self.changed.emit(placement, leaf)

    def clear(self) -> None:
        self.select(-1, -1)

    @property
    def empty(self) -> bool:
        return self.placement < 0


def describe(canopy: Any, label: str, runs: Sequence[Any], instance: int,
             leaf: int = -1) -> list[str]:
    """The selection in words: a title line, the level and area, then one line per light
    result of ``runs`` (the model's ``Run`` objects traced on ``canopy``) with its value for
    the leaf (or, for a plant, the area-weighted mean over its leaves). [] if ``instance`` is
    not a placement of ``canopy``."""
    from maizeviz.mesh.tessellate import triangle_areas_normals

    placements = canopy.layout.placements
    if not 0 <= instance < len(placements):
        return []
    p = placements[instance]
    where = f"stand {instance + 1} at x {p.x:.0f}, y {p.y:.0f} cm"
    rows = np.flatnonzero(canopy.face_instance == instance)
    if leaf > 0:
        rows = rows[canopy.face_leaf[rows] == leaf]
    if leaf == 0:
        return [f"plant {p.plant}, its stalk ({where})", f"level {label}"]
    area, _ = triangle_areas_normals(canopy.vertices, canopy.faces[rows])
    what = f"leaf {leaf}" if leaf > 0 else f"{len(np.unique(canopy.face_leaf[rows]))} leaves"
    lines = [f"plant {p.plant}, {what} ({where})",
             f"level {label}; leaf area {area.sum():,.1f} cm² ({len(rows):,} triangles)"]
    for run in runs:
        for line in (_light_line(run, rows, area, leaf),
                     _assimilation_line(run, rows, area, leaf)):
            if line:
                lines.append(line)
    return lines


def _assimilation_line(run: Any, rows: np.ndarray, area: np.ndarray, leaf: int) -> str:
    """A sun's gross CO2 assimilation (a leaf model on its absorbed PAR) on the triangles
    ``rows``: per m2 of leaf (area-weighted) and in all, umol CO2 per s."""
    gross = getattr(run.extra, "gross_value", None)
    if run.kind != "sun" or gross is None or len(gross) <= rows.max(initial=-1):
        return ""
    v = _mean(np.asarray(gross)[rows], area)
    if not np.isfinite(v):
        return ""
    per = "" if leaf > 0 else " (mean over its leaves)"
    model = run.extra.assimilation.model["model"].upper()
    return (f"sun: gross CO₂ assimilation ({model}) {v:.3g} µmol/m² of leaf/s{per}, "
            f"{v * area.sum() * 1e-4:.3g} µmol/s")


def _mean(values: np.ndarray, area: np.ndarray) -> float:
    """Area-weighted mean of per-triangle ``values`` (NaN where not traced: left out)."""
    ok = np.isfinite(values)
    return float(np.sum(values[ok] * area[ok]) / area[ok].sum()) if ok.any() else float("nan")


def _light_line(run: Any, rows: np.ndarray, area: np.ndarray, leaf: int) -> str:
    """One result's value for the triangles ``rows`` of a leaf or plant (``leaf`` -1)."""
    leaf_value = getattr(run.extra, "leaf_value", None)
    per = "" if leaf > 0 else " (mean over its leaves)"
    if leaf_value is not None and len(leaf_value) > rows.max(initial=-1):
        v = _mean(np.asarray(leaf_value)[rows], area)
        if run.kind == "sun":
            band = run.extra.light.band.upper()
            return f"sun: {band} absorbed {v:.3g} W/m² of leaf{per}"
        if run.kind == "day":
            return f"day: PAR intercepted {v:.3g} mol/m² of leaf{per}"
        return f"sky: {v:.3f} of the open sky's diffuse light per leaf area{per}"
    painting = getattr(run, "painting", None)
    if run.kind == "sun" and painting is not None and len(painting.share) > rows.max(initial=-1):
        share = _mean(np.asarray(painting.share)[rows], area)
        if not np.isfinite(share):
            return "sun: not traced (outside the sample seen from the sun)"
        return (f"sun: sunlit share {share:.2f}, {share * area.sum():,.1f} cm² in the sun"
                f"{per}")
    if run.kind == "sun" and run.classes is not None and len(run.classes) > rows.max(initial=-1):
        direct = float(area[np.asarray(run.classes)[rows] == 2].sum() / max(area.sum(), 1e-12))
        return f"sun: {direct:.0%} of the area in triangles some ray reached first"
    return ""
