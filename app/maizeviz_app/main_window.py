"""The maizeviz main window: the canopy in 3D, the mesh-complexity slider with Table 2, light
with its table and figures, the layout editor and the digitizer.

The window only wires: the study (:class:`maizeviz_app.model.StudyModel`) holds the state and
the settings and runs every action (open, build, light, save, export); the panels bind to its
settings and follow its signals; the window connects them, asks the questions only a window
can ask (file dialogs, unsaved work, a long computation), and keeps the 3D view in step.

How it stays responsive:

- The window shows before anything heavy is imported: pyvista, VTK, matplotlib and most of the
  core are imported by a warm-up thread once the window is on screen; then the 3D view is made
  and the points file opened.
- Every computation runs on a worker thread (:mod:`maizeviz_app.workers`); the Embree work
  (ground cover, light), which holds the GIL inside embreex, runs in child processes
  (:mod:`maizeviz_app.process`). The GUI thread only swaps in results: a new canopy's mesh is
  prepared by the worker (:mod:`maizeviz_app.view_mesh`), the figures are drawn by the worker.
- The 3D view renders once per change and never when idle (:mod:`maizeviz_app.viewport`).
- The 3D view follows the study (:mod:`maizeviz_app.view_link`); while the digitizer
  records, it keeps the plant being digitized and a canopy built meanwhile waits.

Errors go to the status bar and the Messages panel as one line for people
(:mod:`maizeviz_app.messages`), never as a modal box that would stop a technician in the field;
an error about one light setting also marks that field.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QSettings, Qt, QTimer, QUrl, Signal
from PySide6.QtGui import QDesktopServices, QKeySequence
from PySide6.QtWidgets import QLabel, QMainWindow, QMessageBox, QStackedWidget, QUndoView

from maizeviz import __version__
from maizeviz.mesh.levels import COMPLEXITY_STOPS as LEVELS  # noqa: F401 - the slider's stops
from maizeviz.resources import example_points
from maizeviz_app import dialogs, docks
from maizeviz_app.accessible import name_controls
from maizeviz_app.bind import bind, bind_text
from maizeviz_app.model import StudyModel
from maizeviz_app.panels.canopy import CanopyPanel
from maizeviz_app.panels.light import LightPanel, LightPlots
from maizeviz_app.undo import UndoRecorder
from maizeviz_app.view_link import ViewLink
from maizeviz_app.workers import JobRunner, describe_internal

if TYPE_CHECKING:
    from maizeviz_app.panels.digitizer import DigitizerPanel
    from maizeviz_app.panels.layout import LayoutPanel
    from maizeviz_app.viewport import Viewport

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
              "maizeviz.light.report.heatmap", "maizeviz.canopy.export", "maizeviz_app.saved_state",
              "scipy.spatial")))
#: The jobs the status bar names while they run (and Cancel stops).
SHOWN_JOBS = ("load", "build", "light", "open", "save", "export")


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
        self.setAcceptDrops(True)          # points, projects and meshes dropped open
        self._closing = False
        self._settings = QSettings("maizeviz", "maizeviz")
        self.runner = JobRunner(self)
        self.model = StudyModel(tile, self.runner)
        self.model.draw_figures = True    # the window shows them (a script draws none)
        self.undo = UndoRecorder(self.model, self)
        self.viewport: Viewport | None = None
        self.view_link = ViewLink(self)
        self._after_save = None           # what to do once the project is saved (close, open)
        self._progress_shown = 0.0
        self._view_ready = threading.Event()  # the build job waits for it before meshing
        # the threads this window starts (warm-up, core processes): they end with it
        self._threads: list[threading.Thread] = []
        self._threads_stop = threading.Event()
        self._wire_model()

        self._centre = QStackedWidget()
        self._centre.setMinimumSize(320, 200)
        self._centre.addWidget(QLabel("starting the 3D view…",
                                      alignment=Qt.AlignmentFlag.AlignCenter))
        docks.own_window(self._centre)
        self.setCentralWidget(self._centre)
        self._build_panels()
        self.job_label, self.cancel_button = docks.status_widgets(self)
        self.cancel_button.clicked.connect(lambda: self.cancel_jobs())
        from maizeviz_app.menus import build_menus
        from maizeviz_app.workspaces import Workspaces

        self.workspaces = Workspaces(self, self._settings, docks.STATE_VERSION,
                                     sizes=lambda: docks.default_sizes(self))
        self.workspaces.changed.connect(self.view_link.workspace_changed)
        self.light_shown.connect(lambda: None if self.view_link.digitizing else
                                 self.workspaces.show("analyse"))

        self.menu_actions = build_menus(self)
        name_controls(self)
        self._state_restored = docks.restore_window(self, self._settings)
        self._to_open = str(points) if points is not None else self._last_opened()
        self._warmed.connect(self._on_warmed)
        QTimer.singleShot(0, self._warm_up)

    # ------------------------------------------------------------------ wiring
    def _wire_model(self) -> None:
        """The study's signals to the window, its questions to dialogs."""
        m = self.model
        m.confirm_slow = lambda estimate: dialogs.confirm_slow(self, estimate)
        m.cache_folder = dialogs.cache_folder()
        ready = self._view_ready

        def mesher(job, canopy, coarse, from_file=False):
            from maizeviz_app.view_mesh import view_mesh

            return view_mesh(job, canopy, coarse, ready, from_file)

        m.mesher = mesher
        m.modified_changed.connect(lambda on: self.setWindowModified(on))
        m.project_changed.connect(lambda _p: self.setWindowTitle(m.title))
        m.points_changed.connect(self._on_points)
        m.mesh_opened.connect(self._on_mesh)
        m.built_shown.connect(lambda label: self.canopy_shown.emit(label))
        m.said.connect(self.say)
        m.failed.connect(self._on_failed)
        m.light_running.connect(self._on_light_running)
        m.light_added.connect(lambda _run: self.docks["results"].raise_())
        m.light_shown.connect(lambda: self.light_shown.emit())
        m.project_saved.connect(self._on_saved)
        m.exported.connect(lambda path: self.saved.emit(path))
        self.runner.progressed.connect(self._on_progress)
        self.runner.changed.connect(self._on_jobs_changed)

    def _build_panels(self) -> None:
        m = self.model
        self.canopy_panel = CanopyPanel(m)
        self.canopy_panel.open_requested.connect(self.choose_points)
        self.light_panel = LightPanel(m)
        self.light_panel.compute_requested.connect(m.compute_light)
        self.light_panel.cancel_requested.connect(lambda: self.cancel_jobs("light"))
        self.light_panel.place_requested.connect(m.sun_from_place)
        self.light_panel.export_requested.connect(self.choose_export)
        m.summary_changed.connect(self.light_panel.show_summary)
        m.plants_changed.connect(self.light_panel.show_plants)
        # the layout editor and the digitizer import much of the core: they are made once the
        # window is on screen (see _make_late_panels)
        self.layout_panel: LayoutPanel | None = None
        self.digitizer: DigitizerPanel | None = None
        self.plots = LightPlots()
        self._wire_figures()
        from maizeviz_app.panels.colour import ColourPanel

        self.colour_panel = ColourPanel(m.colour, step=m.history.step)
        self.plots.heatmap.limits_shown.connect(self.colour_panel.heatmap_editor.show_limits)
        from maizeviz_app.panels.instruments import InstrumentsPanel

        self.instruments_panel = InstrumentsPanel(canopy=lambda: m.canopy)
        self.instruments_panel.failed.connect(lambda text: self.say(f"error: {text}"))
        m.built_shown.connect(lambda _label: self.instruments_panel.refresh())
        self.messages = docks.messages_widget()
        self.history = QUndoView(self.undo.stack)
        self.history.setEmptyLabel("the study as opened")
        self.history.setAccessibleName("undo history")
        self.history.setToolTip("every edit of this study; click one to go back to it")
        self.docks = docks.make_docks(self, {"canopy": ("Canopy", self.canopy_panel),
                                             "light": ("Light", self.light_panel),
                                             "layout": ("Layout", None),
                                             "digitizer": ("Digitizer", None),
                                             "colour": ("Colour", self.colour_panel),
                                             "instruments": ("Instruments",
                                                             self.instruments_panel)},
                                      self.plots, self.messages, self.history)

    def _wire_figures(self) -> None:
        f, plots = self.model.figures, self.plots

        def maps_changed(kind: str) -> None:
            if kind:
                plots.set_heatmaps(f.maps[kind], kind)
            elif not f.maps:
                plots.clear()
            else:
                plots.keep_only(set(f.maps))

        def shown(*_args) -> None:
            f.shown_kind, f.shown_index = plots.kind, plots.height_box.currentIndex()

        f.maps_changed.connect(maps_changed)
        f.restyled.connect(lambda keep, hold: plots.redraw(keep=keep, hold=hold))
        colour = self.model.colour                  # new colours: the maps drawn again
        colour.heatmap.events.connect(lambda _info: self._restyle())
        colour.events.shared.connect(lambda _on: self._restyle())
        f.map_drawn.connect(lambda kind, index, rgba: plots.set_heatmap(index, rgba, kind))
        f.plot_changed.connect(plots.set_transmission)
        plots.heatmap_needed.connect(self.model.draw_heatmap)
        plots.source.currentIndexChanged.connect(shown)
        plots.height_box.currentIndexChanged.connect(shown)
        # figures drawn at the size they are shown (their texts keep their points)
        from maizeviz_app.figures import Canvas

        for which, view in (("heatmap", plots.heatmap), ("plot", plots.transmission)):
            view.canvas_resized.connect(
                lambda w, h, dpi, which=which: f.set_canvas(which, Canvas(w, h, dpi)))

    def _restyle(self) -> None:
        """The heatmaps' colours changed: every map is drawn again (the one shown at once)."""
        self.model.figures.restyle()

    def showEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        docks.first_show(self, self._state_restored)

    def show_history(self) -> None:
        """The undo history (Edit > Undo history)."""
        dock = self.docks["history"]
        dock.show()
        dock.raise_()

    def reset_layout(self) -> None:
        """Docks back to where they are on a first start."""
        docks.reset(self)

    # ------------------------------------------------------------------ start-up
    def _warm_up(self) -> None:
        """Import the heavy modules off the GUI thread, stage by stage (see WARM_STAGES)."""
        if self._closing:
            return
        self.say("starting: loading the core and the 3D view…", status_only=True)
        warmed, view_ready, stop = self._warmed, self._view_ready, self._threads_stop

        def work():
            import importlib

            for stage, names in WARM_STAGES:
                error = None
                try:
                    for name in names:
                        if stop.is_set():       # the window is closing: import no more
                            return
                        importlib.import_module(name)
                except Exception as exc:  # noqa: BLE001 - reported in the window
                    error = exc
                if stop.is_set():               # closeEvent waits for this thread: the
                    return                      # window still exists, but says nothing more
                try:
                    warmed.emit(stage, error)
                except RuntimeError:            # the window is gone
                    return
                if stage == "view":
                    view_ready.set()
                if error is not None:
                    return

        self._start_thread(work, "maizeviz-warm-up")

    def _start_thread(self, target, name: str) -> None:
        """Start a thread that :meth:`closeEvent` waits for."""
        if self._closing:
            return
        t = threading.Thread(target=target, name=name, daemon=True)
        self._threads.append(t)
        t.start()

    def _end_threads(self, timeout: float = 60.0) -> None:
        """Tell this window's threads to stop and wait for them (an import under way
        finishes first: one left running at exit can touch Qt, or import, while the
        interpreter shuts down)."""
        self._threads_stop.set()
        deadline = time.monotonic() + timeout
        for t in self._threads:
            t.join(max(0.0, deadline - time.monotonic()))
        self._threads = [t for t in self._threads if t.is_alive()]

    def _on_warmed(self, stage: str, error) -> None:
        if self._closing:
            return
        if error is not None:
            describe_internal(error)
            self.say(f"error: the app cannot start ({error}); reinstall maizeviz with its gui "
                     "extra: pip install \"maizeviz[gui]\"", error=True)
            return
        if stage == "core":
            self._start_thread(self._start_processes, "maizeviz-processes")
            if self._to_open:
                self.open_any(self._to_open)
        elif stage == "view":
            from maizeviz_app.viewport import Viewport

            # made in its place: a QOpenGLWidget made as a child of the main window itself makes
            # Qt compose the whole window again (see docks.own_window), and re-laying it out
            # then gives the docks all the room but the view's minimum height
            self.viewport = Viewport(self._centre)
            self.viewport.set_colour_scale(self.model.colour.view)
            self.viewport.limits_shown.connect(self.colour_panel.view_editor.show_limits)
            self.view_link.attach(self.viewport)
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

    def _restore_connection(self) -> None:
        """The digitizer's port and baud of the last connection (QSettings) into the study's
        settings; a stored value the settings refuse leaves the default."""
        from maizeviz_app.settings import InputProblem

        for name in ("port", "baud"):
            stored = self._settings.value(name)
            if stored is None:
                continue
            try:
                value = int(str(stored)) if name == "baud" else str(stored)
                self.model.apply_settings("digitizer", {name: value})
            except (InputProblem, ValueError):
                pass                             # the default stays

    def _make_late_panels(self) -> None:
        from maizeviz_app.panels.digitizer import DigitizerPanel
        from maizeviz_app.panels.layout import LayoutPanel

        self.layout_panel = LayoutPanel(self.model, self.undo.stack)
        self.layout_panel.problem.connect(self.say)
        self.digitizer = DigitizerPanel(self.viewport, session=self.model.digitizing)
        self.digitizer.alert.connect(lambda text: self.say(text, error=True, status_only=True))
        self.digitizer.stopped.connect(self.view_link.digitizing_stopped)
        self.digitizer.started.connect(self.view_link.digitizing_started)
        # the study's digitizer settings are the connection last used (the window keeps it);
        # the panel's port and baud show them and set them
        d, settings = self.digitizer, self.model.settings.digitizer
        self._restore_connection()
        bind(d.baud, settings, "baud")
        bind_text(d.ports.box, settings, "port")
        d.ports.baud = settings.baud            # what Find FASTRAK probes at, as the box
        settings.events.baud.connect(lambda baud, *_: setattr(d.ports, "baud", baud))
        self.docks["layout"].setWidget(docks.scrolled(self.layout_panel))
        self.docks["digitizer"].setWidget(docks.scrolled(self.digitizer))
        name_controls(self)

    def _start_processes(self) -> None:
        for proc in (self.runner.cover_process, self.runner.light_process):
            try:
                proc.start()
            except (InterruptedError, OSError, RuntimeError):
                return

    def _last_opened(self) -> str:
        path = self._settings.value("last_opened")
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
        bar.showMessage(docks.status_line(bar, text, bool(error)), 15000 if error else 8000)

    def _on_failed(self, text: str, doing: str, quantity, mode) -> None:
        """An error the study said: a light setting's field is marked, a save that failed
        lets nothing close or open over unsaved work."""
        if self._closing:
            return
        if doing == "save project":
            self._after_save = None
        if self.light_panel.show_failure(text, doing, quantity, mode):
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

    def open_points(self, path: str | Path, layout=None) -> None:
        """Open a points file, once unsaved work is saved or discarded."""
        if self.keep_unsaved(lambda: self.open_points(path, layout)):
            self.model.open_points(path, layout)

    def open_project(self, path: str | Path) -> None:
        """Open a project, once unsaved work is saved or discarded."""
        if self.keep_unsaved(lambda: self.open_project(path)):
            self.model.open_project(path)

    def open_mesh(self, path: str | Path, unit: str | None = None, up: str = "z",
                  field: str | tuple[float, float, float, float] | None = None) -> None:
        """Open a canopy mesh (see ``StudyModel.open_mesh``), once unsaved work is saved or
        discarded."""
        if self.keep_unsaved(lambda: self.open_mesh(path, unit, up, field)):
            self.model.open_mesh(path, unit, up, field)

    def choose_points(self) -> None:
        path = dialogs.open_file(self, "points")
        if path:
            self.open_points(path)

    def choose_project(self) -> None:
        path = dialogs.open_file(self, "project")
        if path:
            self.open_project(path)

    def choose_mesh(self) -> None:
        """Open a canopy from elsewhere (OpenAlea, Helios, a scan), asking its units, up axis
        and field."""
        chosen = dialogs.choose_mesh(self)
        if chosen is not None:
            self.open_mesh(*chosen)

    def folder(self) -> str:
        return str(self._settings.value("last_folder", str(Path.home())))

    def keep_unsaved(self, then) -> bool:
        """True when the caller may go on: nothing is unsaved, or the user discards it. Save
        saves the project (asking where, the first time) and calls ``then()`` once it is
        written; Cancel (or a save that does not happen) stops."""
        if not self.model.modified or not self.confirm_unsaved or self._closing:
            return True
        answer = dialogs.ask_unsaved(self, self.model.project_path)
        if answer == QMessageBox.StandardButton.Discard:
            return True
        if answer == QMessageBox.StandardButton.Save:
            self._after_save = then
            self.save_project_here()
            if self.runner.current("save") is None:   # the save dialog was cancelled
                self._after_save = None
        return False

    def _on_points(self, loaded) -> None:
        self.setWindowTitle(self.model.title)
        opened = self.model.project_path or loaded.path
        if loaded.path != str(example_points()) or self.model.project_path:
            self._settings.setValue("last_opened", opened)
            self._remember(opened)
        self._settings.setValue("last_folder", str(Path(opened).parent))

    def _on_mesh(self, path: str) -> None:
        self.setWindowTitle(self.model.title)
        self._settings.setValue("last_folder", str(Path(path).parent))
        self._remember(path)

    # ------------------------------------------------------------------ view
    def step_level(self, step: int) -> None:
        s = self.canopy_panel.slider
        s.setValue(max(s.minimum(), min(s.maximum(), s.value() + step)))

    def camera(self, name: str) -> None:
        self.view_link.camera(name)

    def colour_by(self, what: str) -> None:
        self.view_link.colour_by(what)

    # ------------------------------------------------------------------ jobs
    def _on_light_running(self, text: str) -> None:
        panel = self.light_panel
        panel.set_running(bool(text))
        if text:
            panel.clear_problem()
            panel.set_progress(text)
            self.docks["light"].raise_()

    def cancel_jobs(self, kind: str | None = None) -> None:
        """Stop the light computation and rebuilds under way (Esc)."""
        self.model.cancel(kind)

    def _on_progress(self, _job_id: int, kind: str, label: str, done: int, total: int) -> None:
        # each repaint recomposes the window (see docks.status_widgets): twice a second at most
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
        running = [j for j in self.runner.running() if j.kind in SHOWN_JOBS]
        text = ", ".join(j.label for j in running) + ("…" if running else "")
        if self.job_label.text() != text:
            self.job_label.setText(text)
        if self.cancel_button.isEnabled() != bool(running):
            self.cancel_button.setEnabled(bool(running))
        if not any(j.kind == "light" for j in running):
            self.light_panel.set_running(False)

    # ------------------------------------------------------------------ projects, exports
    def choose_project_target(self) -> None:
        path = dialogs.save_project_file(self, self.model.project_path)
        if path:
            self.model.save_project(path)

    def save_project_here(self) -> None:
        if self.model.project_path:
            self.model.save_project(self.model.project_path)
        else:
            self.choose_project_target()

    def _on_saved(self, path: str) -> None:
        self._settings.setValue("last_opened", path)
        self._remember(path)
        self.saved.emit(path)
        then, self._after_save = self._after_save, None
        if then is not None:
            then()

    def choose_export(self, what: str) -> None:
        path = dialogs.export_file(self, what)
        if path:
            self.model.export(what, path)

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

    # ------------------------------------------------------------------ help, close
    def about(self) -> None:
        QMessageBox.about(self, "About maizeviz", about_text())

    def save_window_image(self, path: str | Path) -> bool:
        """The whole window as it is on screen (panels, figures, the 3D view) as a PNG."""
        ok = self.grab().save(str(path), "PNG")
        self.say(f"saved the window as {path}" if ok else
                 f"error: {path}: the image cannot be written", error=not ok)
        return ok

    def choose_window_image(self) -> None:
        from PySide6.QtWidgets import QFileDialog

        path, _ = QFileDialog.getSaveFileName(self, "Save the window as an image",
                                              str(Path(self.folder()) / "maizeviz.png"),
                                              "PNG (*.png)")
        if path:
            self.save_window_image(path)

    # ------------------------------------------------------------------ drops
    def dragEnterEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if self._dropped_path(event.mimeData()) is not None:
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802 - Qt's name
        """A points file, a project or a canopy mesh dropped on the window opens as File >
        Open would open it (unsaved work asked about first)."""
        path = self._dropped_path(event.mimeData())
        if path is not None:
            event.acceptProposedAction()
            self.open_any(path)

    @staticmethod
    def _dropped_path(mime) -> str | None:
        """The first local file of a drop that maizeviz opens, None for anything else."""
        if not mime.hasUrls():
            return None
        for url in mime.urls():
            path = url.toLocalFile()
            if path and Path(path).suffix.lower() in OPENABLE:
                return path
        return None

    def show_shortcuts(self) -> None:
        """Help > Keyboard shortcuts: every menu action's keys."""
        QMessageBox.information(self, "Keyboard shortcuts",
                                shortcuts_text(self.menu_actions.values()))

    def show_system_info(self) -> None:
        """Help > System information: ``maizeviz --info``, selectable, for a bug report."""
        from maizeviz.info import report

        box = QMessageBox(self)
        box.setWindowTitle("System information")
        box.setText("What <code>maizeviz --info</code> prints: paste it into a bug report.")
        box.setDetailedText(report())
        box.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        box.open()
        self.info_box = box

    def open_docs(self) -> None:
        """Help > Documentation: the docs folder's index in the system's viewer."""
        docs = docs_folder()
        if docs is None:
            self.model.say("note: the documentation is in the docs/ folder of maizeviz's "
                           "source; this installation has no copy")
            return
        QDesktopServices.openUrl(QUrl.fromLocalFile(str(docs / "README.md")))

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
        self.model.closing = True
        try:
            if self.digitizer is not None:
                self.digitizer.stop("window closed", wait=True)
        except Exception as exc:  # noqa: BLE001 - closing must go on
            import sys

            print(f"maizeviz: the digitizer did not stop cleanly: {exc}", file=sys.stderr)
        self.instruments_panel.shutdown()
        self.runner.shutdown(10.0)
        self._end_threads()
        self.workspaces.save()
        docks.save_window(self, self._settings)
        if self.viewport is not None:
            self.viewport.close()
        super().closeEvent(event)


