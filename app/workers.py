"""Work the GUI hands to threads: plain functions over the core, with a cancel flag.

Each job captures all its inputs and an id, so the window can drop a stale result when the
slider has moved on (napari's async slicing does the same). Progress is reported through a
Qt signal of a small QObject, emitted from the worker thread and delivered on the GUI thread.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from PySide6.QtCore import QObject, Signal

from maizeviz.canopy.layout import layout_for
from maizeviz.canopy.measures import measure_canopy
from maizeviz.canopy.scene import build_canopy
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.request import LightRequest
from maizeviz.light.transmission import trace_light
from maizeviz.mesh.levels import parse_level


class Progress(QObject):
    """``changed(job id, done, total)``, safe to emit from any thread."""

    changed = Signal(int, int, int)


@dataclass
class Job:
    """A unit of work: an id, a cancel flag and a progress channel."""

    id: int
    progress: Progress
    cancel: threading.Event = field(default_factory=threading.Event)

    def report(self, done: int, total: int) -> bool:
        self.progress.changed.emit(self.id, done, total)
        return not self.cancel.is_set()


@dataclass(frozen=True)
class Loaded:
    path: str
    leaves: list
    skipped: list
    layout: object
    warnings: tuple


def load_points(path: str, tile=(3, 3), row_spacing=60.0, plant_spacing=30.0) -> Loaded:
    """Read, grid and fit a points file and tile it (the paper's canopy by default)."""
    found = read_leaves(path)
    layout = layout_for(found.leaves, tile, row_spacing, plant_spacing)
    return Loaded(path, found.leaves, found.skipped, layout,
                  tuple(found.problems) + tuple(found.notes) + layout.warnings)


@dataclass(frozen=True)
class Built:
    job: int
    level: str
    canopy: object
    measures: object
    build_s: float
    measure_s: float


def build(job: Job, loaded: Loaded, level_text: str, preserve_area: bool = True) -> Built:
    """Rebuild the canopy at a level and measure it (Table 2)."""
    t0 = time.perf_counter()
    canopy = build_canopy(loaded.leaves, loaded.layout, parse_level(level_text), preserve_area,
                          job.report)
    t1 = time.perf_counter()
    if job.cancel.is_set():
        raise InterruptedError("cancelled")
    m = measure_canopy(canopy, cover_resolution=1.0)
    return Built(job.id, canopy.level, canopy, m, t1 - t0, time.perf_counter() - t1)


@dataclass(frozen=True)
class Lit:
    job: int
    result: object


def light(job: Job, canopy, request: LightRequest) -> Lit:
    """Trace the sun through a canopy."""
    return Lit(job.id, trace_light(canopy, request, job.report))
