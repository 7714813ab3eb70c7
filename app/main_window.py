"""The maizeviz main window: the canopy in 3D, the mesh-complexity slider with Table 2, direct
light with its table and figures, the layout editor and the digitizer.

How it stays responsive:

- The window shows before anything heavy is imported: pyvista, VTK, matplotlib and most of the
  core are imported by a warm-up thread once the window is on screen; then the 3D view is made
  and the points file opened.
- Every computation runs on a worker thread (:mod:`maizeviz_app.workers`); the Embree work
  (ground cover, light), which holds the GIL inside embreex, runs in child processes
  (:mod:`maizeviz_app.process`). The GUI thread only swaps in results: a new canopy's mesh is
  prepared by the worker, the figures are drawn by the worker.
- The 3D view renders once per change and never when idle (:mod:`maizeviz_app.viewport`).
- The level label, Table 2 and the view change together when a built canopy arrives.

Errors go to the status bar and the Messages panel as one line for people
(:mod:`maizeviz_app.messages`), never as a modal box that would stop a technician in the field;
an error about one light setting also marks that field.
"""

from __future__ import annotations

import csv
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtWidgets import (QApplication, QDockWidget, QFileDialog, QHBoxLayout, QLabel,
                               QMainWindow, QMessageBox, QPlainTextEdit,
                               QPushButton, QScrollArea, QStackedWidget, QWidget)

from maizeviz import __version__
from maizeviz.errors import MaizevizError
from maizeviz.mesh.levels import COMPLEXITY_STOPS as LEVELS  # noqa: F401 - the slider's stops
from maizeviz.resources import example_points
from maizeviz_app.messages import user_message
from maizeviz_app.panels.canopy import CanopyPanel
from maizeviz_app.panels.light import InputProblem, LightPanel, LightPlots, LightRuns, Run
from maizeviz_app.workers import JobRunner, describe_internal

#: Version of the saved dock layout; bump when docks change so an old layout is not applied.
STATE_VERSION = 3
PROJECT_FILTER = "maizeviz project (*.maizeviz)"
POINTS_FILTER = "Points CSV (*.csv);;All files (*)"
MESH_FILTER = ("PLY (*.ply);;VTK legacy (*.vtk);;VTK XML unstructured (*.vtu);;"
               "VTK XML polydata (*.vtp);;Wavefront OBJ (*.obj);;STL (*.stl)")
PAPER = ("Xinyu Guo, Chunjiang Zhao, Boxiang Xiao, Shenglian Lu, Changfeng Li. <i>Study on "
         "maize leaf morphological modeling and mesh simplification of surface.</i> National "
         "Research Center for Information Technology in Agriculture, Beijing; Dalian "
         "University of Technology. (Chinese version: Xiao B., Guo X., Wang J., Zheng W., "
         "Wang D. <i>Scientia Agricultura Sinica</i> 40(4): 693-697, 2007.)")
#: Modules the warm-up thread imports while the window is already on screen, in three stages:
#: the core (then the points file opens), the 3D view (then the view is made), the rest.
WARM_STAGES = (
    ("core", ("maizeviz_app.jobs", "maizeviz.light.leaf_light")),
    ("view", ("pyvista", "pyvistaqt", "maizeviz_app.viewport", "maizeviz_app.panels.layout",
              "maizeviz_app.panels.digitizer")),
    ("rest", ("matplotlib.figure", "matplotlib.backends.backend_agg", "maizeviz_app.plots",
              "maizeviz.light.heatmap", "maizeviz.canopy.export", "maizeviz_app.project")))


def _scrolled(widget: QWidget) -> QScrollArea:
    area = QScrollArea()
    area.setWidget(widget)
    area.setWidgetResizable(True)
    area.setFrameShape(QScrollArea.NoFrame)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarAsNeeded)
    return area


