"""The app's work, as plain functions over the core (no Qt): what worker threads and the core
process run.

Each function takes everything it needs and returns new objects; the window keeps the results
and drops stale ones by job id. Functions meant for the core process (:data:`OPS`) receive the
child's ``state`` (the canopy it holds, and the Embree scene it built from it) and a
``progress(done, total)`` callback.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from maizeviz.canopy.layout import CanopyLayout, layout_for
from maizeviz.canopy.measures import CanopyMeasures, measure_canopy
from maizeviz.canopy.scene import Canopy, build_canopy
from maizeviz.leaf.fit import Leaf, read_leaves
from maizeviz.light.request import LightRequest
from maizeviz.light.transmission import LightResult, light_scene, trace_light
from maizeviz.mesh.levels import parse_level
from maizeviz.progress import ProgressCallback

#: Pixel edge (cm) of the ground-cover grid in the app (the CLI's default is 0.5 cm).
APP_COVER_RESOLUTION_CM = 1.0


@dataclass(frozen=True)
class Loaded:
    """A points file read, gridded and fitted, and where its plants stand.

    Attributes
    ----------
    path : the file read (for a project: the file on disk or the project's copy of it)
    leaves : fitted leaves; skipped : leaves refused (errors naming plant, leaf, row, col)
    layout : where the plants stand; warnings : lines for the user (repairs, notes)
    shown_name : how the file is named to the user
    """

    path: str
    leaves: list[Leaf]
    skipped: list
    layout: CanopyLayout
    warnings: tuple[str, ...]
    shown_name: str = ""

    @property
    def plants(self) -> set[int]:
        return {lf.grid.plant for lf in self.leaves}


def load_points(path: str, tile: tuple[int, int] = (3, 3), row_spacing: float = 60.0,
                plant_spacing: float = 30.0, shown_name: str = "",
                layout: CanopyLayout | None = None) -> Loaded:
    """Read, grid and fit a points file; lay it out as ``layout`` or tiled ``tile`` times."""
    found = read_leaves(path)
    if layout is None:
        layout = layout_for(found.leaves, tile, row_spacing, plant_spacing)
    return Loaded(str(path), found.leaves, found.skipped, layout,
                  tuple(found.problems) + tuple(found.notes) + tuple(layout.warnings),
                  shown_name or str(path))


@dataclass(frozen=True)
class Built:
    """A canopy at one level with its Table 2 measures (``mesh``: what the viewport draws,
    prepared off the GUI thread)."""

    level: str
    label: str
    canopy: Canopy
    measures: CanopyMeasures
    build_s: float
    measure_s: float
    mesh: Any = None


def build(loaded: Loaded, level_text: str, preserve_area: bool,
          progress: ProgressCallback | None = None) -> tuple[Canopy, float, str]:
    """The canopy at a level: (canopy, seconds, the level's label in Table 2)."""
    level = parse_level(level_text)
    t0 = time.perf_counter()
    canopy = build_canopy(loaded.leaves, loaded.layout, level, preserve_area, progress)
    return canopy, time.perf_counter() - t0, level.variant_label(preserve_area)


# ------------------------------------------------------------------ in the core process
def op_measure(state: dict, progress: ProgressCallback, cover_resolution: float) -> CanopyMeasures:
    """Table 2 measures of the child's canopy (ground cover traces an Embree scene)."""
    return measure_canopy(state["canopy"], cover_resolution=cover_resolution)


def op_light(state: dict, progress: ProgressCallback, request: LightRequest) -> LightResult:
    """Trace the sun through the child's canopy; the scene (a periodic field's holds copies of
    the leaves overhanging the plot edges) is kept for the next sun."""
    build_s = 0.0
    key = ("scene", bool(request.periodic))
    if key not in state:
        t0 = time.perf_counter()
        state[key] = light_scene(state["canopy"], False, bool(request.periodic))
        build_s = time.perf_counter() - t0
    result = trace_light(state["canopy"], request, progress, False, state[key])
    result.seconds["build"] = build_s              # the scene kept from an earlier sun: 0
    return result


def op_ping(state: dict, progress: ProgressCallback) -> str:
    return "pong"


OPS = {"measure": op_measure, "light": op_light, "ping": op_ping}
