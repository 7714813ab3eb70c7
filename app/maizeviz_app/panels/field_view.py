"""The field seen from above: where each plant stands, which digitized plant it is, its turn.

Scene units are centimetres with north (+y) up. Drawn: the ground cells (the central tile, where
light is sampled, shaded), the field outline with its corner coordinates, the rows of the layout
document (:func:`maizeviz.canopy.layout.rows_of`) as dashed lines, and each plant as a disc
labelled with its digitized plant id and an arrow for its azimuth (0 deg points east, counter-
clockwise from above). Drag a disc to move the plant; drag the arrow's knob, or turn the mouse
wheel over a plant (5 deg a notch, 1 deg with Shift), to turn it; the wheel elsewhere zooms and
a double click on empty ground fits the field.
"""

from __future__ import annotations

import math
from functools import lru_cache

from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QPainter, QPen, QTransform
from PySide6.QtWidgets import (
    QGraphicsEllipseItem,
    QGraphicsItem,
    QGraphicsLineItem,
    QGraphicsRectItem,
    QGraphicsScene,
    QGraphicsSimpleTextItem,
    QGraphicsView,
)

from maizeviz.canopy.layout import rows_of
from maizeviz_app.panels.layout_model import fmt

WHEEL_STEP_DEG = 5.0
PLANT = QColor("#2e7d32")
PICKED = QColor("#ff8f00")
#: Plants standing on another's ground.
OVERLAPPING = QColor("#d32f2f")


@lru_cache(maxsize=32)
def _pen(color, width: float = 1.0, style=Qt.PenStyle.SolidLine) -> QPen:
    pen = QPen(QColor(color), width, style)
    pen.setCosmetic(True)                       # pixels, whatever the zoom
    return pen


class _Knob(QGraphicsEllipseItem):
    """The tip of a plant's arrow: drag it round to turn the plant."""

    def __init__(self, plant: PlantItem, radius: float):
        super().__init__(-radius, -radius, 2 * radius, 2 * radius, plant.arrow)
        self.plant = plant
        self.setBrush(QBrush(QColor("white")))
        self.setPen(_pen("#1b5e20", 1.5))
        self.setCursor(Qt.CursorShape.CrossCursor)
        self.setToolTip("drag round to turn the plant")

    def mousePressEvent(self, event) -> None:  # noqa: N802 - Qt's name
        event.accept()

    def _azimuth(self, event) -> float:
        d = event.scenePos() - self.plant.scenePos()
        step = 1.0 if event.modifiers() & Qt.KeyboardModifier.ShiftModifier else 5.0
        return (round(math.degrees(math.atan2(d.y(), d.x())) / step) * step) % 360.0

    def mouseMoveEvent(self, event) -> None:  # noqa: N802
        self.plant.show_azimuth(self._azimuth(event))

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802
        self.plant.view.turned.emit(self.plant.index, self._azimuth(event), False)


class PlantItem(QGraphicsEllipseItem):
    """One placement: a disc at (x, y), its digitized plant's id, an azimuth arrow."""

    def __init__(self, view: FieldView, index: int, placement, radius: float, reach: float):
        super().__init__(-radius, -radius, 2 * radius, 2 * radius)
        self.view, self.index = view, index
        # movable but not selectable: the picked plant is shown by its colour (FieldView.select).
        # No Python paint() or itemChange() here: PySide6 leaks a reference to None on every
        # such call, and a few thousand plants drain it until the interpreter aborts at exit.
        self.setFlags(QGraphicsItem.GraphicsItemFlag.ItemIsMovable)
        self.setBrush(QBrush(PLANT))
        self.setPen(_pen("#1b5e20"))
        self.setCursor(Qt.CursorShape.OpenHandCursor)
        self.setZValue(2)
        self.arrow = QGraphicsLineItem(0, 0, reach, 0, self)
        self.arrow.setPen(_pen("#1b5e20", 2))
        self.knob = _Knob(self, 0.45 * radius)
        self.knob.setPos(reach, 0)
        self.label = QGraphicsSimpleTextItem("", self)
        self.label.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
        font = QFont()
        font.setPointSize(8)
        self.label.setFont(font)
        self.label.setPos(radius * 0.8, -radius * 0.8)
        self._pressed_at = QPointF()
        self.set_placement(placement)

    def set_placement(self, p) -> None:
        self.placement = p
        self.setPos(p.x, p.y)
        self.label.setText(str(p.plant))
        self.setToolTip(f"plant {p.plant} at x {fmt(p.x)}, y {fmt(p.y)} cm, turned "
                        f"{fmt(p.azimuth_deg)}°; drag to move, wheel or knob to turn")
        self.show_azimuth(p.azimuth_deg)

    def show_azimuth(self, deg: float) -> None:
        # the view flips y (north up), so Qt's rotation shows counter-clockwise, as azimuths go
        self.arrow.setRotation(deg)

    def mousePressEvent(self, event) -> None:  # noqa: N802
        self._pressed_at = self.pos()
        self.view.select(self.index)
        self.view.picked.emit(self.index)
        super().mousePressEvent(event)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802
        super().mouseReleaseEvent(event)
        if self.pos() != self._pressed_at:
            self.view.moved.emit(self.index, self.pos().x(), self.pos().y())


