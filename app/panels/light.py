"""Direct light: the settings, Compute/Cancel, the results table (every height, every level
traced under the same sun) and the figures (heatmap per height, transmission vs height).

:class:`LightRuns` is the model: the last result per mesh level, all traced with the same
settings, so switching levels and computing again adds a curve to the comparison. Changing the
sun, heights, density or periodicity starts a new comparison.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QImage, QPixmap
from PySide6.QtWidgets import (QAbstractItemView, QCheckBox, QComboBox, QDoubleSpinBox,
                               QFormLayout, QHBoxLayout, QHeaderView, QLabel, QLineEdit,
                               QPushButton, QSizePolicy, QTableWidget, QTableWidgetItem,
                               QVBoxLayout, QWidget)

from maizeviz.mesh.levels import COMPLEXITY_STOPS, parse_level

DEFAULT_PLACE = "2005-08-01 12:00 39.9 116.4 Asia/Shanghai"
DEFAULT_HEIGHTS = "0, 50, 100, 150, 200, 225"
PROBLEM_STYLE = "border: 2px solid #d0342c; border-radius: 3px;"


class InputProblem(ValueError):
    """A light setting the user typed that cannot be used; ``quantity`` names the field."""

    def __init__(self, message: str, quantity: str):
        super().__init__(message)
        self.quantity = quantity


def parse_heights(text: str) -> tuple[float, ...]:
    """``"0, 50, 100"`` -> (0.0, 50.0, 100.0); a word that is not a number is named."""
    out = []
    for part in text.replace(";", ",").split(","):
        part = part.strip()
        if not part:
            continue
        try:
            h = float(part.removesuffix("cm").strip())
        except ValueError:
            raise InputProblem(f"heights: '{part}' is not a number of centimetres; write them "
                               "separated by commas, e.g. 0, 50, 100", "heights") from None
        if not math.isfinite(h) or h < 0:
            raise InputProblem(f"heights must be 0 cm or more, got {part}", "heights")
        out.append(h)
    if not out:
        raise InputProblem("give at least one height in cm, e.g. 0, 50, 100", "heights")
    return tuple(out)


def level_order(label: str) -> int:
    """Fine-to-coarse rank of a level label (``K=4`` ... ``4 triangles``), for sorting."""
    for k, stop in enumerate(COMPLEXITY_STOPS):
        if parse_level(stop).label == label.split(",")[0]:
            return k
    return len(COMPLEXITY_STOPS)


@dataclass
class Run:
    """One light result: the level it was traced on, the canopy it belongs to (``signature``)
    and each leaf triangle's light class (F,) int8 (None until computed)."""

    label: str
    signature: tuple
    result: Any
    classes: np.ndarray | None = None


class LightRuns:
    """The last light result per mesh level, traced under the same settings."""

    def __init__(self) -> None:
        self.runs: dict[str, Run] = {}
        self.settings: tuple | None = None
        self.last: Run | None = None

    def add(self, run: Run, settings: tuple) -> bool:
        """Keep ``run``; True if it replaced results traced with other settings."""
        dropped = bool(self.runs) and settings != self.settings
        if dropped:
            self.runs.clear()
        self.settings = settings
        self.runs[run.label] = run
        self.runs = dict(sorted(self.runs.items(), key=lambda kv: level_order(kv[0])))
        self.last = run
        return dropped

    def clear(self) -> None:
        self.runs.clear()
        self.settings = None
        self.last = None

    def for_signature(self, signature: tuple) -> Run | None:
        for run in self.runs.values():
            if run.signature == signature:
                return run
        return None

    def heights(self) -> tuple[float, ...]:
        if self.last is None:
            return ()
        return tuple(float(h) for h in self.last.result.heights_cm)

    def curves(self):
        from maizeviz_app.plots import Curve

        return [Curve(r.label, tuple(map(float, r.result.heights_cm)),
                      tuple(map(float, r.result.transmission))) for r in self.runs.values()]

    def table(self) -> tuple[list[str], list[list[str]]]:
        """Header and rows (one per height) of the results table."""
        labels = list(self.runs)
        header = ["height cm"] + labels
        rows = []
        for i, h in enumerate(self.heights()):
            row = [f"{h:g}"]
            for lab in labels:
                r = self.runs[lab].result
                row.append(f"{r.transmission[i]:.3f}" if i < len(r.transmission) else "")
            rows.append(row)
        return header, rows


