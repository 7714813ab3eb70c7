"""A heatmap picture that tells the value under the mouse.

The figure is drawn in a worker (:func:`maizeviz_app.plots.heatmap_image`), which also says
where the map's bins lie in its pixels (:class:`maizeviz_app.plots.Heatmap`); hovering looks
the bin up there: no figure is drawn again and nothing is computed but one index, so the
answer is immediate.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, Signal

from maizeviz_app.panels.image_view import ImageView
from maizeviz_app.plots import Heatmap


def hover_text(heatmap: Heatmap, px: float, py: float) -> str:
    """What the bin under the image pixel (``px``, ``py``) holds, in words; "" off the map."""
    found = heatmap.value_at(px, py)
    if found is None:
        return ""
    x, y, value, rays = found
    where = f"x {x:.0f} cm, y {y:.0f} cm, height {heatmap.height_cm:g} cm"
    if rays == 0 or not np.isfinite(value):
        return f"{where}: no ray reached this bin"
    return f"{where}: {heatmap.what} {value:.3f} ({rays:,} rays)"


class HeatmapView(ImageView):
    """An :class:`~maizeviz_app.panels.image_view.ImageView` of a :class:`Heatmap` (or plain RGBA
    pixels); ``hovered(text)``: what lies under the mouse ("" off the map or away)."""

    hovered = Signal(str)
    #: The (low, high) the colours of the heatmap shown span.
    limits_shown = Signal(float, float)

    def __init__(self, placeholder: str = "", parent=None):
        super().__init__(placeholder, parent)
        self.heatmap: Heatmap | None = None
        self.setMouseTracking(True)

    def set_rgba(self, rgba) -> None:
        """Show a :class:`Heatmap` (its value under the mouse then told) or RGBA pixels."""
        self.heatmap = rgba if isinstance(rgba, Heatmap) else None
        super().set_rgba(rgba.rgba if isinstance(rgba, Heatmap) else rgba)
        self.hovered.emit("")
        if self.heatmap is not None:
            self.limits_shown.emit(*self.heatmap.limits)

    def image_point(self, pos: QPointF) -> tuple[float, float] | None:
        """The image pixel under the widget point ``pos`` (the picture is scaled to fit,
        keeping its aspect, and centred), None outside the picture."""
        image = self.image()
        if image is None or image.width() == 0:
            return None
        scale = min(self.width() / image.width(), self.height() / image.height())
        dx = (self.width() - image.width() * scale) / 2
        dy = (self.height() - image.height() * scale) / 2
        px, py = (pos.x() - dx) / scale, (pos.y() - dy) / scale
        if not (0 <= px < image.width() and 0 <= py < image.height()):
            return None
        return px, py

    def text_at(self, pos: QPointF) -> str:
        """:func:`hover_text` under the widget point ``pos``."""
        point = self.image_point(pos)
        if point is None or self.heatmap is None:
            return ""
        return hover_text(self.heatmap, *point)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().mouseMoveEvent(event)
        self.hovered.emit(self.text_at(event.position()))

    def leaveEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().leaveEvent(event)
        self.hovered.emit("")
