"""Distance and area probes on the canopy, without Qt: points picked on the leaves, and what
they measure (napari's and ParaView's rulers do the same on their layers).

A distance probe takes two points and gives the straight distance between them; an area
probe takes three or more, a polygon, and gives its area (the polygon's vector area, exact
for a plane polygon, Newell's method) and that of its shadow on the ground. The window's
clicks on the 3D view go to the study's probe while one is on (View > Measure), and the view
draws its points and lines; a script adds points itself.
"""

from __future__ import annotations

import numpy as np
from psygnal import Signal

#: The kinds of probe, by what the View menu calls them.
KINDS = {"distance": "Measure distance", "area": "Measure area"}


def polygon_area(points: np.ndarray) -> tuple[float, float]:
    """(area, area seen from above) in cm2 of the polygon through ``points`` (k, 3) cm, in
    order: half the norm of its vector area (exact for a plane polygon), and half its z
    component (its shadow on the ground)."""
    p = np.asarray(points, np.float64).reshape(-1, 3)
    if len(p) < 3:
        return 0.0, 0.0
    vector = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    return float(np.linalg.norm(vector)), float(abs(vector[2]))


class Probe:
    """The probe under way: its kind ("" when off) and the points picked (cm).

    Signals
    -------
    changed() : a point added, the probe started, cleared or stopped.
    """

    changed = Signal()

    def __init__(self) -> None:
        self.kind = ""
        self.points: list[tuple[float, float, float]] = []

    @property
    def on(self) -> bool:
        return bool(self.kind)

    def start(self, kind: str) -> None:
        """Start a probe of ``kind`` ("distance" or "area"), its points cleared; ""
        stops."""
        if kind and kind not in KINDS:
            raise ValueError(f"unknown probe {kind}; one of {', '.join(KINDS)}")
        self.kind, self.points = kind, []
        self.changed.emit()

    def add(self, point) -> None:
        """A point picked (cm); a distance probe's third point starts a new measure."""
        if not self.on:
            return
        if self.kind == "distance" and len(self.points) == 2:
            self.points = []
        self.points.append(tuple(float(v) for v in point))        # type: ignore[arg-type]
        self.changed.emit()

    def text(self) -> str:
        """What the probe measures so far, in words."""
        n = len(self.points)
        if not self.on:
            return ""
        if self.kind == "distance":
            if n < 2:
                return "distance: click two points on the canopy" if n == 0 else \
                    "distance: click the second point"
            a, b = np.asarray(self.points)
            d = b - a
            return (f"distance {np.linalg.norm(d):.1f} cm (across {abs(d[0]):.1f}, along "
                    f"{abs(d[1]):.1f}, up {abs(d[2]):.1f} cm)")
        if n < 3:
            more = f"{3 - n} more point{'s' if 3 - n > 1 else ''}"
            return f"area: click {more} of a polygon on the canopy"
        area, ground = polygon_area(np.asarray(self.points))
        return f"area {area:.1f} cm² ({n} points; seen from above {ground:.1f} cm²)"