#: What a file dropped on the window may be: points, a project, a canopy mesh.
OPENABLE = (".csv", ".txt", ".parquet", ".pq", ".maizeviz", ".ply", ".obj")


def about_text() -> str:
    """What the Help menu's About says: the version, what maizeviz does, the paper, the
    libraries it runs on (with their versions) and where its documentation is."""
    from maizeviz.info import info

    d = info()
    packages: dict[str, Any] = dict(d["packages"])            # type: ignore[call-overload]
    optional: dict[str, Any] = dict(d["optional"])            # type: ignore[call-overload]
    libs = {**packages, **{k: v for k, v in optional.items() if v and v != "not installed"}}
    libraries = ", ".join(f"{name} {version}" for name, version in libs.items())
    docs = docs_folder()
    where = (f"<a href='{docs.as_uri()}'>{docs}</a> (Help &gt; Documentation)" if docs else
             "the docs/ folder of maizeviz's source")
    return (f"<h3>maizeviz {__version__}</h3>"
            "<p>Digitized maize plants: NURBS leaf surfaces through every digitized point, "
            "meshes of chosen complexity, canopies, and light: sun, sky and whole days with "
            "leaf optics and scattering, the leaves' CO₂ assimilation, virtual field "
            "instruments.</p>"
            f"<p>It implements, and goes beyond, the method of: {PAPER}</p>"
            f"<p><b>Libraries</b>: {libraries}; Embree {d['embree']} (embreex "
            f"{d['embreex']}), ray kernel: {d['kernel']}.</p>"
            f"<p><b>Documentation</b>: {where}; method.md says what is computed and how far "
            "it follows the paper, cli.md every command, app.md this window.</p>")


def docs_folder() -> Path | None:
    """The documentation beside the installed package (a source checkout or an editable
    install), or None."""
    import maizeviz

    here = Path(maizeviz.__file__).resolve().parents[1] / "docs"
    return here if (here / "README.md").is_file() else None


def shortcuts_text(actions) -> str:
    """Every menu action with a keyboard shortcut, as an HTML table (Help > Keyboard
    shortcuts)."""
    rows = []
    for act in actions:
        keys = act.shortcut().toString(QKeySequence.SequenceFormat.NativeText)
        if keys:
            rows.append((act.text().replace("&", "").rstrip("…"), keys))
    rows.sort(key=lambda r: r[0].lower())
    body = "".join(f"<tr><td>{name}</td><td><b>{keys}</b></td></tr>" for name, keys in rows)
    return ("<table cellspacing='6'>" + body + "</table><p>Ctrl+Z and Ctrl+Shift+Z undo and "
            "redo from anywhere in the window; Delete removes the plant picked in the layout "
            "editor.</p>")