class LightPanel(QWidget):
    """Signals: ``compute_requested()``, ``cancel_requested()``, ``place_requested(text)``,
    ``export_requested(what)`` with what in ``table``, ``heatmap``, ``plot``, ``canopy``."""

    compute_requested = Signal()
    cancel_requested = Signal()
    place_requested = Signal(str)
    export_requested = Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.zenith = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=89.9, value=22.34,
                                     suffix=" °")
        self.zenith.setToolTip("angle of the sun from the vertical")
        self.azimuth = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=360.0, value=166.95,
                                      suffix=" ° from N")
        self.azimuth.setToolTip("direction of the sun, clockwise from north")
        form.addRow("sun zenith", self.zenith)
        form.addRow("sun azimuth", self.azimuth)
        self.place = QLineEdit(DEFAULT_PLACE)
        self.place.setToolTip("date, local time, latitude, longitude, time zone: the sun's "
                              "angles are computed with pvlib")
        self.place_button = QPushButton("Sun from place")
        self.place_button.clicked.connect(lambda: self.place_requested.emit(self.place.text()))
        place_row = QHBoxLayout()
        place_row.addWidget(self.place, 1)
        place_row.addWidget(self.place_button)
        form.addRow("date time lat lon tz", place_row)
        self.heights = QLineEdit(DEFAULT_HEIGHTS)
        self.heights.setToolTip("heights of the sample planes, cm, separated by commas")
        form.addRow("heights (cm)", self.heights)
        self.density = QDoubleSpinBox(decimals=2, minimum=0.01, maximum=100.0, value=2.0,
                                      suffix=" rays/cm²")
        form.addRow("ray density", self.density)
        self.periodic = QCheckBox("infinite field (rays wrap at the plot edges)")
        self.periodic.setChecked(True)
        form.addRow(self.periodic)
        lay.addLayout(form)
        buttons = QHBoxLayout()
        self.compute_button = QPushButton("Compute direct light")
        self.compute_button.setToolTip("trace the sun through the canopy shown (Ctrl+L)")
        self.compute_button.clicked.connect(self.compute_requested)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel_requested)
        buttons.addWidget(self.compute_button, 1)
        buttons.addWidget(self.cancel_button)
        lay.addLayout(buttons)
        lay.addWidget(QLabel("transmission by height and mesh level (the paper's Table 3)"))
        self.table = QTableWidget(0, 1)
        self.table.setHorizontalHeaderLabels(["height cm"])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QAbstractItemView.NoEditTriggers)
        self.table.setVerticalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeToContents)
        self.table.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        lay.addWidget(self.table)
        self.info = QLabel("")
        self.info.setWordWrap(True)
        lay.addWidget(self.info)
        exports = QHBoxLayout()
        self.export_buttons = {}
        for what, text, tip in (("table", "Table…", "the transmission table as CSV"),
                                ("heatmap", "Heatmap…", "the heatmap shown, as PNG"),
                                ("plot", "Plot…", "transmission vs height, as PNG"),
                                ("canopy", "Canopy…", "the canopy with its light classes as "
                                                      "cell data (PLY, VTK...)")):
            b = QPushButton(text)
            b.setToolTip(f"export {tip}")
            b.setEnabled(False)
            b.clicked.connect(lambda _=False, w=what: self.export_requested.emit(w))
            exports.addWidget(b)
            self.export_buttons[what] = b
        lay.addWidget(QLabel("export"))
        lay.addLayout(exports)
        lay.addStretch(1)
        self.fields = {"sun": self.zenith, "heights": self.heights, "density": self.density,
                       "periodic": self.periodic, "place": self.place, "date": self.place,
                       "time": self.place, "tz": self.place, "rect": self.heights}
        for w in (self.heights, self.place):
            w.textEdited.connect(lambda _t, w=w: self.clear_problem(w))
        for w in (self.zenith, self.azimuth, self.density):
            w.valueChanged.connect(lambda _v, w=w: self.clear_problem(w))
        self._fit_table()

    # ------------------------------------------------------------------ settings
    def settings(self) -> dict:
        """The settings as typed (for a project file)."""
        return {"zenith_deg": self.zenith.value(), "azimuth_deg": self.azimuth.value(),
                "place": self.place.text(), "heights": self.heights.text(),
                "density": self.density.value(), "periodic": self.periodic.isChecked()}

    def apply_settings(self, s: dict) -> None:
        self.zenith.setValue(float(s.get("zenith_deg", self.zenith.value())))
        self.azimuth.setValue(float(s.get("azimuth_deg", self.azimuth.value())))
        self.place.setText(str(s.get("place", self.place.text())))
        self.heights.setText(str(s.get("heights", self.heights.text())))
        self.density.setValue(float(s.get("density", self.density.value())))
        self.periodic.setChecked(bool(s.get("periodic", self.periodic.isChecked())))

    def request(self):
        """The light request the fields describe (hit classes on: the canopy is coloured).

        Raises
        ------
        InputProblem, MaizevizError
            Naming the field (``quantity``).
        """
        from maizeviz.light.request import LightRequest
        from maizeviz.light.sun import Sun

        heights = parse_heights(self.heights.text())
        sun = Sun(self.zenith.value(), self.azimuth.value())
        return LightRequest(sun, heights, self.density.value(), None,
                            self.periodic.isChecked(), 2, classes=True)

    def settings_key(self, request) -> tuple:
        return (round(request.sun.zenith_deg, 6), round(request.sun.azimuth_deg, 6),
                tuple(request.heights_cm), request.density, request.periodic)

    # ------------------------------------------------------------------ problems
    def point_at(self, quantity: str | None, message: str) -> bool:
        """Mark the field a problem is about (red frame, tooltip, focus); False if none."""
        w = self.fields.get(quantity or "")
        if w is None:
            return False
        w.setStyleSheet(PROBLEM_STYLE)
        w.setToolTip(message)
        w.setFocus()
        return True

    def clear_problem(self, w=None) -> None:
        for f in ([w] if w is not None else set(self.fields.values())):
            if f.styleSheet():
                f.setStyleSheet("")

    # ------------------------------------------------------------------ state
    def set_running(self, running: bool) -> None:
        self.compute_button.setEnabled(not running)
        self.cancel_button.setEnabled(running)

    def show_runs(self, runs: LightRuns, info: str = "") -> None:
        header, rows = runs.table()
        self.table.setColumnCount(len(header))
        self.table.setHorizontalHeaderLabels(header)
        self.table.setRowCount(len(rows))
        for r, vals in enumerate(rows):
            for c, v in enumerate(vals):
                item = QTableWidgetItem(v)
                item.setTextAlignment(Qt.AlignRight | Qt.AlignVCenter)
                self.table.setItem(r, c, item)
        self._fit_table()
        self.info.setText(info)
        for b in self.export_buttons.values():
            b.setEnabled(runs.last is not None)

    def _fit_table(self) -> None:
        """Every row visible: the table is as tall as its rows (no vertical scrolling)."""
        t = self.table
        t.resizeRowsToContents()
        h = t.horizontalHeader().height() + 2 * t.frameWidth()
        h += sum(t.rowHeight(r) for r in range(t.rowCount()))
        if t.horizontalScrollBar().isVisible() or t.columnCount() > 4:
            h += t.horizontalScrollBar().sizeHint().height()
        t.setFixedHeight(max(h, t.horizontalHeader().height() + 30))


