"""Virtual field instruments in the app: a line ceptometer, a canopy analyser or a
hemispherical camera placed on the layout's top view, their readings in a table and a figure,
and the record ``maizeviz instrument ... --json`` prints saved as JSON (docs/instruments.md).

Click the top view to place the instrument (each click adds a place; *Clear* removes them);
*Read* traces it through the canopy on screen on a worker thread of the panel's own (one
reading at a time: a new one supersedes the last), and the figure is drawn there too (Agg), so
the GUI thread only swaps the table and the picture in.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, QThreadPool, Signal
from PySide6.QtGui import QBrush, QColor, QPainter, QPen, QTransform
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGraphicsScene,
    QGraphicsView,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from maizeviz_app.panels.image_view import ImageView
from maizeviz_app.workers import JobRunner

KINDS = {"ceptometer": "Ceptometer (LP-80 style)", "analyser": "Canopy analyser (LAI-2200 style)",
         "hemiphoto": "Hemispherical photograph"}
VIEW_CAPS = ("360", "270", "180", "90", "45")


def read_instrument(canopy, kind: str, places: list[tuple[float, float]],
                    s: dict[str, Any]) -> dict[str, Any]:
    """Read an instrument (any thread; no Qt): ``{"record": the --json record, "rows": table
    rows, "header": their names, "rgba": the figure}``. ``s``: the panel's settings."""
    from maizeviz.instruments.sight import Sight

    sight = Sight.of(canopy, s["periodic"], not s["leaves_only"])
    north = canopy.layout.north_deg
    if kind == "ceptometer":
        from maizeviz.instruments.ceptometer import Probe, probe_azimuth, read_ceptometer
        from maizeviz.light.sources.sun import Sun

        az = probe_azimuth(s["orientation"])
        r = read_ceptometer(sight, [Probe(x, y, s["height"], az) for x, y in places],
                            Sun(s["zenith"], s["azimuth"]), par_umol=s["par"],
                            beam_fraction=s["beam_fraction"], north_deg=north)
        rec = r.as_dict()
        header = ["probe", "x cm", "y cm", "tau", "intercepted", "LAI"]
        rows = [[i + 1, f"{p['x_cm']:.1f}", f"{p['y_cm']:.1f}", f"{p['tau']:.4f}",
                 f"{p['intercepted']:.4f}", ""] for i, p in enumerate(rec["probes"])]
        rows.append(["all", "", "", f"{r.tau:.4f}", f"{r.intercepted:.4f}",
                     "inf" if rec["lai"] is None else f"{rec['lai']:.3f}"])
        fig = _ceptometer_figure(r)
    elif kind == "analyser":
        from maizeviz.instruments.analyser import AnalyserPosition, read_analyser

        ana = read_analyser(sight, [AnalyserPosition(x, y, s["height"], s["heading"])
                                    for x, y in places],
                            view_cap_deg=float(s["view_cap"]), rays_per_ring=s["rays"])
        rec = ana.as_dict()
        header = ["ring", "zenith deg", "weight", "T", "K"]
        rows = [[g["ring"], f"{g['from_deg']:g}-{g['to_deg']:g}", g["weight"],
                 f"{g['transmission']:.4f}",
                 "inf" if g["contact"] is None else f"{g['contact']:.4f}"]
                for g in rec["rings"]]
        rows.append(["LAI", "inf" if rec["lai"] is None else f"{rec['lai']:.3f}", "MTA",
                     "-" if rec["mta_deg"] is None else f"{rec['mta_deg']:.1f} deg", ""])
        fig = _analyser_figure(ana)
    else:
        from maizeviz.instruments.hemiphoto import hemiphoto

        photos = [hemiphoto(sight, x, y, s["height"], size=s["size"], north_deg=north)
                  for x, y in places]
        rec = {"instrument": "hemiphoto", "photos": [p.as_dict() for p in photos]}
        header = ["photo", "ring", "zenith deg", "gap fraction"]
        rows = [[k + 1, g["ring"], f"{g['from_deg']:g}-{g['to_deg']:g}",
                 f"{g['gap_fraction']:.4f}"]
                for k, d in enumerate(rec["photos"]) for g in d["rings"]]
        return {"record": rec, "rows": rows, "header": header,
                "rgba": np.dstack([photos[-1].image,
                                   np.full(photos[-1].image.shape[:2], 255, np.uint8)])}
    from maizeviz_app.plots import rgba

    rec.update(periodic=s["periodic"], stalks=not s["leaves_only"])
    return {"record": rec, "rows": rows, "header": header, "rgba": rgba(fig)}


