"""The maizeviz main window: a 3D canopy, a mesh-complexity slider, Table 2 and direct light.

Every computation runs in a superqt worker thread; results come back as signals and stale
ones (the slider has moved on) are dropped by job id. Errors go to the Messages panel, never to
a modal box that would stop a technician in the field.
"""

from __future__ import annotations

import io
import itertools
import traceback
from pathlib import Path

from maizeviz.resources import example_points
from maizeviz_app import workers
from maizeviz_app.viewport import Viewport
from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QPixmap
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDockWidget,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QMainWindow,
    QPlainTextEdit,
    QProgressBar,
    QPushButton,
    QSlider,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)
from superqt.utils import create_worker

from maizeviz.canopy.measures import TABLE2_COLUMNS, table2_row
from maizeviz.errors import MaizevizError
from maizeviz.light.request import LightRequest
from maizeviz.light.sun import Sun, sun_at
from maizeviz.mesh.levels import COMPLEXITY_STOPS as LEVELS
from maizeviz.mesh.levels import parse_level


def _label(level: str) -> str:
    return parse_level(level).description


class MainWindow(QMainWindow):
    """Open a points file, tile it, choose the mesh level, compute light."""

    canopy_shown = Signal(str)          # level label, after the viewport shows a new canopy
    light_shown = Signal()
    failed = Signal(str)

    def __init__(self, points: str | Path | None = None, tile: int = 3):
        super().__init__()
        self.setWindowTitle("maizeviz")
        self.resize(1400, 860)
        self._ids = itertools.count(1)
        self._progress = workers.Progress()
        self._progress.changed.connect(self._on_progress)
        self._workers: set = set()
        self._jobs: dict[str, workers.Job] = {}
        self.loaded: workers.Loaded | None = None
        self.canopy = None
        self.rows: dict[str, list] = {}

        self.viewport = Viewport(self)
        self.setCentralWidget(self.viewport.interactor)
        self._build_canopy_panel(tile)
        self._build_light_panel()
        self._build_messages()
        self._build_digitizer()
        self._build_layout_editor()
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(240)
        self.statusBar().addPermanentWidget(self.progress)
        self._debounce = QTimer(self, singleShot=True, interval=250)
        self._debounce.timeout.connect(self.rebuild)
        self.failed.connect(lambda _: self.light_button.setEnabled(True))
        self._settings = QSettings("maizeviz", "maizeviz")
        self.load(points or self._settings.value("last_points", str(example_points())))

    # ------------------------------------------------------------------------ panels
    def _build_canopy_panel(self, tile: int) -> None:
        box = QWidget()
        lay = QVBoxLayout(box)
        row = QHBoxLayout()
        self.file_label = QLabel("no file")
        self.file_label.setWordWrap(True)
        open_button = QPushButton("Open points…")
        open_button.clicked.connect(self._choose_file)
        row.addWidget(self.file_label, 1)
        row.addWidget(open_button)
        lay.addLayout(row)
        form = QFormLayout()
        self.tile = QComboBox()
        self.tile.addItems(["1x1", "3x3", "5x5"])
        self.tile.setCurrentText(f"{tile}x{tile}")
        self.tile.currentTextChanged.connect(lambda _: self.reload())
        form.addRow("tiling of the digitized block", self.tile)
        self.preserve = QCheckBox("keep leaf area below the standard mesh (widen cross-sections)")
        self.preserve.setChecked(True)
        self.preserve.toggled.connect(lambda _: self._debounce.start())
        form.addRow(self.preserve)
        lay.addLayout(form)
        group = QGroupBox("mesh complexity")
        g = QVBoxLayout(group)
        self.slider = QSlider(Qt.Horizontal)
        self.slider.setRange(0, len(LEVELS) - 1)
        self.slider.setValue(LEVELS.index("36"))
        self.slider.setTickPosition(QSlider.TicksBelow)
        self.slider.valueChanged.connect(self._on_slider)
        self.level_label = QLabel(_label(self.level))
        g.addWidget(self.slider)
        g.addWidget(QLabel("fine (K=4)  ←→  coarse (4 triangles)"))
        g.addWidget(self.level_label)
        lay.addWidget(group)
        self.table = QTableWidget(0, len(TABLE2_COLUMNS))
        self.table.setHorizontalHeaderLabels([h for _, h in TABLE2_COLUMNS])
        self.table.verticalHeader().setVisible(False)
        lay.addWidget(QLabel("canopy measures per level (the paper's Table 2)"))
        lay.addWidget(self.table, 1)
        dock = QDockWidget("Canopy", self)
        dock.setObjectName("canopy")
        dock.setWidget(box)
        self.addDockWidget(Qt.RightDockWidgetArea, dock)

    def _build_light_panel(self) -> None:
        box = QWidget()
        lay = QVBoxLayout(box)
        form = QFormLayout()
        self.zenith = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=89.9, value=22.34,
                                     suffix=" °")
        self.azimuth = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=360.0, value=166.95,
                                      suffix=" ° from N")
        form.addRow("sun zenith", self.zenith)
        form.addRow("sun azimuth", self.azimuth)
        self.place = QLineEdit("2005-08-01 12:00 39.9 116.4 Asia/Shanghai")
        place_row = QHBoxLayout()
        place_row.addWidget(self.place, 1)
        use_place = QPushButton("Sun from place")
        use_place.clicked.connect(self._sun_from_place)
        place_row.addWidget(use_place)
        form.addRow("date time lat lon tz", place_row)
        self.heights = QLineEdit("0,50,100,150,200,225")
        form.addRow("heights (cm)", self.heights)
        self.density = QDoubleSpinBox(decimals=2, minimum=0.01, maximum=100.0, value=2.0,
                                      suffix=" rays/cm²")
        form.addRow("ray density", self.density)
        self.periodic = QCheckBox("infinite field (rays wrap at the plot edges)")
        self.periodic.setChecked(True)
        form.addRow(self.periodic)
        lay.addLayout(form)
        self.light_button = QPushButton("Compute direct light")
        self.light_button.clicked.connect(self.compute_light)
        lay.addWidget(self.light_button)
        self.light_table = QTableWidget(0, 2)
        self.light_table.setHorizontalHeaderLabels(["height cm", "transmission"])
        self.light_table.verticalHeader().setVisible(False)
        lay.addWidget(self.light_table)
        self.light_info = QLabel("")
        self.light_info.setWordWrap(True)
        lay.addWidget(self.light_info)
        self.heatmap = QLabel()
        self.heatmap.setMinimumHeight(220)
        self.heatmap.setAlignment(Qt.AlignCenter)
        lay.addWidget(self.heatmap, 1)
        dock = QDockWidget("Direct light", self)
        dock.setObjectName("light")
        dock.setWidget(box)
        self.addDockWidget(Qt.RightDockWidgetArea, dock)

    def _build_digitizer(self) -> None:
        from maizeviz_app.panels.digitizer import DigitizerPanel

        self.digitizer = DigitizerPanel(self.viewport)
        self.digitizer.alert.connect(lambda text: self.statusBar().showMessage(text, 15_000))
        self.digitizer.stopped.connect(self._digitizing_stopped)
        dock = QDockWidget("Digitizer", self)
        dock.setObjectName("digitizer")
        dock.setWidget(self.digitizer)
        self.addDockWidget(Qt.LeftDockWidgetArea, dock)

    def _digitizing_stopped(self, _why: str) -> None:
        if self.canopy is not None:                 # the canopy comes back after a session
            self.viewport.show_canopy(self.canopy)

    def _build_layout_editor(self) -> None:
        from maizeviz_app.panels.layout import LayoutPanel

        self.layout_panel = LayoutPanel()
        self.layout_panel.applied.connect(self._on_layout)
        self.layout_panel.problem.connect(self.say)
        dock = QDockWidget("Canopy layout", self)
        dock.setObjectName("layout")
        dock.setWidget(self.layout_panel)
        self.addDockWidget(Qt.LeftDockWidgetArea, dock)
        digitizer = self.findChild(QDockWidget, "digitizer")
        self.tabifyDockWidget(digitizer, dock)
        digitizer.raise_()

    def _on_layout(self, layout) -> None:
        from dataclasses import replace

        if self.loaded is None:
            return
        self.loaded = replace(self.loaded, layout=layout)
        self.rows.clear()
        self.say(f"layout applied: {len(layout.placements)} plants")
        self.rebuild()

    def _build_messages(self) -> None:
        self.messages = QPlainTextEdit(readOnly=True)
        self.messages.setMaximumBlockCount(500)
        dock = QDockWidget("Messages", self)
        dock.setObjectName("messages")
        dock.setWidget(self.messages)
        self.addDockWidget(Qt.BottomDockWidgetArea, dock)

    def say(self, text: str) -> None:
        self.messages.appendPlainText(text)
        self.statusBar().showMessage(text.splitlines()[0], 8000)

    # ------------------------------------------------------------------------ work
    @property
    def level(self) -> str:
        return LEVELS[self.slider.value()]

    def _run(self, kind: str, func, *args, on_done):
        """Run ``func(job, *args)`` in a worker; a newer job of the same kind cancels it."""
        old = self._jobs.get(kind)
        if old is not None:
            old.cancel.set()
        job = workers.Job(next(self._ids), self._progress)
        self._jobs[kind] = job

        def guarded(*a):
            try:
                return func(*a)
            except InterruptedError:                 # superseded or closing: not an error
                return None

        worker = create_worker(guarded, job, *args, _start_thread=False, _ignore_errors=True)

        def done(result):
            if result is not None and self._jobs.get(kind) is job:
                on_done(result)

        def error(exc):
            if self._jobs.get(kind) is job:
                text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
                self.say(f"error: {text}")
                self.failed.emit(text)

        worker.returned.connect(done)
        worker.errored.connect(error)
        worker.finished.connect(lambda: self._workers.discard(worker))
        self._workers.add(worker)
        worker.start()
        return job

    def _on_progress(self, job_id: int, done: int, total: int) -> None:
        if any(j.id == job_id for j in self._jobs.values()):
            self.progress.setMaximum(max(total, 1))
            self.progress.setValue(done)

    def load(self, path) -> None:
        path = str(path)
        self.file_label.setText(Path(path).name)
        self.say(f"reading {path}")
        n = int(self.tile.currentText().split("x")[0])
        self._run("load", lambda job, p, t: workers.load_points(p, t), path, (n, n),
                  on_done=self._on_loaded)

    def reload(self) -> None:
        if self.loaded is not None:
            self.load(self.loaded.path)

    def _choose_file(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open digitized points", "",
                                              "Points CSV (*.csv);;All files (*)")
        if path:
            self.load(path)

    def _on_loaded(self, loaded: workers.Loaded) -> None:
        self.loaded = loaded
        self.rows.clear()
        self._settings.setValue("last_points", loaded.path)
        for w in loaded.warnings:
            self.say(f"note: {w}")
        for e in loaded.skipped:
            self.say(f"skipped: {e}")
        plants = {lf.grid.plant for lf in loaded.leaves}
        self.say(f"{len(loaded.leaves)} leaves of {len(plants)} plants; "
                 f"{len(loaded.layout.placements)} plants in the canopy")
        self.layout_panel.show_layout(loaded.layout, plants)
        self.rebuild()

    def _on_slider(self, _value: int) -> None:
        self.level_label.setText(_label(self.level))
        self._debounce.start()

    def rebuild(self) -> None:
        if self.loaded is None:
            return
        self._run("build", workers.build, self.loaded, self.level, self.preserve.isChecked(),
                  on_done=self._on_built)

    def _on_built(self, built: workers.Built) -> None:
        self.canopy = built.canopy
        self.viewport.show_canopy(built.canopy)
        m = built.measures
        label = parse_level(self.level).variant_label(self.preserve.isChecked())
        row = table2_row(m, built.build_s, label)
        self.rows[label] = [row[k] for k, _ in TABLE2_COLUMNS]
        self.table.setRowCount(len(self.rows))
        for r, values in enumerate(self.rows.values()):
            for c, v in enumerate(values):
                item = QTableWidgetItem(v)
                item.setTextAlignment(Qt.AlignRight | Qt.AlignVCenter)
                self.table.setItem(r, c, item)
        self.table.resizeColumnsToContents()
        self.statusBar().showMessage(f"{built.level}: {m.triangles:,} triangles, leaf area "
                                     f"{m.leaf_area_m2:.2f} m², LAI {m.lai:.2f}, built in "
                                     f"{built.build_s:.2f} s")
        self.canopy_shown.emit(built.level)

    def _sun_from_place(self) -> None:
        try:
            date, clock, lat, lon, tz = self.place.text().split()
            sun = sun_at(date, clock, float(lat), float(lon), tz)
        except ValueError:
            self.say("error: write the place as: YYYY-MM-DD HH:MM lat lon timezone")
            return
        except Exception as exc:  # noqa: BLE001 - a slot must not let an exception escape
            self.say(f"error: {exc}")
            return
        self.zenith.setValue(sun.zenith_deg)
        self.azimuth.setValue(sun.azimuth_deg)
        self.say(f"sun at {sun.when}: zenith {sun.zenith_deg:.2f}°, azimuth "
                 f"{sun.azimuth_deg:.2f}°")

    def compute_light(self) -> None:
        if self.canopy is None:
            self.say("no canopy yet")
            return
        try:
            heights = tuple(float(h) for h in self.heights.text().split(",") if h.strip())
            req = LightRequest(Sun(self.zenith.value(), self.azimuth.value()), heights,
                               self.density.value(), None, self.periodic.isChecked(), 2,
                               classes=False)
        except (MaizevizError, ValueError) as exc:  # bad input is said, not raised
            self.say(f"error: {exc}")
            return
        self.light_button.setEnabled(False)
        self._run("light", workers.light, self.canopy, req, on_done=self._on_lit)

    def _on_lit(self, lit: workers.Lit) -> None:
        from maizeviz.light.heatmap import heatmap_figure, transmission_map

        self.light_button.setEnabled(True)
        r = lit.result
        self.light_table.setRowCount(len(r.heights_cm))
        for i, (h, t) in enumerate(zip(r.heights_cm, r.transmission)):
            self.light_table.setItem(i, 0, QTableWidgetItem(f"{h:g}"))
            self.light_table.setItem(i, 1, QTableWidgetItem(f"{t:.3f}"))
        self.light_info.setText(
            f"{r.rays:,} rays on the central tile, level {r.level}; Embree scene "
            f"{r.seconds['build']:.2f} s, tracing {r.seconds['trace']:.3f} s"
            + ("".join(f"\n⚠ {w}" for w in r.warnings)))
        for w in r.warnings:
            self.say(f"warning: {w}")
        tmap = transmission_map(r, float(r.heights_cm[0]), 5.0)
        self.heatmap.setPixmap(_heatmap_pixmap(heatmap_figure(tmap, r, width_in=4.6, dpi=90)))
        self.light_shown.emit()

    # ------------------------------------------------------------------------ close
    def closeEvent(self, event) -> None:
        self.digitizer.stop("window closed")
        for job in self._jobs.values():
            job.cancel.set()
        for worker in list(self._workers):
            try:
                worker.quit()
            except RuntimeError:
                pass
        from superqt.utils._qthreading import WorkerBase
        WorkerBase.await_workers(10_000)
        self._settings.setValue("geometry", self.saveGeometry())
        self.viewport.close()
        super().closeEvent(event)


def _heatmap_pixmap(fig) -> QPixmap:
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    pix = QPixmap()
    pix.loadFromData(buf.getvalue(), "PNG")
    return pix
