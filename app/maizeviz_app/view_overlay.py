"""An orientation triad and a scale bar over the 3D view, drawn by Qt, not by VTK.

A VTK orientation widget or scale bar is a render pass of every frame (60-80 ms each on a
software OpenGL); these are a few lines Qt paints in a corner, recomputed from the camera
when a frame is rendered: the field's axes (x across the rows, y along them, z up) as the
camera sees them, and a bar of a round length (1, 2 or 5 x 10^k cm) as long on screen as
that length at the point the camera looks at.
"""

from __future__ import annotations

import math

import numpy as np
from PySide6.QtCore import QPointF, Qt
from PySide6.QtGui import QColor, QFont, QPainter, QPen
from PySide6.QtWidgets import QWidget

#: The axes' colours (x, y, z) and names.
AXES = (("x", QColor("#c62828")), ("y", QColor("#2e7d32")), ("z", QColor("#1565c0")))
#: Pixels the scale bar aims at (it is a round length near this long).
BAR_PX = 110


def axes_on_screen(position, focal_point, view_up) -> np.ndarray:
    """(3, 2) float: the field's x, y and z unit axes as the camera sees them, in screen
    directions (right, down), each of length up to 1 (shorter when pointing at the eye).

    Parameters
    ----------
    position, focal_point, view_up : (3,) float, cm, the camera's pose
    """
    forward = np.asarray(focal_point, float) - np.asarray(position, float)
    forward /= np.linalg.norm(forward) or 1.0
    right = np.cross(forward, np.asarray(view_up, float))
    right /= np.linalg.norm(right) or 1.0
    up = np.cross(right, forward)
    eye = np.eye(3)
    return np.column_stack([eye @ right, -(eye @ up)])


def round_length(cm_per_px: float, target_px: float = BAR_PX) -> float:
    """The round length (1, 2 or 5 x 10^k cm) nearest below ``target_px`` pixels."""
    if not (cm_per_px > 0 and math.isfinite(cm_per_px)):
        return 0.0
    want = cm_per_px * target_px
    k = math.floor(math.log10(want))
    best = 10.0 ** k
    for m in (2.0, 5.0, 10.0):
        if m * 10.0 ** k <= want:
            best = m * 10.0 ** k
    return best


def length_text(cm: float) -> str:
    return f"{cm / 100:g} m" if cm >= 100 else f"{cm:g} cm" if cm >= 1 else f"{cm * 10:g} mm"


class ViewOverlay:
    """The triad (bottom left) and the scale bar (bottom right) of a viewport: two small
    widgets (a widget the size of the view over its OpenGL surface would cost a composition
    of every frame); :meth:`update_from` takes the camera after each frame, :meth:`place`
    follows the view's size."""

    def __init__(self, view: QWidget):
        self.view = view
        self.triad = _Triad(view)
        self.bar = _Bar(view)
        self.place()

    def place(self) -> None:
        h, w = self.view.height(), self.view.width()
        self.triad.move(4, h - self.triad.height() - 4)
        self.bar.move(w - self.bar.width() - 8, h - self.bar.height() - 6)

    def set_visible(self, on: bool) -> None:
        self.triad.setVisible(on)
        self.bar.setVisible(on)

    def update_from(self, position, focal_point, view_up, view_angle_deg: float,
                    parallel_scale: float | None = None) -> None:
        """The camera's pose (cm) and its view angle (deg), or its parallel scale (cm, half
        the view's height) for a parallel projection."""
        self.triad.axes = axes_on_screen(position, focal_point, view_up)
        h = max(self.view.height(), 1)
        if parallel_scale:
            cm_per_px = 2.0 * parallel_scale / h
        else:
            d = float(np.linalg.norm(np.asarray(focal_point, float)
                                     - np.asarray(position, float)))
            cm_per_px = 2.0 * d * math.tan(math.radians(view_angle_deg) / 2.0) / h
        self.bar.cm = round_length(cm_per_px, min(BAR_PX, self.bar.width() - 20))
        self.bar.px = self.bar.cm / cm_per_px if cm_per_px > 0 else 0.0
        self.triad.update()
        self.bar.update()


class _Corner(QWidget):
    def __init__(self, parent: QWidget, w: int, h: int):
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.setAutoFillBackground(False)
        self.resize(w, h)


class _Triad(_Corner):
    """x, y and z as the camera sees them."""

    def __init__(self, parent: QWidget):
        super().__init__(parent, 84, 84)
        self.axes = np.zeros((3, 2))
        self.setToolTip("the field's axes: x across the rows, y along them, z up")

    def paintEvent(self, _event) -> None:  # noqa: N802 - Qt's name
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        font = QFont(self.font())
        font.setBold(True)
        p.setFont(font)
        centre = QPointF(self.width() / 2, self.height() / 2)
        for (name, colour), (dx, dy) in zip(AXES, self.axes):
            p.setPen(QPen(colour, 2.5))
            p.drawLine(centre, centre + QPointF(dx, dy) * 28)
            p.drawText(centre + QPointF(dx, dy) * 36 + QPointF(-4, 5), name)
        p.end()


class _Bar(_Corner):
    """A round length at the point the camera looks at."""

    def __init__(self, parent: QWidget):
        super().__init__(parent, 150, 34)
        self.cm = 0.0
        self.px = 0.0

    def paintEvent(self, _event) -> None:  # noqa: N802 - Qt's name
        if self.px <= 0:
            return
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        right, base = self.width() - 4.0, self.height() - 8.0
        left = max(right - self.px, 2.0)
        p.setPen(QPen(QColor("#222"), 2))
        p.drawLine(QPointF(left, base), QPointF(right, base))
        for x in (left, right):
            p.drawLine(QPointF(x, base - 5), QPointF(x, base + 5))
        text = length_text(self.cm)
        w = p.fontMetrics().horizontalAdvance(text)
        p.drawText(QPointF((left + right - w) / 2, base - 8), text)
        p.end()