def _ceptometer_figure(r):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5, 3), dpi=90)
    ax = fig.add_subplot()
    for k, par in enumerate(r.par_umol):
        ax.plot(np.arange(1, len(par) + 1), par, "-", linewidth=1, label=f"probe {k + 1}")
    ax.axhline(r.above_umol, color="0.5", linestyle="--", linewidth=1, label="above")
    ax.set_xlabel("sensor along the probe")
    ax.set_ylabel("PAR (umol m-2 s-1)")
    ax.set_title(f"ceptometer: tau {r.tau:.3f}, intercepted {r.intercepted:.3f}", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    fig.subplots_adjust(left=0.15, right=0.97, bottom=0.16, top=0.9)
    return fig


def _analyser_figure(r):
    from matplotlib.figure import Figure

    from maizeviz.instruments.analyser import RING_CENTRES_DEG

    fig = Figure(figsize=(5, 3), dpi=90)
    ax = fig.add_subplot()
    for gaps in r.gap_fraction:
        ax.plot(RING_CENTRES_DEG, gaps, "-", color="0.75", linewidth=0.8)
    ax.plot(RING_CENTRES_DEG, r.transmission, "o-", color="#2e7d32", label="T (mean)")
    ax.set_xlabel("ring centre (deg from the zenith)")
    ax.set_ylabel("gap fraction")
    ax.set_ylim(0, 1)
    lai = r.lai
    ax.set_title(f"canopy analyser: LAI {lai:.2f}" if math.isfinite(lai) else
                 "canopy analyser: a ring sees no gap", fontsize=9)
    ax.legend(fontsize=7)
    fig.subplots_adjust(left=0.15, right=0.97, bottom=0.16, top=0.9)
    return fig


class TopView(QGraphicsView):
    """The field from above (north, +y, up): the plot, each plant as a disc, the places
    chosen. A left click emits ``clicked(x, y)`` in field cm."""

    clicked = Signal(float, float)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setScene(QGraphicsScene(self))
        self.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.setTransform(QTransform.fromScale(1, -1))          # y up
        self.setMinimumHeight(160)
        off = Qt.ScrollBarPolicy.ScrollBarAlwaysOff
        self.setHorizontalScrollBarPolicy(off)
        self.setVerticalScrollBarPolicy(off)
        self.setAccessibleName("instrument places")
        self.setToolTip("click to place the instrument (each click adds a place)")
        self._bounds = (0.0, 0.0, 1.0, 1.0)

    def show_field(self, canopy, places: list[tuple[float, float]], kind: str,
                   azimuth_deg: float) -> None:
        sc = self.scene()
        sc.clear()
        if canopy is None:
            return
        x0, y0, x1, y1 = self._bounds = canopy.layout.bounds
        pen = QPen(QColor("#555"))
        pen.setCosmetic(True)
        sc.addRect(x0, y0, x1 - x0, y1 - y0, pen, QBrush(QColor("#f4f1e8")))
        for p in canopy.layout.placements:
            sc.addEllipse(p.x - 5, p.y - 5, 10, 10, QPen(QColor("#1b5e20")),
                          QBrush(QColor("#66bb6a")))
        mark = QPen(QColor("#d84315"), 3)
        mark.setCosmetic(True)
        for x, y in places:
            if kind == "ceptometer":
                a = math.radians(azimuth_deg)
                dx, dy = 40 * math.sin(a), 40 * math.cos(a)
                sc.addLine(x - dx, y - dy, x + dx, y + dy, mark)
            else:
                sc.addEllipse(x - 4, y - 4, 8, 8, mark, QBrush(QColor("#ff8a65")))
        self._fit()

    def _fit(self) -> None:
        """The plot (and a margin) fills the view: the same mapping whatever is placed, so
        that a click lands where the previous ones did."""
        x0, y0, x1, y1 = self._bounds
        m = 0.05 * max(x1 - x0, y1 - y0)
        rect = QRectF(x0 - m, y0 - m, x1 - x0 + 2 * m, y1 - y0 + 2 * m)
        self.setSceneRect(rect)                 # not the items' (a mark moves the view)
        self.fitInView(rect, self._keep())

    @staticmethod
    def _keep():
        return Qt.AspectRatioMode.KeepAspectRatio

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._fit()

    def mousePressEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if event.button() == Qt.MouseButton.LeftButton:
            p: QPointF = self.mapToScene(event.position().toPoint())
            self.clicked.emit(float(p.x()), float(p.y()))
        event.accept()


class InstrumentsPanel(QWidget):
    """Place and read a virtual instrument in the canopy on screen.

    ``canopy()``: a callable giving the canopy on screen (or None). Signals: ``read_done(dict)``
    with the --json record once a reading is shown; ``failed(str)`` with a one-line reason.
    """

    read_done = Signal(object)
    failed = Signal(str)

    def __init__(self, canopy=None, parent=None):
        super().__init__(parent)
        self._canopy = canopy or (lambda: None)
        self.places: list[tuple[float, float]] = []
        self.record: dict | None = None
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self.runner = JobRunner(self, pool=self._pool)
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.kind = QComboBox()
        for key, text in KINDS.items():
            self.kind.addItem(text, key)
        self.kind.setAccessibleName("instrument")
        form.addRow("instrument", self.kind)
        self.height_spin = self._spin(0, 1000, 0, " cm", "height of the sensors above the ground")
        form.addRow("height", self.height_spin)
        self.orientation = QComboBox()
        self.orientation.addItems(["across", "along"])
        self.orientation.setToolTip("the probe across the rows or along them")
        form.addRow("probe", self.orientation)
        self.zenith = self._spin(0, 89.9, 30, " deg", "the sun's zenith angle")
        self.azimuth = self._spin(0, 360, 180, " deg", "the sun's azimuth, clockwise from north")
        sun = QHBoxLayout()
        sun.addWidget(self.zenith)
        sun.addWidget(self.azimuth)
        form.addRow("sun zenith, azimuth", sun)
        self.beam = self._spin(0, 1, 0.8, "", "the sun's share of the PAR above")
        self.beam.setSingleStep(0.05)
        form.addRow("beam fraction", self.beam)
        self.view_cap = QComboBox()
        self.view_cap.addItems(VIEW_CAPS)
        self.view_cap.setToolTip("azimuth the analyser sees, deg (360: no cap)")
        form.addRow("view cap", self.view_cap)
        self.size_spin = QSpinBox()
        self.size_spin.setRange(16, 2048)
        self.size_spin.setValue(256)
        self.size_spin.setSuffix(" px")
        self.size_spin.setToolTip("pixels a side of the photograph")
        form.addRow("photo size", self.size_spin)
        self.periodic = QCheckBox("periodic field")
        self.periodic.setChecked(True)
        self.leaves_only = QCheckBox("leaves only (stalks let light through)")
        form.addRow(self.periodic)
        form.addRow(self.leaves_only)
        lay.addLayout(form)
        self.top = TopView()
        self.top.clicked.connect(self.add_place)
        lay.addWidget(self.top, 1)
        buttons = QHBoxLayout()
        self.places_label = QLabel("no place: click the field")
        self.clear_button = QPushButton("Clear")
        self.clear_button.clicked.connect(self.clear_places)
        self.read_button = QPushButton("Read")
        self.read_button.setToolTip("trace the instrument through the canopy on screen")
        self.read_button.clicked.connect(self.read)
        self.save_button = QPushButton("Save JSON…")
        self.save_button.setToolTip("the record maizeviz instrument ... --json prints")
        self.save_button.setEnabled(False)
        self.save_button.clicked.connect(self._ask_save)
        for w in (self.places_label, self.clear_button, self.read_button, self.save_button):
            buttons.addWidget(w)
        lay.addLayout(buttons)
        self.table = QTableWidget(0, 0)
        self.table.setAccessibleName("instrument readings")
        lay.addWidget(self.table, 1)
        self.figure = ImageView("read the instrument to see its figure")
        lay.addWidget(self.figure, 1)
        for box in (self.kind, self.orientation):
            box.currentIndexChanged.connect(lambda _i: self.refresh())
        self.refresh()

    @staticmethod
    def _spin(lo: float, hi: float, value: float, suffix: str, tip: str) -> QDoubleSpinBox:
        s = QDoubleSpinBox()
        s.setRange(lo, hi)
        s.setDecimals(2)
        s.setValue(value)
        s.setSuffix(suffix)
        s.setToolTip(tip)
        return s

    # ------------------------------------------------------------------ settings
    def settings(self) -> dict[str, Any]:
        return {"height": self.height_spin.value(), "orientation": self.orientation.currentText(),
                "zenith": self.zenith.value(), "azimuth": self.azimuth.value(),
                "par": 2000.0, "beam_fraction": self.beam.value(), "heading": 0.0,
                "view_cap": self.view_cap.currentText(), "rays": 1000,
                "size": self.size_spin.value(), "periodic": self.periodic.isChecked(),
                "leaves_only": self.leaves_only.isChecked()}

    @property
    def kind_key(self) -> str:
        return str(self.kind.currentData())

    def refresh(self) -> None:
        """The top view again (a new canopy, places or instrument)."""
        kind = self.kind_key
        az = 90.0 if self.orientation.currentText() == "across" else 0.0
        self.top.show_field(self._canopy(), self.places, kind, az)
        n = len(self.places)
        self.places_label.setText(f"{n} place{'s' if n != 1 else ''}" if n else
                                  "no place: click the field")

    def add_place(self, x: float, y: float) -> None:
        self.places.append((x, y))
        self.refresh()

    def clear_places(self) -> None:
        self.places.clear()
        self.refresh()

    # ------------------------------------------------------------------ reading
    def read(self) -> None:
        canopy = self._canopy()
        if canopy is None:
            self.failed.emit("open a canopy first")
            return
        if not self.places:
            from maizeviz.instruments.sight import default_place

            self.places.append(default_place(canopy))
            self.refresh()
        self.read_button.setEnabled(False)
        self.runner.run("instrument", f"reading the {self.kind_key}",
                        lambda _job, *a: read_instrument(*a), canopy, self.kind_key,
                        list(self.places), self.settings(), on_done=self._show,
                        on_error=self._fail)

    def _show(self, got: dict) -> None:
        self.read_button.setEnabled(True)
        self.record = got["record"]
        header, rows = got["header"], got["rows"]
        self.table.setColumnCount(len(header))
        self.table.setHorizontalHeaderLabels(header)
        self.table.setRowCount(len(rows))
        for i, row in enumerate(rows):
            for j, v in enumerate(row):
                self.table.setItem(i, j, QTableWidgetItem(str(v)))
        self.table.resizeColumnsToContents()
        self.figure.set_rgba(got["rgba"])
        self.save_button.setEnabled(True)
        self.read_done.emit(self.record)

    def _fail(self, exc: BaseException) -> None:
        self.read_button.setEnabled(True)
        self.failed.emit(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)

    # ------------------------------------------------------------------ saving
    def save_json(self, path: str | Path) -> Path:
        """Write the last reading's record (as ``maizeviz instrument ... --json``)."""
        from maizeviz.io.atomic import write_text

        if self.record is None:
            raise ValueError("nothing read yet")
        write_text(path, json.dumps(self.record, indent=1) + "\n")
        return Path(path)

    def _ask_save(self) -> None:
        from PySide6.QtWidgets import QFileDialog

        path, _ = QFileDialog.getSaveFileName(self, "Save the readings", "instrument.json",
                                              "JSON (*.json)")
        if path:
            try:
                self.save_json(path)
            except OSError as exc:
                self.failed.emit(f"{path}: {exc.strerror or exc}")

    def shutdown(self) -> None:
        """Stop the reading under way and wait for the panel's thread (the window closes)."""
        self.runner.shutdown(10.0)