class ImageView(QLabel):
    """A picture scaled to fit the widget, keeping its aspect (figures drawn elsewhere)."""

    def __init__(self, placeholder: str = "", parent=None):
        super().__init__(placeholder, parent)
        self._image: QImage | None = None
        self.setAlignment(Qt.AlignCenter)
        self.setMinimumSize(160, 120)
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Ignored)
        self.setStyleSheet("background: white; color: #666;")

    def set_rgba(self, rgba: np.ndarray | None) -> None:
        if rgba is None:
            self._image = None
            self.clear()
            return
        h, w = rgba.shape[:2]
        self._image = QImage(np.ascontiguousarray(rgba).data, w, h, 4 * w,
                             QImage.Format_RGBA8888).copy()
        self._rescale()

    def image(self) -> QImage | None:
        return self._image

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._rescale()

    def _rescale(self) -> None:
        if self._image is None:
            return
        self.setPixmap(QPixmap.fromImage(self._image).scaled(
            self.size(), Qt.KeepAspectRatio, Qt.SmoothTransformation))

    def sizeHint(self) -> QSize:  # noqa: N802
        return QSize(360, 200)


class LightPlots(QWidget):
    """The heatmap of one height (chosen in ``height``) beside transmission vs height.
    ``heatmap_needed(index)`` asks for a height's figure not drawn yet."""

    heatmap_needed = Signal(int)

    def __init__(self, parent=None):
        super().__init__(parent)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        left = QVBoxLayout()
        top = QHBoxLayout()
        top.addWidget(QLabel("heatmap at"))
        self.height = QComboBox()
        self.height.setToolTip("height of the sample plane shown (PgUp / PgDown)")
        self.height.currentIndexChanged.connect(self._show_height)
        top.addWidget(self.height)
        top.addStretch(1)
        left.addLayout(top)
        self.heatmap = ImageView("compute direct light to see where it reaches each height")
        left.addWidget(self.heatmap, 1)
        lay.addLayout(left, 1)
        self.transmission = ImageView("transmission by height appears here")
        lay.addWidget(self.transmission, 1)
        self._maps: list[tuple[float, np.ndarray | None]] = []

    def set_heatmaps(self, maps: Sequence[tuple[float, np.ndarray | None]]) -> None:
        keep = self.height.currentIndex()
        self._maps = list(maps)
        self.height.blockSignals(True)
        self.height.clear()
        self.height.addItems([f"{h:g} cm" for h, _ in self._maps])
        self.height.blockSignals(False)
        if self._maps:
            self.height.setCurrentIndex(keep if 0 <= keep < len(self._maps) else 0)
        self._show_height(self.height.currentIndex())

    def set_heatmap(self, index: int, rgba: np.ndarray) -> None:
        """A height's figure, drawn after it was asked for."""
        if 0 <= index < len(self._maps):
            self._maps[index] = (self._maps[index][0], rgba)
            if index == self.height.currentIndex():
                self.heatmap.set_rgba(rgba)

    def _show_height(self, index: int) -> None:
        if 0 <= index < len(self._maps):
            rgba = self._maps[index][1]
            self.heatmap.set_rgba(rgba)
            if rgba is None:
                self.heatmap.setText("drawing…")
                self.heatmap_needed.emit(index)
        else:
            self.heatmap.set_rgba(None)

    @property
    def shown_height(self) -> float | None:
        i = self.height.currentIndex()
        return self._maps[i][0] if 0 <= i < len(self._maps) else None

    def set_transmission(self, rgba: np.ndarray | None) -> None:
        self.transmission.set_rgba(rgba)
