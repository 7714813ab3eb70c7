"""The light figures of the study, without Qt: for each light (sun, sky, day) the result whose
heatmaps are shown and its heatmaps (an RGBA image per height, None until drawn), and the
transmission-vs-height plot. The model fills them (:mod:`maizeviz_app.lighting`); the figures
panel follows them and says which light and height it shows (:attr:`Figures.shown_kind`,
:attr:`Figures.shown_index`), which exports and new runs use.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from psygnal import Signal

#: (height cm, RGBA image or None) per height of a result.
Maps = list[tuple[float, np.ndarray | None]]


@dataclass(frozen=True)
class Canvas:
    """Where a figure is shown: ``width_px`` x ``height_px`` device pixels at ``dpi`` (the
    screen's logical dpi times its device pixel ratio). A figure drawn for it is made that
    size, so its texts keep their points there instead of being scaled down to fit."""

    width_px: int
    height_px: int
    dpi: float

    @property
    def inches(self) -> tuple[float, float]:
        """(width, height) of the canvas, inches."""
        return self.width_px / self.dpi, self.height_px / self.dpi

    def close_to(self, other: Canvas | None, rel: float = 0.05) -> bool:
        """Whether a figure drawn for ``other`` would look the same here (sizes within
        ``rel``, the same dpi): no need to draw it again."""
        return other is not None and other.dpi == self.dpi and \
            abs(other.width_px - self.width_px) <= rel * self.width_px and \
            abs(other.height_px - self.height_px) <= rel * self.height_px


class Figures:
    """Heatmaps per light and the transmission plot.

    Signals
    -------
    maps_changed(kind) : the maps of light ``kind`` were replaced ('' : several lights
        forgotten; None maps: that light's forgotten).
    map_drawn(kind, index, rgba) : one height's heatmap drawn after it was asked for.
    plot_changed(rgba) : the transmission plot (None: none).
    restyled(keep, hold) : the maps of every light but ``keep`` are to be drawn again (the
        scale they share took in a new result); with ``hold`` the map shown stays in view
        until it is (the same map for a canvas of another size).
    canvas_changed(which) : where the ``heatmap`` or the ``plot`` is shown changed size: it
        is to be drawn again for its new :class:`Canvas`.

    Attributes
    ----------
    canvases : {"heatmap" or "plot": Canvas}, where each figure is shown (the window says);
        figures are drawn for them, the core's fixed size where none is known.
    """

    maps_changed = Signal(str)
    map_drawn = Signal(str, int, object)
    plot_changed = Signal(object)
    restyled = Signal(object, bool)
    canvas_changed = Signal(str)

    def __init__(self) -> None:
        self.shown_for: dict[str, Any] = {}     # light -> the run whose maps are shown
        self.maps: dict[str, Maps] = {}
        self.plot: np.ndarray | None = None
        self.shown_kind: str | None = None      # what the figures panel shows
        self.shown_index = 0
        self.canvases: dict[str, Canvas] = {}

    def set_canvas(self, which: str, canvas: Canvas) -> None:
        """The ``heatmap`` or the ``plot`` is shown on ``canvas``; ``canvas_changed`` when a
        figure drawn for the old one would look different there."""
        if which not in ("heatmap", "plot"):
            raise ValueError(f"no figure {which!r} (heatmap or plot)")
        if canvas.close_to(self.canvases.get(which)):
            return
        self.canvases[which] = canvas
        self.canvas_changed.emit(which)

    @property
    def shown_height(self) -> float | None:
        """The height (cm) of the heatmap shown, None when none is."""
        maps = self.maps.get(self.shown_kind or "", [])
        return maps[self.shown_index][0] if 0 <= self.shown_index < len(maps) else None

    def clear(self) -> None:
        """Forget every figure (new points, a new layout)."""
        self.shown_for.clear()
        self.maps.clear()
        self.maps_changed.emit("")
        self.set_plot(None)

    def set_maps(self, kind: str, run: Any, maps: Maps) -> None:
        """The maps of ``run`` (a ``Run`` of light ``kind``) are shown for that light."""
        self.shown_for[kind] = run
        self.maps[kind] = list(maps)
        self.maps_changed.emit(kind)

    def keep_only(self, kinds) -> None:
        """Forget the maps of the lights not in ``kinds`` (a new comparison started)."""
        gone = [k for k in self.maps if k not in kinds]
        for k in gone:
            del self.maps[k]
        self.shown_for = {k: v for k, v in self.shown_for.items() if k in kinds}
        if gone:
            self.maps_changed.emit("")

    def set_map(self, kind: str, run: Any, index: int, rgba: np.ndarray) -> bool:
        """One height's map drawn for ``run``; False if that run's maps are no longer shown."""
        maps = self.maps.get(kind)
        if self.shown_for.get(kind) is not run or maps is None or \
                not 0 <= index < len(maps):
            return False
        maps[index] = (maps[index][0], rgba)
        self.map_drawn.emit(kind, index, rgba)
        return True

    def restyle(self, keep: str | None = None, hold: bool = False) -> None:
        """Forget the maps of every light but ``keep`` (drawn again when shown; with
        ``hold``, the one shown stays in view until then)."""
        for kind, maps in self.maps.items():
            if kind != keep:
                self.maps[kind] = [(h, None) for h, _ in maps]
        self.restyled.emit(keep, hold)

    def set_plot(self, rgba: np.ndarray | None) -> None:
        self.plot = rgba
        self.plot_changed.emit(rgba)