class MainWindow(QMainWindow):
    """Open a points file or a project, choose the mesh level, compute light, export.

    ``points``: a points CSV or a ``.maizeviz`` project to open; None reopens the last one
    (or the bundled example the first time).
    """

    canopy_shown = Signal(str)          # level label, when a new canopy is on screen
    light_shown = Signal()              # a light result is in the table, figures and view
    failed = Signal(str)                # an error the user was told about
    ready = Signal()                    # the 3D view and every panel exist
    saved = Signal(str)                 # a project or export written (its path)
    _warmed = Signal(str, object)       # from the warm-up thread: stage, None or the error

    def __init__(self, points: str | Path | None = None, tile: int = 3):
        super().__init__()
        self.setWindowTitle("maizeviz")
        self._closing = False
        self._settings = QSettings("maizeviz", "maizeviz")
        self.runner = JobRunner(self)
        self.runner.progressed.connect(self._on_progress)
        self.runner.changed.connect(self._on_jobs_changed)
        self.viewport = None
        self.loaded = None
        self.canopy = None
        self.built = None
        self.measures_rows: dict[str, dict] = {}
        self.runs = LightRuns()
        self.project_path: str | None = None
        self._serial = 0                  # changes whenever the points or layout change
        self._pending_runs: list = []     # light results of a project, waiting for a canopy
        self._progress_shown = 0.0
        self._canopy_id = 0               # identifies the canopy shown (the light process
                                          # keeps the last one and its Embree scene)
        self._points_bytes = b""
        self._points_origin = ""          # where the points came from (a project's original)
        self._layout_edited = False       # the layout is not the tiling of the settings
        self._project_layout = False
        self._heatmaps_for: object = None

        placeholder = QLabel("starting the 3D view…", alignment=Qt.AlignCenter)
        self._centre = QStackedWidget()
        self._centre.setMinimumSize(320, 200)
        self._centre.addWidget(placeholder)
        self.setCentralWidget(self._centre)
        self.docks: dict[str, QDockWidget] = {}
        self._build_panels(tile)
        self._build_status()
        from maizeviz_app.menus import build_menus

        self.actions = build_menus(self)
        self._default_state = None             # taken at the first show, docks sized
        self._state_restored = self._restore_window()
        self._to_open = str(points) if points is not None else self._last_opened()
        self._view_ready = threading.Event()  # the build job waits for it before meshing
        self._warmed.connect(self._on_warmed)
        QTimer.singleShot(0, self._warm_up)

    # ------------------------------------------------------------------ building
    def _dock(self, name: str, title: str, widget: QWidget, area, scroll: bool = True):
        dock = QDockWidget(title, self)
        dock.setObjectName(name)
        dock.setWidget(_scrolled(widget) if scroll else widget)
        dock.setFeatures(QDockWidget.DockWidgetMovable | QDockWidget.DockWidgetFloatable |
                         QDockWidget.DockWidgetClosable)
        self.addDockWidget(area, dock)
        self.docks[name] = dock
        return dock

    def _build_panels(self, tile: int) -> None:
        self.setCorner(Qt.BottomRightCorner, Qt.RightDockWidgetArea)
        self.setCorner(Qt.TopRightCorner, Qt.RightDockWidgetArea)
        self.setDockOptions(QMainWindow.AnimatedDocks | QMainWindow.AllowTabbedDocks)
        self.canopy_panel = CanopyPanel(tile)
        self.canopy_panel.open_requested.connect(self.choose_points)
        self.canopy_panel.tile_changed.connect(lambda _n: self.reload())
        self.canopy_panel.level_requested.connect(lambda _lv: self.rebuild())
        self.canopy_panel.preserve_changed.connect(lambda _b: self.rebuild())
        self.light_panel = LightPanel()
        self.light_panel.compute_requested.connect(self.compute_light)
        self.light_panel.cancel_requested.connect(lambda: self.cancel_jobs("light"))
        self.light_panel.place_requested.connect(lambda _t: self.sun_from_place())
        self.light_panel.export_requested.connect(self.choose_export)
        # the layout editor and the digitizer import much of the core: they are made once the
        # window is on screen (see _make_late_panels)
        self.layout_panel = None
        self.digitizer = None
        self.plots = LightPlots()
        self.plots.heatmap_needed.connect(self._draw_heatmap)
        self.messages = QPlainTextEdit(readOnly=True)
        self.messages.setMaximumBlockCount(1000)

        right = Qt.RightDockWidgetArea
        canopy = self._dock("canopy", "Canopy", self.canopy_panel, right)
        light = self._dock("light", "Light", self.light_panel, right)
        layout = self._dock("layout", "Layout", QLabel("starting…"), right)
        digitizer = self._dock("digitizer", "Digitizer", QLabel("starting…"), right)
        for d in (light, layout, digitizer):
            self.tabifyDockWidget(canopy, d)
        canopy.raise_()
        results = self._dock("results", "Light results", self.plots, Qt.BottomDockWidgetArea,
                             scroll=False)
        messages = self._dock("messages", "Messages", self.messages, Qt.BottomDockWidgetArea,
                              scroll=False)
        self.tabifyDockWidget(results, messages)
        results.raise_()

    def _build_status(self) -> None:
        """What is running, how far, and Cancel: always in place (showing or hiding widgets
        relayouts the window), updated as text (a QProgressBar repaints synchronously, and
        every repaint recomposes the whole window with the 3D view: 50-100 ms on software
        OpenGL)."""
        box = QWidget()
        lay = QHBoxLayout(box)
        lay.setContentsMargins(0, 0, 0, 0)
        self.job_label = QLabel("")
        self.job_label.setFixedWidth(300)
        self.job_label.setAlignment(Qt.AlignRight | Qt.AlignVCenter)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("stop the work under way (Esc)")
        self.cancel_button.clicked.connect(lambda: self.cancel_jobs())
        self.cancel_button.setEnabled(False)
        lay.addWidget(self.job_label)
        lay.addWidget(self.cancel_button)
        self.statusBar().addPermanentWidget(box)

    def _restore_window(self) -> None:
        geometry = self._settings.value("geometry")
        restored = bool(geometry) and self.restoreGeometry(geometry)
        if not restored:
            screen = QApplication.primaryScreen()
            avail = screen.availableGeometry() if screen is not None else None
            if avail is not None:
                w = min(1600, int(avail.width() * 0.94))
                h = min(1000, int(avail.height() * 0.92))
                self.resize(w, h)
                self.move(avail.x() + (avail.width() - w) // 2,
                          avail.y() + (avail.height() - h) // 2)
            else:
                self.resize(1280, 720)
        state = self._settings.value("window_state")
        return bool(state) and self.restoreState(state, STATE_VERSION)

    def showEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        if self._default_state is None:
            QTimer.singleShot(50, self._size_docks)

    def _size_docks(self) -> None:
        """First show: the panels a third of the width, the figures a third of the height;
        that is also what View > Reset window layout goes back to."""
        if self._closing or self._default_state is not None:
            return
        if not self._state_restored:
            self._apply_default_sizes()
        restored = self.saveState(STATE_VERSION)
        self._apply_default_sizes()
        self._default_state = self.saveState(STATE_VERSION)
        if self._state_restored:
            self.restoreState(restored, STATE_VERSION)

    def _apply_default_sizes(self) -> None:
        w, h = self.width(), self.height()
        self.resizeDocks([self.docks["canopy"]], [max(380, min(480, int(w * 0.33)))],
                         Qt.Horizontal)
        self.resizeDocks([self.docks["results"]], [max(200, min(380, int(h * 0.36)))],
                         Qt.Vertical)

    def reset_layout(self) -> None:
        """Docks back to where they are on a first start."""
        if self._default_state is None:
            return
        self.restoreState(self._default_state, STATE_VERSION)
        for dock in self.docks.values():
            dock.setFloating(False)
            dock.show()
        self.docks["canopy"].raise_()
        self.docks["results"].raise_()

    # ------------------------------------------------------------------ start-up
    def _warm_up(self) -> None:
        """Import the heavy modules off the GUI thread, stage by stage (see WARM_STAGES)."""
        if self._closing:
            return
        self.say("starting: loading the core and the 3D view…", status_only=True)
        warmed, view_ready = self._warmed, self._view_ready

        def work():
            import importlib

            for stage, names in WARM_STAGES:
                error = None
                try:
                    for name in names:
                        importlib.import_module(name)
                except Exception as exc:  # noqa: BLE001 - reported in the window
                    error = exc
                try:
                    warmed.emit(stage, error)
                except RuntimeError:            # the window is gone
                    return
                if stage == "view":
                    view_ready.set()
                if error is not None:
                    return

        threading.Thread(target=work, name="maizeviz-warm-up", daemon=True).start()

    def _on_warmed(self, stage: str, error) -> None:
        if self._closing:
            return
        if error is not None:
            describe_internal(error)
            self.say(f"error: the app cannot start ({error}); reinstall maizeviz with its gui "
                     "extra: pip install \"maizeviz[gui]\"", error=True)
            return
        if stage == "core":
            threading.Thread(target=self._start_processes, name="maizeviz-processes",
                             daemon=True).start()
            if self._to_open:
                self.open_any(self._to_open)
        elif stage == "view":
            from maizeviz_app.viewport import Viewport

            self.viewport = Viewport(self)
            # the central widget stays (a new one would make the docks take its room)
            self._centre.addWidget(self.viewport)
            self._centre.setCurrentWidget(self.viewport)
            self._make_late_panels()
            self.ready.emit()
        else:
            import gc

            gc.freeze()       # start-up objects out of the collector's way: shorter pauses

    def _make_late_panels(self) -> None:
        from maizeviz_app.panels.digitizer import DigitizerPanel
        from maizeviz_app.panels.layout import LayoutPanel

        self.layout_panel = LayoutPanel()
        self.layout_panel.applied.connect(self._on_layout)
        self.layout_panel.problem.connect(self.say)
        self.digitizer = DigitizerPanel(None)
        self.digitizer.alert.connect(lambda text: self.say(text, error=True, status_only=True))
        self.digitizer.stopped.connect(self._digitizing_stopped)
        self.docks["layout"].setWidget(_scrolled(self.layout_panel))
        self.docks["digitizer"].setWidget(_scrolled(self.digitizer))
        self.digitizer.viewport = self.viewport
        if self.loaded is not None:
            self.layout_panel.show_layout(self.loaded.layout, self.loaded.plants)

    def _start_processes(self) -> None:
        for proc in (self.runner.cover_process, self.runner.light_process):
            try:
                proc.start()
            except (InterruptedError, OSError, RuntimeError):
                return

    def _last_opened(self) -> str:
        for key in ("last_opened",):
            path = self._settings.value(key)
            if path and Path(str(path)).is_file():
                return str(path)
        return str(example_points())

    # ------------------------------------------------------------------ messages
    def say(self, text: str, error: bool | None = None, status_only: bool = False) -> None:
        """A line for the user: in the status bar, and in Messages unless ``status_only``."""
        if self._closing:
            return
        error = text.startswith("error") if error is None else error
        if not status_only:
            self.messages.appendPlainText(text)
        bar = self.statusBar()
        bar.setStyleSheet("QStatusBar { color: #b3261e; font-weight: bold; }" if error else "")
        bar.showMessage(text.splitlines()[0], 15000 if error else 8000)

    def _fail(self, exc: BaseException, doing: str) -> None:
        """An error from a job: one line for people; the traceback on stderr if it is a bug."""
        if self._closing:
            return
        if not isinstance(exc, (MaizevizError, OSError, MemoryError)):
            describe_internal(exc)
        text = user_message(exc, doing)
        self.say(f"error: {text}", error=True)
        quantity = getattr(exc, "quantity", None)
        if quantity:
            if self.light_panel.point_at(quantity, text):
                self.docks["light"].raise_()
        self.failed.emit(text)

    # ------------------------------------------------------------------ opening
    def open_any(self, path: str | Path) -> None:
        """A project (``.maizeviz``) or a points CSV."""
        if str(path).endswith(".maizeviz"):
            self.open_project(path)
        else:
            self.open_points(path)

    def choose_points(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open digitized points", self._folder(),
                                              POINTS_FILTER)
        if path:
            self.open_points(path)

    def choose_project(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open project", self._folder(),
                                              PROJECT_FILTER)
        if path:
            self.open_project(path)

    def _folder(self) -> str:
        return str(self._settings.value("last_folder", str(Path.home())))

    def open_points(self, path: str | Path, layout=None) -> None:
        """Read a points file in a worker; the current canopy stays until it has loaded."""
        from maizeviz_app import jobs

        path = str(path)
        n = self.canopy_panel.tile_n
        self.say(f"reading {path}")

        def load(job, p):
            loaded = jobs.load_points(p, (n, n), layout=layout)
            return loaded, Path(p).read_bytes()

        self.runner.run("load", f"reading {Path(path).name}", load, path,
                        on_done=lambda r: self._on_loaded(r[0], r[1], None, r[0].path),
                        on_error=lambda e: self._fail(e, "open points"))

    def reload(self) -> None:
        """The same points with the tiling now chosen (edits of the layout are replaced)."""
        if self.loaded is not None:
            if self.project_path is not None:
                self.project_path = None
            self.open_points(self.loaded.path)

    def _on_loaded(self, loaded, points_bytes: bytes, project: str | None,
                   origin: str) -> None:
        self.loaded = loaded
        self._points_bytes = points_bytes
        self._points_origin = str(Path(origin).resolve())
        self._serial += 1
        self.runs.clear()
        self.measures_rows.clear()
        self.canopy_panel.clear_rows()
        self.light_panel.show_runs(self.runs)
        self.plots.set_heatmaps([])
        self.plots.set_transmission(None)
        self.canopy_panel.set_file(Path(loaded.shown_name).name if project is None
                                   else loaded.shown_name, loaded.path)
        self.project_path = project
        self._layout_edited = project is not None and self._project_layout
        opened = project or loaded.path
        if loaded.path != str(example_points()) or project:
            self._settings.setValue("last_opened", opened)
            self._remember(opened)
        self._settings.setValue("last_folder", str(Path(opened).parent))
        self.setWindowTitle(f"maizeviz — {Path(opened).name}")
        for w in loaded.warnings:
            self.say(f"note: {w}")
        for e in loaded.skipped:
            self.say(f"skipped: {e}")
        self.say(f"{len(loaded.leaves)} leaves of {len(loaded.plants)} plants; "
                 f"{len(loaded.layout.placements)} plants in the canopy")
        if self.layout_panel is not None:
            self.layout_panel.show_layout(loaded.layout, loaded.plants)
        self.rebuild()

    def _on_layout(self, layout) -> None:
        if self.loaded is None:
            return
        self.loaded = replace(self.loaded, layout=layout)
        self._layout_edited = True
        self._serial += 1
        if self.runs.runs:
            self.say("note: the layout changed; light results of the previous layout were "
                     "cleared")
        self.runs.clear()
        self.light_panel.show_runs(self.runs)
        self.measures_rows.clear()
        self.canopy_panel.clear_rows()
        self.say(f"layout applied: {len(layout.placements)} plants")
        self.rebuild()

    # ------------------------------------------------------------------ building
    @property
    def level(self) -> str:
        return self.canopy_panel.level

    # the panel's widgets, under the names tests and scripts know
    @property
    def slider(self):
        return self.canopy_panel.slider

    @property
    def table(self):
        return self.canopy_panel.table

    @property
    def level_label(self):
        return self.canopy_panel.level_label

    def signature(self, label: str) -> tuple:
        """What identifies a canopy: the points and layout (serial) and the level variant."""
        return (self._serial, label)

    def rebuild(self) -> None:
        """Rebuild the canopy at the slider's level (a running rebuild is superseded)."""
        if self.loaded is None or self._closing:
            return
        from maizeviz_app import jobs

        loaded, level = self.loaded, self.level
        preserve = self.canopy_panel.preserve.isChecked()
        serial = self._serial
        key = object()
        runner = self.runner
        view_ready = self._view_ready

        def work(job):
            from maizeviz.canopy.measures import TABLE2_COLUMNS, table2_row

            canopy, build_s, label = jobs.build(loaded, level, preserve, job.report)
            job.check()
            t0 = time.perf_counter()
            m = runner.cover_process.call("measure", key, canopy,
                                          (jobs.APP_COVER_RESOLUTION_CM,), job)
            measure_s = time.perf_counter() - t0
            while not view_ready.wait(0.05):        # pyvista still loading at start-up
                job.check()
            from maizeviz_app.viewport import canopy_polydata

            mesh = canopy_polydata(canopy)
            row = table2_row(m, build_s, label)
            return jobs.Built(level, label, canopy, m, build_s, measure_s,
                              (mesh, list(TABLE2_COLUMNS), row, serial))

        from maizeviz.mesh.levels import parse_level

        self.canopy_panel.set_pending(f"building: {parse_level(level).description}…")
        self.runner.run("build", f"building {parse_level(level).label}", work,
                        on_done=self._on_built, on_error=lambda e: self._fail(e, "build"))

    def _on_built(self, built) -> None:
        mesh, columns, row, serial = built.mesh
        if serial != self._serial or self.viewport is None:
            return
        self.canopy = built.canopy
        self.built = built
        self._canopy_id += 1
        self.viewport.show_canopy(built.canopy, mesh)
        self.canopy_panel.show_built(built.level, columns, row)
        self.measures_rows[built.label] = row
        self._adopt_pending_runs()
        run = self.runs.for_signature(self.signature(built.label))
        if run is not None and run.classes is not None:
            self.viewport.set_light(run.classes)
        self._sync_colour_actions()
        m = built.measures
        self.say(f"{built.label}: {m.triangles:,} triangles, leaf area {m.leaf_area_m2:.2f} m², "
                 f"LAI {m.lai:.2f}; built in {built.build_s:.2f} s, measured in "
                 f"{built.measure_s:.2f} s", status_only=True)
        self.canopy_shown.emit(built.label)

    def step_level(self, step: int) -> None:
        s = self.canopy_panel.slider
        s.setValue(max(s.minimum(), min(s.maximum(), s.value() + step)))

    # ------------------------------------------------------------------ light
    def compute_light(self) -> None:
        """Trace the sun through the canopy shown (hit classes on, to colour the leaves)."""
        if self._closing:
            return
        if self.canopy is None or self.built is None:
            self.say("error: no canopy yet: open a points file first", error=True)
            return
        self.light_panel.clear_problem()
        try:
            request = self.light_panel.request()
        except (InputProblem, MaizevizError) as exc:
            self._fail(exc, "light")
            return
        from maizeviz_app import plots

        canopy, built = self.canopy, self.built
        label = built.label
        signature = self.signature(label)
        settings_key = self.light_panel.settings_key(request)
        prior = self.runs.curves() if self.runs.settings == settings_key else []
        key = self._canopy_id
        runner = self.runner
        shown_height = max(self.plots.height.currentIndex(), 0)

        def work(job):
            from maizeviz.light.leaf_light import triangle_light
            from maizeviz_app.panels.light import level_order

            result = runner.light_process.call("light", key, canopy, (request,), job)
            job.check()
            classes = triangle_light(canopy, result)
            maps = plots.heatmap_images(result, first=shown_height, check=job.check)
            curves = [c for c in prior if c.label != label]
            curves.append(plots.Curve(label, tuple(map(float, result.heights_cm)),
                                      tuple(map(float, result.transmission))))
            curves.sort(key=lambda c: level_order(c.label))
            plot = plots.rgba(plots.transmission_figure(curves, _plot_title(result)))
            return Run(label, signature, result, classes), settings_key, maps, plot

        self.light_panel.set_running(True)
        self.docks["light"].raise_()
        self.runner.run("light", f"light on {label}", work, on_done=self._on_lit,
                        on_error=self._light_failed)

    def _light_failed(self, exc: BaseException) -> None:
        self.light_panel.set_running(False)
        self._fail(exc, "light")

    def _on_lit(self, out) -> None:
        run, settings_key, maps, plot = out
        self.light_panel.set_running(False)
        if run.signature[0] != self._serial:
            return
        if self.runs.add(run, settings_key):
            self.say("note: the light settings changed; the comparison starts again")
        r = run.result
        info = (f"{r.rays:,} rays on the central tile at {r.density_per_cm2:.2f} per cm²; "
                f"level {run.label}; Embree scene {r.seconds.get('build', 0):.2f} s, tracing "
                f"{r.seconds.get('trace', 0) + r.seconds.get('second', 0):.2f} s")
        share = r.sunlit_intercepted_fraction
        if share is not None:
            info += f"; leaves take {share:.1%} of the direct light"
        info += "".join(f"\n⚠ {w}" for w in r.warnings)
        self.light_panel.show_runs(self.runs, info)
        self._heatmaps_for = run
        self.plots.set_heatmaps(maps)
        self.plots.set_transmission(plot)
        for w in r.warnings:
            self.say(f"warning: {w}")
        if self.viewport is not None and self.built is not None and \
                self.signature(self.built.label) == run.signature:
            self.viewport.set_light(run.classes)
            self.colour_by("light")
        self.docks["results"].raise_()
        self.say(f"light on {run.label}: transmission "
                 + ", ".join(f"{t:.3f}" for t in r.transmission) + " at "
                 + ", ".join(f"{h:g}" for h in r.heights_cm) + " cm", status_only=True)
        self.light_shown.emit()

    def _draw_heatmap(self, index: int) -> None:
        """The heatmap of another height of the result shown, drawn in a worker."""
        run = self._heatmaps_for
        if run is None:
            return
        from maizeviz_app import plots

        result = run.result
        height = float(result.heights_cm[index])

        def done(rgba):
            if self._heatmaps_for is run:
                self.plots.set_heatmap(index, rgba)

        self.runner.run("heatmap", f"drawing the heatmap at {height:g} cm",
                        lambda job: plots.heatmap_image(result, height), on_done=done,
                        on_error=lambda e: self._fail(e, "light"))

    def sun_from_place(self) -> None:
        """Sun angles from the date, time and place typed (pvlib, in a worker)."""
        text = self.light_panel.place.text()

        def work(job, t):
            from maizeviz.light.sun import sun_at

            parts = t.split()
            if len(parts) != 5:
                raise MaizevizError("write the place as: YYYY-MM-DD HH:MM latitude longitude "
                                    "time zone", quantity="place")
            date, clock, lat, lon, tz = parts
            try:
                la, lo = float(lat), float(lon)
            except ValueError:
                raise MaizevizError(f"latitude and longitude must be numbers, got '{lat}' "
                                    f"'{lon}'", quantity="place") from None
            return sun_at(date, clock, la, lo, tz)

        self.runner.run("sun", "sun position", work, text, on_done=self._on_sun,
                        on_error=lambda e: self._fail(e, "sun"))

    def _on_sun(self, sun) -> None:
        self.light_panel.zenith.setValue(sun.zenith_deg)
        self.light_panel.azimuth.setValue(sun.azimuth_deg)
        self.say(f"sun at {sun.when}: zenith {sun.zenith_deg:.2f}°, azimuth "
                 f"{sun.azimuth_deg:.2f}°")

    # ------------------------------------------------------------------ view
    def camera(self, name: str) -> None:
        if self.viewport is not None:
            self.viewport.camera_preset(name)

    def colour_by(self, what: str) -> None:
        if self.viewport is None:
            return
        if not self.viewport.colour_by(what):
            self.say("no light result for the canopy shown: compute direct light first "
                     "(Ctrl+L)")
        self._sync_colour_actions()

    def _sync_colour_actions(self) -> None:
        if self.viewport is None:
            return
        for name in ("plant", "leaf", "light"):
            act = self.actions.get(f"colour_{name}")
            if act is not None:
                act.setChecked(self.viewport.colouring == name)

    def _digitizing_stopped(self, _why: str) -> None:
        if self.viewport is not None and self.canopy is not None:
            self.viewport.restore_canopy()          # the canopy comes back after a session

    # ------------------------------------------------------------------ jobs
    def cancel_jobs(self, kind: str | None = None) -> None:
        """Stop the light computation and rebuilds under way (Esc)."""
        running = [j for j in self.runner.running() if kind is None or j.kind == kind]
        if not running:
            return
        self.runner.cancel(kind)
        if kind in (None, "light"):
            self.light_panel.set_running(False)
        if kind in (None, "build"):
            self.canopy_panel.set_pending("")
        self.say("cancelled: " + ", ".join(j.label for j in running))

    def _on_progress(self, _job_id: int, _kind: str, label: str, done: int, total: int) -> None:
        # each repaint recomposes the window (see _build_status): twice a second at most
        now = time.perf_counter()
        if now - self._progress_shown < 0.5:
            return
        self._progress_shown = now
        self.job_label.setText(f"{label}… {100 * done // max(total, 1)}%")

    def _on_jobs_changed(self) -> None:
        if self._closing:
            return
        running = [j for j in self.runner.running() if j.kind in ("load", "build", "light",
                                                                   "open", "save", "export")]
        text = ", ".join(j.label for j in running) + ("…" if running else "")
        if self.job_label.text() != text:
            self.job_label.setText(text)
        if self.cancel_button.isEnabled() != bool(running):
            self.cancel_button.setEnabled(bool(running))
        if not any(j.kind == "light" for j in running):
            self.light_panel.set_running(False)

    # ------------------------------------------------------------------ projects
    def choose_project_target(self) -> None:
        start = self.project_path or str(Path(self._folder()) / "study.maizeviz")
        path, _ = QFileDialog.getSaveFileName(self, "Save project", start, PROJECT_FILTER)
        if path:
            if not path.endswith(".maizeviz"):
                path += ".maizeviz"
            self.save_project(path)

    def save_project_here(self) -> None:
        if self.project_path:
            self.save_project(self.project_path)
        else:
            self.choose_project_target()

    def save_project(self, path: str | Path) -> None:
        """Write the project (points, layout, settings, light results) in a worker."""
        if self.loaded is None:
            self.say("error: nothing to save yet: open a points file first", error=True)
            return
        from maizeviz_app import project

        loaded, data, origin = self.loaded, self._points_bytes, self._points_origin
        layout = loaded.layout if self._layout_edited else None   # else: the tiling, exactly
        canopy = {"tile": self.canopy_panel.tile_n, "level": self.level,
                  "preserve_area": self.canopy_panel.preserve.isChecked()}
        light = self.light_panel.settings()
        runs = [(r.label, r.result) for r in self.runs.runs.values()]
        path = str(path)

        def work(job):
            from maizeviz.io.project import save_project

            proj = project.make_project(origin, data, layout, canopy, light, runs)
            save_project(path, proj)
            return path

        self.runner.run("save", f"saving {Path(path).name}", work, on_done=self._on_saved,
                        on_error=lambda e: self._fail(e, "save project"), supersede=False)

    def _on_saved(self, path: str) -> None:
        self.project_path = path
        self._settings.setValue("last_opened", path)
        self._remember(path)
        self.setWindowTitle(f"maizeviz — {Path(path).name}")
        self.say(f"saved the project {path}")
        self.saved.emit(path)

    def open_project(self, path: str | Path) -> None:
        """Read a project in a worker; the current canopy stays if it cannot be used."""
        from maizeviz_app import jobs, project

        path = str(path)
        self.say(f"opening the project {path}")
        cache = self._cache_folder()

        def work(job):
            opened = project.open_project(path, cache)
            tile, level, preserve = project.canopy_settings(opened)
            light = project.light_settings(opened)
            found = jobs.load_points(opened.points_path, (tile, tile),
                                     shown_name=opened.shown_name)
            layout = found.layout
            if opened.project.layout is not None:
                layout = project.layout_from_parts(opened.project.layout,
                                                   opened.project.arrays, found.plants, path)
            loaded = replace(found, layout=layout)
            return opened, loaded, (tile, level, preserve), light

        self.runner.run("load", f"opening {Path(path).name}", work, on_done=self._on_project,
                        on_error=lambda e: self._fail(e, "open project"))

    def _cache_folder(self) -> str:
        from PySide6.QtCore import QStandardPaths

        base = QStandardPaths.writableLocation(QStandardPaths.CacheLocation)
        return str(Path(base or Path.home() / ".cache" / "maizeviz") / "projects")

    def _on_project(self, out) -> None:
        opened, loaded, (tile, level, preserve), light = out
        for note in opened.notes:
            self.say(f"note: {note}")
        self.canopy_panel.set_tile(tile)
        self.canopy_panel.set_level(level)
        self.canopy_panel.preserve.blockSignals(True)
        self.canopy_panel.preserve.setChecked(preserve)
        self.canopy_panel.preserve.blockSignals(False)
        self.light_panel.apply_settings(light)
        self._project_layout = opened.project.layout is not None
        self._on_loaded(loaded, opened.project.points_csv, opened.path,
                        opened.project.points_path)
        self._pending_runs = list(opened.runs)

    def _adopt_pending_runs(self) -> None:
        """Light results of an opened project join the comparison once its canopy is built
        (their triangle classes are computed against the canopy they were traced on)."""
        if not self._pending_runs or self.built is None:
            return
        from maizeviz.light.leaf_light import triangle_light
        from maizeviz_app import plots

        pending, self._pending_runs = self._pending_runs, []
        for label, result in pending:
            classes = None
            if label == self.built.label and result.first_hits is not None and \
                    len(result.first_hits) >= self.canopy.n_triangles:
                classes = triangle_light(self.canopy, result)
            key = (round(result.sun.zenith_deg, 6), round(result.sun.azimuth_deg, 6),
                   tuple(float(h) for h in result.heights_cm), result.density,
                   self.light_panel.periodic.isChecked())
            self.runs.add(Run(label, self.signature(label), result, classes), key)
        self.light_panel.show_runs(self.runs, f"{len(pending)} light result(s) from the "
                                              "project")
        last = self.runs.for_signature(self.signature(self.built.label)) or self.runs.last
        if last is None:
            return
        curves = self.runs.curves()
        result = last.result
        self._heatmaps_for = last

        def work(job):
            maps = plots.heatmap_images(result, check=job.check)
            plot = plots.rgba(plots.transmission_figure(curves, _plot_title(result)))
            return maps, plot

        def done(out):
            self.plots.set_heatmaps(out[0])
            self.plots.set_transmission(out[1])
            self.light_shown.emit()

        self.runner.run("figures", "drawing the light figures", work, on_done=done,
                        on_error=lambda e: self._fail(e, "light"))
        if last.classes is not None:
            self.viewport.set_light(last.classes)
            self.colour_by("light")

    # ------------------------------------------------------------------ recent files
    def recent_files(self) -> list[str]:
        value = self._settings.value("recent", [])
        if isinstance(value, str):
            value = [value]
        return [str(p) for p in (value or []) if Path(str(p)).exists()]

    def _remember(self, path: str) -> None:
        from maizeviz_app.menus import RECENT_MAX

        paths = [str(Path(path))] + [p for p in self.recent_files() if p != str(Path(path))]
        self._settings.setValue("recent", paths[:RECENT_MAX])

    def clear_recent(self) -> None:
        self._settings.setValue("recent", [])

    # ------------------------------------------------------------------ exports
    def choose_export(self, what: str) -> None:
        names = {"canopy": ("Export the canopy mesh", "canopy.ply", MESH_FILTER),
                 "table": ("Export the transmission table", "transmission.csv", "CSV (*.csv)"),
                 "measures": ("Export the canopy measures", "canopy_measures.csv",
                              "CSV (*.csv)"),
                 "heatmap": ("Export the heatmap", "heatmap.png", "PNG (*.png)"),
                 "plot": ("Export transmission vs height", "transmission.png", "PNG (*.png)")}
        title, default, filt = names[what]
        path, chosen = QFileDialog.getSaveFileName(self, title, str(Path(self._folder()) /
                                                                     default), filt)
        if not path:
            return
        if "." not in Path(path).name and "(*." in chosen:
            path += chosen.split("(*", 1)[1].split(")")[0]
        self.export(what, path)

    def export(self, what: str, path: str | Path) -> None:
        """Write ``what`` (canopy, table, measures, heatmap, plot) to ``path`` in a worker."""
        path = str(path)
        try:
            work, args = self._export_work(what, path)
        except MaizevizError as exc:
            self._fail(exc, "export")
            return

        def done(p):
            self.say(f"exported {p}")
            self.saved.emit(p)

        self.runner.run("export", f"exporting {Path(path).name}", work, *args, on_done=done,
                        on_error=lambda e: self._fail(e, "export"), supersede=False)

    def _export_work(self, what: str, path: str):
        if what == "canopy":
            if self.canopy is None:
                raise MaizevizError("no canopy to export yet")
            canopy = self.canopy
            run = self.runs.for_signature(self.signature(self.built.label))
            classes = run.classes if run is not None else None

            def work(job):
                from maizeviz.canopy.export import export_canopy

                cells = {} if classes is None else {"light": classes.astype("int32")}
                export_canopy(path, canopy, cell_data=cells)
                return path
            return work, ()
        if what == "measures":
            if not self.measures_rows:
                raise MaizevizError("no canopy measures to export yet")
            rows = list(self.measures_rows.values())

            def work(job):
                from maizeviz.io.atomic import atomic_open

                with atomic_open(path, "w", newline="") as fh:
                    w = csv.DictWriter(fh, fieldnames=list(rows[0]))
                    w.writeheader()
                    for r in rows:
                        w.writerow({k: v.replace(",", "") for k, v in r.items()})
                return path
            return work, ()
        if self.runs.last is None:
            raise MaizevizError("no light result to export yet: compute direct light first")
        if what == "table":
            header, rows = self.runs.table()

            def work(job):
                from maizeviz.io.atomic import atomic_open

                with atomic_open(path, "w", newline="") as fh:
                    w = csv.writer(fh)
                    w.writerow(["height_cm"] + [f"transmission {h}" for h in header[1:]])
                    w.writerows(rows)
                return path
            return work, ()
        if what == "heatmap":
            run = self._heatmaps_for or self.runs.last
            height = self.plots.shown_height
            if height is None:
                height = float(run.result.heights_cm[0])
            result = run.result

            def work(job):
                from maizeviz.light.heatmap import heatmap_figure, save_figure, transmission_map

                save_figure(heatmap_figure(transmission_map(result, height, 5.0), result), path)
                return path
            return work, ()
        if what == "plot":
            from maizeviz_app import plots

            curves = self.runs.curves()
            title = _plot_title(self.runs.last.result)

            def work(job):
                from maizeviz.light.heatmap import save_figure

                save_figure(plots.transmission_figure(curves, title, width_in=7, dpi=110), path)
                return path
            return work, ()
        raise MaizevizError(f"unknown export '{what}'")

    # ------------------------------------------------------------------ help
    def about(self) -> None:
        QMessageBox.about(self, "About maizeviz", about_text())

    # ------------------------------------------------------------------ close
    def closeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        """Stop the reader, cancel and wait for the jobs, kill the core processes, save the
        window's geometry and docks, close the 3D view explicitly."""
        self._closing = True
        try:
            if self.digitizer is not None:
                self.digitizer.stop("window closed")
        except Exception as exc:  # noqa: BLE001 - closing must go on
            print(f"maizeviz: the digitizer did not stop cleanly: {exc}", file=sys.stderr)
        self.runner.shutdown(10.0)
        self._settings.setValue("geometry", self.saveGeometry())
        self._settings.setValue("window_state", self.saveState(STATE_VERSION))
        self._settings.sync()
        if self.viewport is not None:
            self.viewport.close()
        super().closeEvent(event)


def _plot_title(result) -> str:
    return (f"sun zenith {result.sun.zenith_deg:.1f}°, azimuth {result.sun.azimuth_deg:.1f}°; "
            f"{result.density:g} rays/cm²")


def about_text() -> str:
    return (f"<h3>maizeviz {__version__}</h3>"
            "<p>Digitized maize plants: NURBS leaf surfaces through every digitized point, "
            "meshes of chosen complexity, canopies and direct light.</p>"
            f"<p>It implements the method of: {PAPER}</p>"
            "<p>See docs/method.md for what is computed and how far it follows the paper.</p>")