class FieldView(QGraphicsView):
    """Top view of a layout. Signals carry placement indices and new values (cm, deg):
    ``moved(i, x, y)``, ``turned(i, azimuth, by_wheel)``, ``picked(i)``."""

    moved = Signal(int, float, float)
    turned = Signal(int, float, bool)
    picked = Signal(int)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setScene(QGraphicsScene(self))
        self.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.setTransformationAnchor(QGraphicsView.ViewportAnchor.AnchorUnderMouse)
        self.setViewportUpdateMode(QGraphicsView.ViewportUpdateMode.SmartViewportUpdate)
        self.setBackgroundBrush(QBrush(QColor("#f4f1e8")))
        self.setMinimumSize(160, 120)
        self.items_: list[PlantItem] = []
        self._labels: list[QGraphicsSimpleTextItem] = []
        self._spacing = 30.0
        self._zoomed = False
        self._picked = -1
        self._overlapping: set[int] = set()
        self._ground: list[QGraphicsItem] = []       # cells, field, rows, corner labels
        self._spare: list[PlantItem] = []            # plant items hidden, to be used again

    # ------------------------------------------------------------------------ content
    def show_layout(self, layout, placements) -> None:
        """Draw ``layout``'s ground with ``placements`` (the edited ones) on it. The plants'
        items are kept and moved where the spacing stays (a new item costs ten times a move:
        an undo or a new field of hundreds of plants redraws in a fraction of the time)."""
        scene = self.scene()
        for item in self._ground:
            scene.removeItem(item)
        self._ground = []
        old = self._spacing
        self._picked = -1
        self._overlapping = set()
        if layout is None:
            scene.clear()
            self.items_, self._spare = [], []
            return
        rs, ps = layout.row_spacing, layout.plant_spacing
        self._spacing = min(rs, ps)
        if self._spacing != old:
            for item in self.items_ + self._spare:
                scene.removeItem(item)
            self.items_, self._spare = [], []
        centre = {tuple(c) for c in layout.centre_cells.tolist()}
        many = 0 < len(centre) < len(layout.cells)      # a central tile among others
        for cell in layout.cells.tolist():
            x0, y0, x1, y1 = cell
            box = QGraphicsRectItem(QRectF(x0, y0, x1 - x0, y1 - y0))
            box.setPen(_pen("#c8c0a8", 0.8))
            if many and tuple(cell) in centre:
                box.setBrush(QBrush(QColor("#fff3c4")))
            scene.addItem(box)
            self._ground.append(box)
        x0, y0, x1, y1 = layout.bounds
        field = scene.addRect(QRectF(x0, y0, x1 - x0, y1 - y0), _pen("#5d4037", 2))
        field.setZValue(1)
        self._ground.append(field)
        for row in rows_of(placements):
            line = scene.addLine(row["x"], y0, row["x"], y1,
                                 _pen("#8d9e6b", 1, Qt.PenStyle.DashLine))
            line.setZValue(0.5)
            self._ground.append(line)
        self._labels = []
        for text, x, y, above in ((f"{fmt(x0, 0)}, {fmt(y0, 0)} cm", x0, y0, False),
                                  (f"{fmt(x1, 0)}, {fmt(y1, 0)} cm", x1, y1, True)):
            label = scene.addSimpleText(text)
            label.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
            label.setBrush(QBrush(QColor("#5d4037")))
            label.setPos(x, y)
            if above:                                   # the top-right corner: above, inside
                r = label.boundingRect()
                label.setTransform(QTransform.fromTranslate(-r.width(), -r.height() - 2))
            self._ground.append(label)
        radius = 0.16 * self._spacing
        for item in self.items_[len(placements):]:     # kept hidden for the next field
            item.hide()
            self._spare.append(item)
        del self.items_[len(placements):]
        for i, p in enumerate(placements):
            if i < len(self.items_):
                item = self.items_[i]
            elif self._spare:
                item = self._spare.pop()
                item.show()
                self.items_.append(item)
            else:
                item = PlantItem(self, i, p, radius, 0.42 * self._spacing)
                scene.addItem(item)
                self.items_.append(item)
                continue
            item.index = i
            item.setBrush(QBrush(PLANT))
            item.set_placement(p)
        pad = 0.06 * max(x1 - x0, y1 - y0) + radius
        rect = QRectF(x0, y0, x1 - x0, y1 - y0)
        for item in self.items_:                        # plants standing off the field too
            rect = rect.united(QRectF(item.x(), item.y(), 0, 0))
        scene.setSceneRect(rect.adjusted(-pad, -pad, pad, pad))
        self._zoomed = False
        self.fit()

    def update_plant(self, index: int, placement) -> None:
        if 0 <= index < len(self.items_):
            self.items_[index].set_placement(placement)

    def _colour(self, index: int) -> QColor:
        if index == self._picked:
            return PICKED
        return OVERLAPPING if index in self._overlapping else PLANT

    def set_overlapping(self, indices: set[int]) -> None:
        """Draw the plants at ``indices`` red: they stand on another's ground."""
        changed = self._overlapping ^ set(indices)
        self._overlapping = set(indices)
        for i in changed:
            if 0 <= i < len(self.items_):
                self.items_[i].setBrush(QBrush(self._colour(i)))

    def select(self, index: int) -> None:
        """Show placement ``index`` as the picked one (-1: none)."""
        old = self._picked
        self._picked = index if 0 <= index < len(self.items_) else -1
        if 0 <= old < len(self.items_):
            self.items_[old].setBrush(QBrush(self._colour(old)))
        if self._picked >= 0:
            item = self.items_[self._picked]
            item.setBrush(QBrush(PICKED))
            self.ensureVisible(item, 20, 20)

    # --------------------------------------------------------------------------- view
    def fit(self) -> None:
        """Fit the field, north up."""
        rect = self.scene().sceneRect()
        if rect.isEmpty():
            return
        self.resetTransform()
        self.fitInView(rect, Qt.AspectRatioMode.KeepAspectRatio)
        self.scale(1, -1)
        self._level_of_detail()

    def _level_of_detail(self) -> None:
        # plant ids only when a plant's cell is big enough on screen to hold one; arrows only
        # when they are long enough to show a direction (a 30 x 30 field in a 400 px dock:
        # a third of the items to paint, 0.1 s less a frame)
        cell = abs(self.transform().m11()) * self._spacing
        readable, pointed = cell > 22, cell > 12
        for item in self.items_:
            item.label.setVisible(readable)
            item.arrow.setVisible(pointed)

    def resizeEvent(self, event) -> None:  # noqa: N802
        super().resizeEvent(event)
        if not self._zoomed:
            self.fit()

    def mouseDoubleClickEvent(self, event) -> None:  # noqa: N802
        if self._plant_at(event.position().toPoint()) is None:
            self._zoomed = False
            self.fit()
        else:
            super().mouseDoubleClickEvent(event)

    def _plant_at(self, pos) -> PlantItem | None:
        item = self.itemAt(pos)
        while item is not None and not isinstance(item, PlantItem):
            item = item.parentItem()
        return item

    def wheelEvent(self, event) -> None:  # noqa: N802
        notches = event.angleDelta().y() / 120.0
        if not notches:
            return
        plant = self._plant_at(event.position().toPoint())
        if plant is not None:
            step = 1.0 if event.modifiers() & Qt.KeyboardModifier.ShiftModifier else WHEEL_STEP_DEG
            az = (plant.placement.azimuth_deg + step * notches) % 360.0
            self.turned.emit(plant.index, az, True)
        else:
            factor = 1.15 ** notches
            self.scale(factor, factor)
            self._zoomed = True
            self._level_of_detail()
        event.accept()
