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
- The level label, Table 2 and the view change together when a built canopy arrives (while
  the digitizer records, the view keeps the plant being digitized and the new canopy waits
  until the session stops).

Errors go to the status bar and the Messages panel as one line for people
(:mod:`maizeviz_app.messages`), never as a modal box that would stop a technician in the field;
an error about one light setting also marks that field.
"""

from __future__ import annotations

import sys
import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QByteArray, QSettings, Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QPlainTextEdit,
    QPushButton,
    QScrollArea,
    QStackedWidget,
    QWidget,
)

from maizeviz import __version__
from maizeviz.errors import MaizevizError
from maizeviz.mesh.levels import COMPLEXITY_STOPS as LEVELS  # noqa: F401 - the slider's stops
from maizeviz.resources import example_points
from maizeviz_app.exports import export_job
from maizeviz_app.messages import user_message
from maizeviz_app.model import StudyModel
from maizeviz_app.panels.canopy import MESH_LEVEL, CanopyPanel
from maizeviz_app.panels.light import (
    COMPUTE_TEXT,
    MODES,
    InputProblem,
    LightPanel,
    LightPlots,
    LightRuns,
    Run,
)
from maizeviz_app.runs import day_summary, plot_title, run_info, value_legend
from maizeviz_app.workers import JobRunner, describe_internal

if TYPE_CHECKING:
    from maizeviz_app.panels.digitizer import DigitizerPanel
    from maizeviz_app.panels.layout import LayoutPanel
    from maizeviz_app.viewport import Viewport

#: The level the view draws the plants around the sampled tile at, when the canopy has more
#: triangles than the view's budget (maizeviz_app.viewport.VIEW_BUDGET).
DISPLAY_LEVEL = "36"
#: Version of the saved dock layout; bump when docks change so an old layout is not applied.
STATE_VERSION = 3
PROJECT_FILTER = "maizeviz project (*.maizeviz)"
POINTS_FILTER = "Points CSV (*.csv);;All files (*)"
CANOPY_MESH_FILTER = "Canopy mesh with plant and leaf ids (*.ply *.obj);;All files (*)"
#: Units and up axis a mesh file may be written in (what the open dialog offers).
MESH_FRAMES = {"cm, z up": ("cm", "z"), "m, z up": ("m", "z"), "mm, z up": ("mm", "z"),
               "cm, y up": ("cm", "y"), "m, y up": ("m", "y"), "mm, y up": ("mm", "y")}
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
    ("core", ("maizeviz_app.jobs", "maizeviz.light.results.per_leaf")),
    ("view", ("pyvista", "pyvistaqt", "maizeviz_app.viewport", "maizeviz_app.panels.layout",
              "maizeviz_app.panels.digitizer")),
    ("rest", ("matplotlib.figure", "matplotlib.backends.backend_agg", "maizeviz_app.plots",
              "maizeviz.light.report.heatmap", "maizeviz.canopy.export", "maizeviz_app.project")))


def _count(n: int, one: str, many: str | None = None) -> str:
    """``n`` and its noun, singular or plural ("1 plant", "2 leaves")."""
    return f"{n} {one if n == 1 else many or one + 's'}"


def _scrolled(widget: QWidget) -> QScrollArea:
    area = QScrollArea()
    area.setWidget(widget)
    area.setWidgetResizable(True)
    area.setFrameShape(QScrollArea.Shape.NoFrame)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAsNeeded)
    return area


def _own_window(centre: QWidget) -> None:
    """Give the 3D view's place a native window of its own (on X11), before the window shows.

    The 3D view is a QOpenGLWidget (pyvistaqt): Qt then composes the window it lies in through
    OpenGL at every repaint, and on software OpenGL (Mesa llvmpipe) composing the whole main
    window costs 20-30 ms, for a label or a progress bar as for a frame of the view. In a
    native window of its own, only the view's area is composed and the other widgets paint as
    plain raster (a status message: under 1 ms instead of 15-25). Its siblings (the docks)
    stay non-native. The view must be made inside it: a QOpenGLWidget that is ever a child of
    the main window itself makes Qt compose the whole window again."""
    if QApplication.platformName() != "xcb":
        return
    QApplication.setAttribute(Qt.ApplicationAttribute.AA_DontCreateNativeWidgetSiblings)
    centre.setAttribute(Qt.WidgetAttribute.WA_NativeWindow)


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
    #: Ask Save / Discard / Cancel before unsaved work (an edited layout, light results) is
    #: closed or replaced by another file.
    confirm_unsaved = True

    def __init__(self, points: str | Path | None = None, tile: int = 3):
        super().__init__()
        self.setWindowTitle("maizeviz")
        self._closing = False
        self._settings = QSettings("maizeviz", "maizeviz")
        self.runner = JobRunner(self)
        self.runner.progressed.connect(self._on_progress)
        self.runner.changed.connect(self._on_jobs_changed)
        self.model = StudyModel(tile)
        self.model.modified_changed.connect(lambda on: self.setWindowModified(on))
        self.model.project_changed.connect(lambda _p: self.setWindowTitle(self.model.title))
        self.model.points_changed.connect(lambda _l: self.setWindowTitle(self.model.title))
        self.viewport: Viewport | None = None
        self._view_pending: tuple | None = None   # (canopy, mesh) built while digitizing
        self._pending_runs: list = []     # light results of a project, waiting for a canopy
        self._after_save = None           # what to do once the project is saved (close, open)
        self._progress_shown = 0.0
        self._canopy_id = 0               # identifies the canopy shown (the light process
                                          # keeps the last one and its Embree scene)
        self._project_layout = False
        self._heatmaps_for: dict[str, Run] = {}    # light -> the run whose maps are shown

        placeholder = QLabel("starting the 3D view…", alignment=Qt.AlignmentFlag.AlignCenter)
        self._centre = QStackedWidget()
        self._centre.setMinimumSize(320, 200)
        self._centre.addWidget(placeholder)
        _own_window(self._centre)
        self.setCentralWidget(self._centre)
        self.docks: dict[str, QDockWidget] = {}
        self._build_panels()
        self._build_status()
        from maizeviz_app.menus import build_menus
        from maizeviz_app.workspaces import Workspaces

        self.workspaces = Workspaces(self, self._settings, STATE_VERSION,
                                     sizes=self._apply_default_sizes)
        self.workspaces.changed.connect(self._workspace_changed)
        self._canopy_away = False         # the digitizer has the view (until Analyse)
        self.light_shown.connect(lambda: None if self.digitizing else
                                 self.workspaces.show("analyse"))

        self.menu_actions = build_menus(self)
        self._default_state: QByteArray | None = None   # taken at the first show, docks sized
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
        feature = QDockWidget.DockWidgetFeature
        dock.setFeatures(feature.DockWidgetMovable | feature.DockWidgetFloatable
                         | feature.DockWidgetClosable)
        self.addDockWidget(area, dock)
        self.docks[name] = dock
        return dock

    def _build_panels(self) -> None:
        self.setCorner(Qt.Corner.BottomRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
        self.setCorner(Qt.Corner.TopRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
        self.setDockOptions(QMainWindow.DockOption.AnimatedDocks
                            | QMainWindow.DockOption.AllowTabbedDocks)
        self.canopy_panel = CanopyPanel(self.model)
        self.canopy_panel.open_requested.connect(self.choose_points)
        self.canopy_panel.level_requested.connect(lambda _lv: self.rebuild())
        self.canopy_panel.preserve_changed.connect(lambda _b: self.rebuild())
        self.light_panel = LightPanel(self.model)
        self.light_panel.compute_requested.connect(self.compute_light)
        self.light_panel.cancel_requested.connect(lambda: self.cancel_jobs("light"))
        self.light_panel.place_requested.connect(lambda _t: self.sun_from_place())
        self.light_panel.export_requested.connect(self.choose_export)
        self.light_panel.mode_changed.connect(lambda _m: self.light_panel.clear_problem())
        # the layout editor and the digitizer import much of the core: they are made once the
        # window is on screen (see _make_late_panels)
        self.layout_panel: LayoutPanel | None = None
        self.digitizer: DigitizerPanel | None = None
        self.plots = LightPlots()
        self.plots.heatmap_needed.connect(self._draw_heatmap)
        self.model.colour.heatmap.events.connect(lambda _info: self.plots.redraw())
        self.model.colour.events.shared.connect(lambda _on: self.plots.redraw())
        self.model.colour.events.painting.connect(lambda _p: self._light_to_view())
        self.messages = QPlainTextEdit(readOnly=True)
        self.messages.setMaximumBlockCount(1000)
        from maizeviz_app.panels.colour import ColourPanel

        self.colour_panel = ColourPanel(self.model.colour)
        self.plots.heatmap.limits_shown.connect(self.colour_panel.heatmap_editor.show_limits)

        right = Qt.DockWidgetArea.RightDockWidgetArea
        canopy = self._dock("canopy", "Canopy", self.canopy_panel, right)
        light = self._dock("light", "Light", self.light_panel, right)
        layout = self._dock("layout", "Layout", QLabel("starting…"), right)
        digitizer = self._dock("digitizer", "Digitizer", QLabel("starting…"), right)
        colour = self._dock("colour", "Colour", self.colour_panel, right)
        for d in (light, layout, digitizer, colour):
            self.tabifyDockWidget(canopy, d)
        canopy.raise_()
        bottom = Qt.DockWidgetArea.BottomDockWidgetArea
        results = self._dock("results", "Light results", self.plots, bottom, scroll=False)
        messages = self._dock("messages", "Messages", self.messages, bottom, scroll=False)
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
        self.job_label.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("stop the work under way (Esc)")
        self.cancel_button.clicked.connect(lambda: self.cancel_jobs())
        self.cancel_button.setEnabled(False)
        lay.addWidget(self.job_label)
        lay.addWidget(self.cancel_button)
        self.statusBar().addPermanentWidget(box)

    def _restore_window(self) -> bool:
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
        self.workspaces.settle(self._state_restored)

    def _apply_default_sizes(self) -> None:
        w, h = self.width(), self.height()
        self.resizeDocks([self.docks["canopy"]], [max(380, min(480, int(w * 0.33)))],
                         Qt.Orientation.Horizontal)
        self.resizeDocks([self.docks["results"]], [max(200, min(380, int(h * 0.36)))],
                         Qt.Orientation.Vertical)

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
        self.workspaces.reset()

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

            # made in its place: a QOpenGLWidget made as a child of the main window itself makes
            # Qt compose the whole window again (see _own_window), and re-laying it out then
            # gives the docks all the room but the view's minimum height
            self.viewport = Viewport(self._centre)
            self.viewport.set_colour_scale(self.model.colour.view)
            self.viewport.limits_shown.connect(self.colour_panel.view_editor.show_limits)
            from maizeviz_app.linked import LinkedSelection

            self.linked = LinkedSelection(self.model, self.viewport, self.light_panel.plants,
                                          lambda text: self.say(text, status_only=True))
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

        self.layout_panel = LayoutPanel(self.model)
        self.layout_panel.applied.connect(self._on_layout)
        self.layout_panel.problem.connect(self.say)
        self.digitizer = DigitizerPanel(self.viewport)
        self.digitizer.alert.connect(lambda text: self.say(text, error=True, status_only=True))
        self.digitizer.stopped.connect(self._digitizing_stopped)
        self.digitizer.started.connect(self._digitizing_started)
        self.docks["layout"].setWidget(_scrolled(self.layout_panel))
        self.docks["digitizer"].setWidget(_scrolled(self.digitizer))

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

    def _fail(self, exc: BaseException, doing: str, mode: str | None = None) -> None:
        """An error from a job: one line for people; the traceback on stderr if it is a bug.
        An error about a light setting is also said in the light panel, its field marked
        (``mode``: the light it was computed for; the sun for "Sun from place")."""
        if self._closing:
            return
        if not isinstance(exc, (MaizevizError, OSError, MemoryError)):
            describe_internal(exc)
        text = user_message(exc, doing)
        self.say(f"error: {text}", error=True)
        quantity = getattr(exc, "quantity", None)
        if doing in ("light", "sun"):
            self.light_panel.show_problem(text)
        if quantity:
            mode = mode or ("sun" if doing == "sun" else None)
            if self.light_panel.point_at(quantity, text, mode):
                self.docks["light"].raise_()
        self.failed.emit(text)

    # ------------------------------------------------------------------ opening
    def open_any(self, path: str | Path) -> None:
        """A project (``.maizeviz``), a canopy mesh (``.ply``, ``.obj``) or a points CSV."""
        from maizeviz.io.mesh_canopy import is_mesh_path

        if str(path).endswith(".maizeviz"):
            self.open_project(path)
        elif is_mesh_path(path):
            self.open_mesh(path)
        else:
            self.open_points(path)

    def choose_points(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open digitized points", self._folder(),
                                              POINTS_FILTER)
        if path:
            self.open_points(path)

    def choose_mesh(self) -> None:
        """Open a canopy from elsewhere (OpenAlea, Helios, a scan): a PLY or OBJ with a plant
        and a leaf id per face, after asking its units and up axis."""
        from PySide6.QtWidgets import QInputDialog

        path, _ = QFileDialog.getOpenFileName(self, "Open a canopy mesh", self._folder(),
                                              CANOPY_MESH_FILTER)
        if not path:
            return
        frame, ok = QInputDialog.getItem(
            self, "Units of the mesh", "The file's coordinates are in (OpenAlea and Helios "
            "write z up, many scanners y up):", list(MESH_FRAMES), 0, False)
        if not ok:
            return
        field, ok = QInputDialog.getText(
            self, "Field of the mesh", "The ground plot x0, y0, x1, y1 in cm, in field "
            "coordinates (it sets leaf area index, ground cover and the periodic field's tile; "
            "leave empty for the plot the file carries, as maizeviz's exports do, else the "
            "mesh's extent seen from above):")
        if ok:
            self.open_mesh(path, *MESH_FRAMES[frame], field=field.strip() or None)

    def open_mesh(self, path: str | Path, unit: str | None = None, up: str = "z",
                  field: str | tuple[float, float, float, float] | None = None) -> None:
        """Read a canopy mesh in a worker (:func:`maizeviz.canopy.from_mesh.read_mesh_canopy`:
        ``unit`` cm, m or mm, None: cm, refused when the size says otherwise; ``field`` x0,
        y0, x1, y1 cm, as numbers or text, None: the mesh's extent seen from above); it
        replaces the points: light, tables and exports work on it, the slider and layout do
        not apply."""
        if not self.keep_unsaved(lambda: self.open_mesh(path, unit, up, field)):
            return
        from maizeviz_app import jobs

        path = str(path)
        self.say(f"reading the canopy mesh {path}")
        runner, view_ready = self.runner, self._view_ready

        def work(job):
            from maizeviz.canopy.from_mesh import check_field, read_mesh_canopy
            from maizeviz.canopy.measures import TABLE2_COLUMNS, table2_row

            t0 = time.perf_counter()
            ground = None if field is None else check_field(field)
            canopy, _mesh, notes = read_mesh_canopy(path, unit, up, ground)  # type: ignore[arg-type]
            read_s = time.perf_counter() - t0
            job.check()
            from maizeviz.cost import TooSlow, check, cover_cost

            try:       # the ground cover is measured over the whole field, as for points
                check([[cover_cost(canopy.layout, jobs.APP_COVER_RESOLUTION_CM)]])
            except TooSlow as exc:
                raise MaizevizError(f"{exc.estimate}: give a smaller field",
                                    quantity="field") from None
            t0 = time.perf_counter()
            m = runner.cover_process.call("measure", object(), canopy,
                                          (jobs.APP_COVER_RESOLUTION_CM,), job)
            measure_s = time.perf_counter() - t0
            while not view_ready.wait(0.05):
                job.check()
            from maizeviz_app.mesh_view import mesh_polydata

            row = table2_row(m, read_s, MESH_LEVEL)
            return notes, (canopy, m, read_s, measure_s, mesh_polydata(canopy),
                           tuple(TABLE2_COLUMNS), row)

        self.runner.run("load", f"reading {Path(path).name}", work,
                        on_done=lambda out: self._on_mesh(path, *out),
                        on_error=lambda e: self._fail(e, "open mesh"))

    def _on_mesh(self, path: str, notes: list, parts: tuple) -> None:
        from maizeviz_app import jobs

        self._heatmaps_for.clear()
        self.plots.clear()
        self.plots.set_transmission(None)
        self.model.open_mesh(path)
        self._settings.setValue("last_folder", str(Path(path).parent))
        self._remember(path)
        canopy, m, read_s, measure_s, mesh, columns, row = parts
        for note in [*notes, *canopy.layout.warnings]:         # the latter say the field
            self.say(f"note: {note}")
        self._on_built(jobs.Built(MESH_LEVEL, MESH_LEVEL, canopy, m, read_s, measure_s, mesh,
                                  columns, row, self.model.serial))

    def choose_project(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open project", self._folder(),
                                              PROJECT_FILTER)
        if path:
            self.open_project(path)

    def _folder(self) -> str:
        return str(self._settings.value("last_folder", str(Path.home())))

    def keep_unsaved(self, then) -> bool:
        """True when the caller may go on: nothing is unsaved, or the user discards it. Save
        saves the project (asking where, the first time) and calls ``then()`` once it is
        written; Cancel (or a save that does not happen) stops."""
        if not self.model.modified or not self.confirm_unsaved or self._closing:
            return True
        name = Path(self.project_path).name if self.project_path else "this study"
        box = QMessageBox(QMessageBox.Icon.Warning, "Unsaved changes",
                          f"{name} has changes that are not in a project: an edited layout or "
                          "light results. Save them first?",
                          QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard
                          | QMessageBox.StandardButton.Cancel, self)
        box.setDefaultButton(QMessageBox.StandardButton.Save)
        answer = box.exec()
        if answer == QMessageBox.StandardButton.Discard:
            return True
        if answer == QMessageBox.StandardButton.Save:
            self._after_save = then
            self.save_project_here()
            if self.runner.current("save") is None:   # the save dialog was cancelled
                self._after_save = None
        return False

    def open_points(self, path: str | Path, layout=None) -> None:
        """Read a points file in a worker; the current canopy stays until it has loaded."""
        if not self.keep_unsaved(lambda: self.open_points(path, layout)):
            return
        from maizeviz_app import jobs

        path = str(path)
        n = self.tile_n
        self.say(f"reading {path}")

        def load(job, p):
            loaded = jobs.load_points(p, (n, n), layout=layout)
            return loaded, Path(p).read_bytes()

        self.runner.run("load", f"reading {Path(path).name}", load, path,
                        on_done=lambda r: self._on_loaded(r[0], r[1], None, r[0].path),
                        on_error=lambda e: self._fail(e, "open points"))

    @property
    def tile_n(self) -> int:
        """Tiles along each side of the layout on screen (see ``StudyModel.tile_n``)."""
        return self.model.tile_n

    # the model's state, under the names tests and scripts know
    @property
    def loaded(self):
        return self.model.loaded

    @property
    def built(self):
        return self.model.built

    @property
    def canopy(self):
        return self.model.canopy

    @property
    def runs(self) -> LightRuns:
        return self.model.runs

    @property
    def project_path(self) -> str | None:
        return self.model.project_path

    @property
    def measures_rows(self) -> dict[str, dict]:
        return self.model.measures_rows

    def _on_loaded(self, loaded, points_bytes: bytes, project: str | None,
                   origin: str) -> None:
        self._heatmaps_for.clear()
        self.plots.clear()
        self.plots.set_transmission(None)
        self.model.open_points(loaded, points_bytes, origin, project,
                               project is not None and self._project_layout)
        opened = project or loaded.path
        if loaded.path != str(example_points()) or project:
            self._settings.setValue("last_opened", opened)
            self._remember(opened)
        self._settings.setValue("last_folder", str(Path(opened).parent))
        for w in loaded.warnings:
            self.say(f"note: {w}")
        for e in loaded.skipped:
            self.say(f"skipped: {e}")
        self.say(f"{_count(len(loaded.leaves), 'leaf', 'leaves')} of "
                 f"{_count(len(loaded.plants), 'plant')}; "
                 f"{len(loaded.layout.placements)} plants in the canopy")
        self.rebuild()

    def _on_layout(self, layout) -> None:
        if self.loaded is None:
            return
        if self.model.edit_layout(layout):
            self.say("note: the layout changed; light results of the previous layout were "
                     "cleared")
        self._heatmaps_for.clear()
        self.plots.clear()
        self.plots.set_transmission(None)
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
        return self.model.signature(label)

    def rebuild(self) -> None:
        """Rebuild the canopy at the slider's level (a running rebuild is superseded)."""
        if self.loaded is None or self._closing:
            return
        from maizeviz_app import jobs

        loaded, level = self.loaded, self.level
        preserve = self.canopy_panel.preserve.isChecked()
        serial = self.model.serial
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
            from maizeviz_app.viewport import VIEW_BUDGET, canopy_polydata, display_polydata

            if canopy.n_triangles > VIEW_BUDGET and level != DISPLAY_LEVEL:
                # a frame of millions of triangles stalls software OpenGL: the plants around
                # the sampled tile are drawn at 36 triangles a leaf (light still per triangle)
                coarse = jobs.build(loaded, DISPLAY_LEVEL, preserve)[0]
                job.check()
                mesh = display_polydata(canopy, coarse) \
                    if coarse.n_triangles < canopy.n_triangles else canopy_polydata(canopy)
            else:
                mesh = canopy_polydata(canopy)
            row = table2_row(m, build_s, label)
            return jobs.Built(level, label, canopy, m, build_s, measure_s, mesh,
                              tuple(TABLE2_COLUMNS), row, serial)

        from maizeviz.cost import cover_cost, layout_cost
        from maizeviz.mesh.levels import parse_level

        stage = [layout_cost(loaded.leaves, loaded.layout, parse_level(level)),
                 cover_cost(loaded.layout, jobs.APP_COVER_RESOLUTION_CM)]
        if not self.affordable([stage], "build"):
            shown = self.built is not None and self.built.serial == serial
            if shown:
                self.canopy_panel.set_level(self.built.level)
            self.canopy_panel.set_pending("" if shown else
                                          "not built: choose a coarser level or fewer plants")
            return
        self.canopy_panel.set_pending(f"building: {parse_level(level).description}…")
        self.runner.run("build", f"building {parse_level(level).label}", work,
                        on_done=self._on_built, on_error=lambda e: self._fail(e, "build"))

    def _on_built(self, built) -> None:
        """A canopy built: the level label, Table 2 and the view change together; while the
        digitizer records, the view keeps the plant being digitized and the canopy waits
        (``canopy_shown`` is emitted either way: the canopy is the window's)."""
        mesh = built.polydata
        if self.viewport is None or not self.model.show_built(built):
            return
        self._canopy_id += 1
        if self.digitizing or self._canopy_away:
            self._view_pending = (built.canopy, mesh)
            self.say(f"{built.label} is ready; it shows in the Analyse workspace once the "
                     "digitizing session stops", status_only=True)
        else:
            self._view_pending = None
            self.viewport.show_canopy(built.canopy, mesh)
        self._adopt_pending_runs()
        self._complete_runs()
        self._light_to_view()
        m = built.measures
        if "view_note" in mesh.field_data:
            self.say(f"note: {built.label} has {m.triangles:,} triangles; to keep the window "
                     f"responsive {mesh.field_data['view_note'][0]}")
        elif "source" in mesh.field_data:
            self.say(f"note: {built.label} has {m.triangles:,} triangles; to keep the window "
                     "responsive the view draws the plants around the sampled tile at 36 "
                     "triangles a leaf (light, tables and exports use every triangle)")
        if not self.digitizing:
            self.say(f"{built.label}: {m.triangles:,} triangles, leaf area "
                     f"{m.leaf_area_m2:.2f} m², LAI {m.lai:.2f}; built in {built.build_s:.2f} s, "
                     f"measured in {built.measure_s:.2f} s", status_only=True)
        self.canopy_shown.emit(built.label)

    @property
    def digitizing(self) -> bool:
        """A digitizing session is recording (the view shows the plant being digitized)."""
        return self.digitizer is not None and self.digitizer.recording

    def _light_to_view(self, colour: bool = False) -> None:
        """Colour the canopy in view by the light last computed on it (the sun's classes, or a
        sky's or day's light per leaf), unless the view is busy with the digitizer;
        ``colour``: switch the colouring to light."""
        if self.viewport is None or self.built is None or self.digitizing or \
                self._canopy_away or self._view_pending is not None:
            return
        run = self.runs.latest(self.signature(self.built.label))
        if run is not None and run.kind == "sun" and run.classes is not None and \
                (run.extra is None or run.extra.leaf_value is None):
            self.viewport.set_sun(run.painting, self.model.colour.painting, run.classes)
            self.colour_panel.show_painting(self.viewport.painting_note)
        elif run is not None and run.extra is not None and \
                getattr(run.extra, "leaf_value", None) is not None:
            title, unit = value_legend(run)
            self.viewport.set_light_values(run.extra.leaf_value, title, unit)
            self.colour_panel.show_painting("")          # a sun's painting is not shown
        if colour and run is not None:
            self.colour_by("light")
        self._sync_colour_actions()

    def step_level(self, step: int) -> None:
        s = self.canopy_panel.slider
        s.setValue(max(s.minimum(), min(s.maximum(), s.value() + step)))

    # ------------------------------------------------------------------ light
    def compute_light(self) -> None:
        """Compute the light of the mode chosen in the light panel (sun, sky or day) on the
        canopy shown, in the light process (which keeps the canopy's Embree scene)."""
        if self._closing:
            return
        if self.canopy is None or self.built is None:
            self.say("error: no canopy yet: open a points file first", error=True)
            return
        panel = self.light_panel
        panel.clear_problem()
        mode = panel.mode
        settings: object
        args: tuple
        try:
            optics = None
            if mode == "sun":
                request = panel.request()
                heights = request.heights_cm
                optics = panel.optics_spec()
                settings = (round(request.sun.zenith_deg, 6), round(request.sun.azimuth_deg, 6),
                            optics)
                op, args = "light", (request,)
            else:
                sampling = panel.sampling()
                heights = sampling.heights_cm
                sky = panel.sky_spec()
                if mode == "sky":
                    settings, op, args = sky, "sky", (sampling, sky)
                else:
                    day = panel.day_spec()
                    settings, op, args = (day, sky), "period", (sampling, sky, day)
        except (InputProblem, MaizevizError) as exc:
            self._fail(exc, "light", mode)
            return
        if not self.affordable([self._light_costs(mode, args, heights, optics)], "light"):
            return
        from maizeviz_app import plots

        canopy, built = self.canopy, self.built
        label = built.label
        signature = self.signature(label)
        sampling_key = panel.sampling_key(heights)
        runs = self.runs.copy()
        key = self._canopy_id
        runner = self.runner
        shown_height = max(self.plots.height_box.currentIndex(), 0)
        look = plots.Look.of(self.model.colour, self._heatmaps_for)

        def work(job):
            out = runner.light_process.call(op, key, canopy, args, job)
            job.check()
            if mode == "sun":
                from maizeviz.light.results.painting import sun_painting

                absorbed = None
                if optics is not None:              # leaves with optics: absorbed light too
                    absorbed = runner.light_process.call("absorbed", key, canopy,
                                                         (args[0], optics), job)
                    job.check()
                painting = sun_painting(canopy, out)
                run = Run(label, signature, out, painting.classes, extra=absorbed,
                          painting=painting)
            else:
                run = Run(label, signature, out.light, None, mode, out)
            maps = plots.heatmap_images(run.result, first=shown_height, check=job.check,
                                        kind=mode, look=look.sharing(mode, run.result))
            runs.add(run, settings, sampling_key)
            plot = plots.rgba(plots.transmission_figure(runs.curves(), plot_title(runs)))
            return run, settings, sampling_key, maps, plot

        panel.set_running(True)
        panel.set_progress(f"{COMPUTE_TEXT[mode].replace('Compute', 'computing')} on {label}…")
        self.docks["light"].raise_()
        self.runner.run("light", f"{mode} light on {label}", work, on_done=self._on_lit,
                        on_error=lambda e: self._light_failed(e, mode))

    def _light_costs(self, mode: str, args: tuple, heights, optics=None) -> list:
        """What a light run of ``mode`` on the canopy shown will cost (``maizeviz.cost``): its
        rays (times the directions: the sun, the sky's, a day's steps; with leaf optics, the
        absorbed light's beams and their scattering) and its heatmaps."""
        from maizeviz.cost import light_costs
        from maizeviz_app.plots import HEATMAP_BIN_CM

        rect = args[0].rect or self.canopy.layout.centre_bounds
        directions = 1
        if optics is not None:                          # the beams, each scattered ~3 times
            directions += 3 * (1 + (46 if optics.diffuse_w_m2 > 0 else 0))
        if mode != "sun":
            directions = max(args[1].directions, 1)
            if mode == "day":
                directions += args[2].steps_bound()
        return light_costs(rect, args[0].density, len(heights), directions, 1, HEATMAP_BIN_CM,
                           self.built.measures.triangles)

    def affordable(self, stages, doing: str) -> bool:
        """Whether to start work estimated as ``stages`` (lists of ``maizeviz.cost.Cost``): no,
        with a message, when it would not fit in this machine's memory; when merely slow, as
        the user answers :meth:`confirm_slow`."""
        from maizeviz.cost import TooSlow, check

        try:
            check(stages)
        except TooSlow as exc:
            if self.confirm_slow(exc.estimate):
                return True
            self.say(f"not started: {exc.estimate}", status_only=True)
            return False
        except MaizevizError as exc:
            self._fail(exc, doing)
            return False
        return True

    def confirm_slow(self, estimate: str) -> bool:
        """Ask before starting work estimated at ``estimate`` (more than a quarter of an
        hour); it runs in the background and can be cancelled."""
        box = QMessageBox(QMessageBox.Icon.Question, "Start a long computation?",
                          f"{estimate}.\n\nIt runs in the background and can be cancelled; "
                          "a coarser level, a lower density or fewer directions or steps make "
                          "it shorter.",
                          QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.Cancel, self)
        box.button(QMessageBox.StandardButton.Yes).setText("Start")
        box.setDefaultButton(QMessageBox.StandardButton.Cancel)
        return box.exec() == QMessageBox.StandardButton.Yes

    def _light_failed(self, exc: BaseException, mode: str = "sun") -> None:
        self.light_panel.set_running(False)
        self._fail(exc, "light", mode)

    def _on_lit(self, out) -> None:
        """A light result: table, summary, plants, figures and colours change together;
        nothing shown is dropped unless a new comparison starts."""
        run, settings, sampling_key, maps, plot = out
        panel = self.light_panel
        panel.set_running(False)
        if run.signature[0] != self.model.serial:
            return
        if self.model.add_run(run, settings, sampling_key, run_info(run)):
            self.say("note: the light settings changed; the comparison starts again")
        r = run.result
        if run.kind == "day":
            summary = day_summary(r)
            panel.show_summary(summary)
        elif self.runs.of_kind("day") is None:
            panel.show_summary("")
        if run.kind != "sun" or run.extra is not None:
            panel.show_plants(run)
        elif self.runs.of_kind("sky") is None and self.runs.of_kind("day") is None:
            panel.show_plants(None)
        self._heatmaps_for = {k: v for k, v in self._heatmaps_for.items()
                              if self.runs.of_kind(k) is not None}
        self._heatmaps_for[run.kind] = run
        self.plots.keep_only(set(self._heatmaps_for))
        self.plots.set_heatmaps(maps, run.kind)
        if self.model.colour.shared:                  # the others' scale includes this run
            self.plots.redraw(keep=run.kind)
        self.plots.set_transmission(plot)
        for w in r.warnings:
            self.say(f"{'note' if 'sun never rises' in w else 'warning'}: {w}")
        if self.built is not None and self.signature(self.built.label) == run.signature:
            self._light_to_view(colour=True)
            if run.painting is not None and self.viewport is not None:
                self.say(f"note: the view shows {self.viewport.painting_note}")
        self.docks["results"].raise_()
        if run.kind == "day":
            self.say(summary.replace("\n", "; "), status_only=True)
        else:
            self.say(f"{run.name}: transmission "
                     + ", ".join(f"{t:.3f}" for t in run.transmission) + " at "
                     + ", ".join(f"{h:g}" for h in r.heights_cm) + " cm", status_only=True)
        self.light_shown.emit()

    def _draw_heatmap(self, kind: str, index: int) -> None:
        """The heatmap of another height of a result shown, drawn in a worker."""
        run = self._heatmaps_for.get(kind)
        if run is None:
            return
        from maizeviz_app import plots

        result = run.result
        height = float(result.heights_cm[index])
        look = plots.Look.of(self.model.colour, self._heatmaps_for)

        def done(rgba):
            if self._heatmaps_for.get(kind) is run:
                self.plots.set_heatmap(index, rgba, kind)

        self.runner.run("heatmap", f"drawing the heatmap at {height:g} cm",
                        lambda job: plots.heatmap_image(result, height, kind=kind, look=look),
                        on_done=done, on_error=lambda e: self._fail(e, "light"))

    def sun_from_place(self) -> None:
        """Sun angles from the date, time and place typed (pvlib, in a worker)."""
        text = self.light_panel.place.text()

        def work(job, t):
            from maizeviz.light.sources.sun import sun_at

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
    def choose_view_image(self) -> None:
        """File > Save view as image: ask the width and the file, then save."""
        if self.viewport is None:
            return
        from maizeviz_app.snapshot import ask_view_image

        chosen = ask_view_image(self, self.viewport, self._folder())
        if chosen is not None:
            self.save_view_image(*chosen)

    def save_view_image(self, path: str | Path, width: int | None = None) -> None:
        """The 3D view as a PNG ``width`` pixels wide (None: the view's), with its colour key
        (:mod:`maizeviz_app.snapshot`)."""
        if self.viewport is None:
            return
        from maizeviz_app.snapshot import save_view_image

        try:
            written = save_view_image(self.viewport, path, width)
        except (MaizevizError, OSError, ValueError) as exc:
            self._fail(exc, "export")
            return
        self.say(f"saved the view as {written}")
        self.saved.emit(str(written))

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
            act = self.menu_actions.get(f"colour_{name}")
            if act is not None:
                act.setChecked(self.viewport.colouring == name)

    def _digitizing_started(self) -> None:
        self._canopy_away = True
        self.workspaces.show("digitize")

    def _digitizing_stopped(self, _why: str) -> None:
        """In Digitize the plant just digitized stays in the view (no canopy frame on Stop);
        in Analyse the canopy comes back at once."""
        if not self._closing and self.workspaces.current == "analyse":
            self._canopy_back()

    def _workspace_changed(self, name: str) -> None:
        if name == "analyse" and not self.digitizing:
            self._canopy_back()

    def _canopy_back(self) -> None:
        """The canopy back in the view after a session: the one built meanwhile if any."""
        if not self._canopy_away:
            return
        self._canopy_away = False
        if self.digitizer is not None:
            self.digitizer.release_view()
        if self.viewport is None or self.canopy is None:
            return
        pending, self._view_pending = self._view_pending, None
        if pending is not None:
            self.viewport.show_canopy(*pending)
            self.viewport.camera_preset("reset")
        else:
            self.viewport.restore_canopy()
        self._light_to_view()

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

    def _on_progress(self, _job_id: int, kind: str, label: str, done: int, total: int) -> None:
        # each repaint recomposes the window (see _build_status): twice a second at most
        now = time.perf_counter()
        if now - self._progress_shown < 0.5:
            return
        self._progress_shown = now
        text = f"{label} ({100 * done // max(total, 1)}%)"
        self.job_label.setText(text)
        if kind == "light":
            self.light_panel.set_progress(text)

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
        if self.model.mesh_path is not None:
            self.say("error: a canopy read from a mesh file is not saved in a project (a "
                     "project keeps digitized points); export its light instead", error=True)
            return
        if self.loaded is None:
            self.say("error: nothing to save yet: open a points file first", error=True)
            return
        from maizeviz_app import project

        model = self.model
        loaded, data, origin = model.loaded, model.points_bytes, model.points_origin
        layout = loaded.layout if model.layout_edited else None   # else: the tiling, exactly
        canopy = {"tile": self.tile_n, "level": self.level,
                  "preserve_area": self.canopy_panel.preserve.isChecked()}
        light = self.light_panel.settings()
        view = self.model.colour.to_doc()
        runs = []
        sun_settings = self.runs.settings.get("sun")
        optics = sun_settings[2] if isinstance(sun_settings, tuple) and \
            len(sun_settings) == 3 else None
        for r in self.runs.in_order():
            runs.append((r.label, r.result,
                         project.settings_doc(r.kind, self.runs.settings.get(r.kind))))
            if r.balance is not None:              # the sun's absorbed light beside it
                runs.append((r.label, r.extra.light, project.settings_doc("absorbed",
                                                                           optics)))
        path = str(path)

        def work(job):
            from maizeviz.io.project import save_project
            from maizeviz.project.study import make_project

            # the runs were all traced on the layout shown (a layout edit clears them)
            proj = make_project(origin, data, layout, loaded.layout, canopy, light, runs,
                                view)
            save_project(path, proj)
            return path

        self.runner.run("save", f"saving {Path(path).name}", work, on_done=self._on_saved,
                        on_error=self._save_failed, supersede=False)

    def _save_failed(self, exc: BaseException) -> None:
        self._after_save = None                  # nothing closes or opens over unsaved work
        self._fail(exc, "save project")

    def _on_saved(self, path: str) -> None:
        self.model.saved(path)
        self._settings.setValue("last_opened", path)
        self._remember(path)
        self.say(f"saved the project {path}")
        self.saved.emit(path)
        then, self._after_save = self._after_save, None
        if then is not None:
            then()

    def open_project(self, path: str | Path) -> None:
        """Read a project in a worker; the current canopy stays if it cannot be used."""
        if not self.keep_unsaved(lambda: self.open_project(path)):
            return
        from maizeviz_app import jobs, project

        path = str(path)
        self.say(f"opening the project {path}")
        cache = self._cache_folder()

        def work(job):
            from maizeviz.mesh.levels import parse_level
            from maizeviz.project import study

            opened = study.open_project(path, cache)
            tile, level, preserve = project.canopy_settings(opened)
            light = project.light_settings(opened)
            project.view_settings(opened)
            found = jobs.load_points(opened.points_path, (tile, tile),
                                     shown_name=opened.shown_name)
            layout = study.restore_layout(opened, found.plants) or found.layout
            study.check_canopy_fits(found.leaves, layout, parse_level(level), path)
            results, dropped = study.results_on(opened, layout, found.leaves)
            opened.notes.extend(dropped)
            runs = [project.stored_run(r, path) for r in results]
            loaded = replace(found, layout=layout)
            return opened, loaded, (tile, level, preserve), light, runs

        self.runner.run("load", f"opening {Path(path).name}", work, on_done=self._on_project,
                        on_error=lambda e: self._fail(e, "open project"))

    def _cache_folder(self) -> str:
        from PySide6.QtCore import QStandardPaths

        base = QStandardPaths.writableLocation(QStandardPaths.StandardLocation.CacheLocation)
        return str(Path(base or Path.home() / ".cache" / "maizeviz") / "projects")

    def _on_project(self, out) -> None:
        opened, loaded, (tile, level, preserve), light, runs = out
        for note in opened.notes:
            self.say(f"note: {note}")
        self.model.tile = tile
        self.canopy_panel.set_level(level)
        self.canopy_panel.preserve.blockSignals(True)
        self.canopy_panel.preserve.setChecked(preserve)
        self.canopy_panel.preserve.blockSignals(False)
        self.light_panel.apply_settings(light)
        self.model.colour.update_from_doc(opened.view, opened.path)
        self._project_layout = opened.project.layout is not None
        self._on_loaded(loaded, opened.project.points_csv, opened.path,
                        opened.project.points_path)
        self._pending_runs = list(runs)

    def _adopt_pending_runs(self) -> None:
        """Light results of an opened project (sun, sky and day) join the comparison once its
        canopy is built, shown as after a fresh run: table, plot, heatmaps, the day's summary,
        the plants' light and the canopy's colours (those of the results traced on the canopy
        shown are computed against it, the others' when their level is shown)."""
        if not self._pending_runs or self.built is None:
            return
        from maizeviz_app import jobs, plots

        pending, self._pending_runs = self._pending_runs, []
        absorbed = {s.label: s for s in pending if s.kind == "absorbed"}
        pending = [s for s in pending if s.kind != "absorbed"]
        for stored in pending:
            label, result, kind, settings = stored
            extra = None
            if kind == "sun":
                kept = absorbed.get(label)
                settings = (round(result.sun.zenith_deg, 6), round(result.sun.azimuth_deg, 6),
                            kept.settings if kept is not None else None)
                if kept is not None:                # computed against the canopy later
                    extra = jobs.Absorbed(kept.result, None, None)
                density = result.density
            elif kind == "sky":
                density = result.density
            else:
                density = result.sky.density if result.sky is not None else \
                    self.light_panel.density.value()
            sampling = (tuple(float(h) for h in result.heights_cm), density,
                        bool(getattr(result, "periodic", self.light_panel.periodic.isChecked())))
            self.model.add_run(Run(label, self.signature(label), result, None, kind, extra),
                               settings, sampling,
                               f"{len(pending)} light result(s) from the project", saved=True)
        here = self.signature(self.built.label)
        shown = {}
        for kind in MODES:
            run = self.runs.for_signature(here, kind) or self.runs.of_kind(kind)
            if run is not None:
                shown[kind] = run
        if not shown:
            return
        day = shown.get("day")
        self.light_panel.show_summary(day_summary(day.result) if day is not None else "")
        self.light_panel.show_plants(self._plants_run())
        latest = self.runs.latest(here) or self.runs.last
        order = sorted(shown, key=lambda k: latest is not None and k == latest.kind)
        curves = self.runs.curves()
        title = plot_title(self.runs)
        self._heatmaps_for = dict(shown)
        results = [(k, shown[k].result) for k in order]
        look = plots.Look.of(self.model.colour, shown)

        def work(job):
            maps = [(k, plots.heatmap_images(r, check=job.check, kind=k, look=look))
                    for k, r in results]
            plot = plots.rgba(plots.transmission_figure(curves, title))
            return maps, plot

        def done(out):
            for kind, maps in out[0]:
                if self._heatmaps_for.get(kind) is shown[kind]:
                    self.plots.set_heatmaps(maps, kind)
            self.plots.set_transmission(out[1])
            if self.runner.current("complete") is None:        # else: once it is done
                self.light_shown.emit()

        self.runner.run("figures", "drawing the light figures", work, on_done=done,
                        on_error=lambda e: self._fail(e, "light"))
        self._light_to_view(colour=True)

    def _plants_run(self) -> Run | None:
        """The latest result with light per plant to show: a sky's, a day's or a sun's
        absorbed light (once computed against its canopy)."""
        runs = [r for r in self.runs.in_order()
                if r.kind != "sun" or getattr(r.extra, "plant_rows", None) is not None]
        return runs[-1] if runs else None

    def _complete_runs(self) -> None:
        """Results read from a project that were traced on the canopy shown get what the
        window shows of them, computed against it in a worker: a sun's light class per
        triangle, a sky's or day's light per leaf and plant; then the plants' light and the
        canopy's colours follow."""
        if self.built is None or self.canopy is None:
            return
        here, canopy = self.signature(self.built.label), self.canopy
        n = canopy.n_triangles
        todo = []
        for run in self.runs.runs.values():
            if run.signature != here:
                continue
            r = run.result
            if run.kind == "sun" and (run.classes is None or run.extra is not None
                                      and run.extra.leaf_value is None):
                if r.first_hits is not None and len(r.first_hits) >= n:
                    todo.append(run)
            elif run.kind != "sun" and run.extra is None:
                per_triangle = r.triangle_share if run.kind == "sky" else r.triangle_direct_mol
                if len(per_triangle) >= n:
                    todo.append(run)
        if not todo:
            return

        def work(job):
            from maizeviz.light.results.painting import sun_painting
            from maizeviz_app import jobs

            done: list[Any] = []
            for run in todo:
                job.check()
                if run.kind == "sun":
                    absorbed = None if run.extra is None else \
                        jobs.absorbed_of(canopy, run.extra.light)
                    done.append((sun_painting(canopy, run.result), absorbed))
                else:
                    done.append(jobs.diffuse_of(canopy, run.result, run.kind))
            return done

        def adopt(done):
            for run, value in zip(todo, done):
                if run.kind == "sun":
                    run.painting, absorbed = value
                    run.classes = run.painting.classes
                    if absorbed is not None:
                        run.extra = absorbed
                else:
                    run.extra = value
            if self.built is not None and self.signature(self.built.label) == here:
                self.light_panel.show_plants(self._plants_run())
                self._light_to_view(colour=True)
                if self.runner.current("figures") is None:     # else: when they are drawn
                    self.light_shown.emit()

        self.runner.run("complete", "light per leaf of the project's results", work,
                        on_done=adopt, on_error=lambda e: self._fail(e, "light"))

    # ------------------------------------------------------------------ recent files
    def recent_files(self) -> list[str]:
        value: Any = self._settings.value("recent", [])
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
                 "plot": ("Export transmission vs height", "transmission.png", "PNG (*.png)"),
                 "steps": ("Export the day's time steps", "steps.csv", "CSV (*.csv)"),
                 "leaves": ("Export the light per leaf", "leaf_light.csv", "CSV (*.csv)"),
                 "plants": ("Export the light per plant", "plant_light.csv", "CSV (*.csv)"),
                 "day": ("Export the day figure", "day.png", "PNG (*.png)")}
        title, default, filt = names[what]
        path, chosen = QFileDialog.getSaveFileName(self, title, str(Path(self._folder()) /
                                                                     default), filt)
        if not path:
            return
        if "." not in Path(path).name and "(*." in chosen:
            path += chosen.split("(*", 1)[1].split(")")[0]
        self.export(what, path)

    def export(self, what: str, path: str | Path) -> None:
        """Write ``what`` (canopy, table, measures, heatmap, plot; steps, leaves, plants, day
        for a sky or a day) to ``path`` in a worker, atomically."""
        path = str(path)
        try:
            heatmap = (self.plots.kind, dict(self._heatmaps_for), self.plots.shown_height)
            work, args = export_job(what, path, self.model, heatmap)
        except MaizevizError as exc:
            self._fail(exc, "export")
            return

        def done(p):
            self.say(f"exported {p}")
            self.saved.emit(p)

        self.runner.run("export", f"exporting {Path(path).name}", work, *args, on_done=done,
                        on_error=lambda e: self._fail(e, "export"), supersede=False)

    # ------------------------------------------------------------------ help
    def about(self) -> None:
        QMessageBox.about(self, "About maizeviz", about_text())

    # ------------------------------------------------------------------ close
    def closeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        """Stop the reader, cancel and wait for the jobs, kill the core processes, save the
        window's geometry and docks, close the 3D view explicitly. Unsaved work is asked
        about first (:meth:`keep_unsaved`)."""
        if not self._closing and self.digitizer is not None and \
                not self.digitizer.may_close(self):
            event.ignore()
            return
        if not self._closing and not self.keep_unsaved(self.close):
            event.ignore()
            return
        self._closing = True
        try:
            if self.digitizer is not None:
                self.digitizer.stop("window closed", wait=True)
        except Exception as exc:  # noqa: BLE001 - closing must go on
            print(f"maizeviz: the digitizer did not stop cleanly: {exc}", file=sys.stderr)
        self.runner.shutdown(10.0)
        self._settings.setValue("geometry", self.saveGeometry())
        self._settings.setValue("window_state", self.saveState(STATE_VERSION))
        self.workspaces.save()
        self._settings.sync()
        if self.viewport is not None:
            self.viewport.close()
        super().closeEvent(event)


def about_text() -> str:
    return (f"<h3>maizeviz {__version__}</h3>"
            "<p>Digitized maize plants: NURBS leaf surfaces through every digitized point, "
            "meshes of chosen complexity, canopies and direct light.</p>"
            f"<p>It implements the method of: {PAPER}</p>"
            "<p>See docs/method.md for what is computed and how far it follows the paper.</p>")
