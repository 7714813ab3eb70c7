"""The study open in the app, without Qt: its state and settings, and the changes of state
every action ends in (napari's ``ViewerModel`` holds its layers, dims and camera the same way).

:class:`StudyState` holds what the window shows and a project saves (points, layout, canopy,
light results, figures, project), the evented settings the widgets bind to
(:mod:`maizeviz_app.settings`), the colours (:mod:`maizeviz_app.colour`), the selection and the
undo history (:mod:`maizeviz_app.history`), and says what changed through psygnal signals. The
actions that change it (open, build, light, save, export) are functions over it, in
:mod:`maizeviz_app.building`, :mod:`maizeviz_app.lighting` and :mod:`maizeviz_app.studyfiles`;
they import this state and call only its public changes, and this module imports none of them
(:class:`maizeviz_app.model.StudyModel` gathers both as one object for the window and scripts).

What counts as unsaved work (:attr:`StudyState.modified`): an edited layout and light results
not yet in a project. Opening a points file or a project, and saving, start clean; the
digitized points themselves are journalled by the recorder as they arrive and never depend on
saving a project.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from psygnal import Signal, SignalGroup, evented

from maizeviz.errors import MaizevizError
from maizeviz_app.colour import ColourSettings
from maizeviz_app.figures import Figures
from maizeviz_app.history import DraftEdit, History, watch
from maizeviz_app.layout_draft import Change, LayoutDraft
from maizeviz_app.messages import user_message
from maizeviz_app.probe import Probe
from maizeviz_app.runner import InlineRunner, Runner, describe_internal
from maizeviz_app.runs import LightRuns, Run
from maizeviz_app.selection import Selection
from maizeviz_app.settings import StudySettings, field_names
from maizeviz_app.view_state import ViewState

if TYPE_CHECKING:
    from maizeviz.canopy.build import Canopy
    from maizeviz.canopy.layout import CanopyLayout
    from maizeviz_app.jobs import Built, Loaded
    from maizeviz_app.saved_state import StoredRun

#: Settings groups whose edits are undoable (the digitizer's connection is not an edit of the
#: study; the tiling is set by opening, not edited).
UNDOABLE = ("canopy", "light", "sun", "sampling", "sky", "day", "optics", "photosynthesis")
#: The colour settings' groups, by the name the history gives them: the 3D view's scale, the
#: heatmaps' and the rest; undoable too (as ParaView's colour map edits), though they change
#: no result.
COLOUR_GROUPS = ("view colours", "heatmap colours", "colours")
#: Layouts whose light results are kept after an edit (the light panel's undo depth for
#: them; a layout further back is traced again).
KEPT_LAYOUTS = 8
#: What the light panel and the status bar say of results set aside by a layout edit.
SET_ASIDE = ("light results set aside: they belong to the previous layout (Undo, Ctrl+Z, "
             "brings them back; Compute traces this one)")
#: What they say when a layout returns to stands whose results were set aside.
BROUGHT_BACK = "the light results of this layout are back (traced before the edit, not again)"


def stands_key(layout: CanopyLayout) -> tuple[int, str]:
    """What identifies a layout's stands (:func:`maizeviz.canopy.layout.stands_identity`:
    their plants, places, rotations and tiles, in order) as a dictionary key."""
    from maizeviz.canopy.layout import stands_identity

    ident = stands_identity(layout)
    return ident["n"], ident["sha256"]

@evented
@dataclass
class LayoutOptions:
    """How the layout being edited reaches the study (evented: the layout editor binds to it).

    Attributes
    ----------
    follow : every edit of the layout (and its undo) is applied at once, the canopy rebuilt
        on it; off: only when asked (:meth:`maizeviz_app.model.StudyModel.apply_draft`)
    """

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    follow: bool = True


class StudyState:
    """What the window shows and a project saves, and the changes of it.

    Parameters
    ----------
    tile : int
        Tiles along each side of the canopy until a layout is loaded (the app's ``--tile``).
    runner : Runner, optional
        Where jobs run (the window's thread pool); default an :class:`InlineRunner`.

    Attributes
    ----------
    settings : StudySettings
        Canopy, light and digitizer settings (evented; widgets bind to them).
    loaded : maizeviz_app.jobs.Loaded or None
        The points (fitted leaves, plants) and the layout they are arranged in.
    points_bytes : bytes
        The points file as read, saved into a project byte for byte.
    points_origin : str
        Where the points came from (a project's original file), resolved.
    built : maizeviz_app.jobs.Built or None
        The canopy on screen: its level, Embree-ready meshes, Table 2 measures (the last one
        built stays until the canopy of new points or a new layout replaces it).
    measures_rows : dict[str, dict]
        Table 2 rows of every level built on these points and layout, by level label.
    runs : LightRuns
        Light results (sun, sky, day) per level, compared while they share their sampling.
    figures : Figures
        The heatmaps and the transmission plot of the results shown.
    draw_figures : bool
        Draw the figures of each light result (in a job of their own, after it): the window
        sets it, since it shows them; a script leaves it off and pays nothing for them
        (an export draws the figure it writes).
    summary : str
        The day's totals in two lines (empty: no day computed).
    plants_run : Run or None
        The result whose light per plant is shown.
    project_path : str or None
        The ``.maizeviz`` file the study was opened from or saved to.
    draft : LayoutDraft
        The layout being edited (applied by :meth:`apply_layout`).
    layout_edited : bool
        The layout is not the plain tiling of the settings (saved into the project).
    serial : int
        Changes whenever the points or the layout change: a canopy or light result carries
        the serial it was made for, and one made for an older serial is dropped.
    canopy_key : int
        Changes with every canopy shown (the light process keeps the last canopy it was sent
        and its Embree scene, under this key).
    modified : bool
        There is work a project does not hold yet (see the module docstring).
    confirm_slow : callable(str) -> bool
        Asked before starting work estimated at over a quarter of an hour (the window asks
        the user; with no window: no).
    mesher : callable or None
        ``mesher(job, canopy, coarse, from_file)`` makes what the 3D view draws of a canopy,
        in the worker (``coarse()``: the canopy at the view's display level, or None;
        ``from_file``: a canopy read from a mesh file); None: nothing is drawn (no window).
    colour : ColourSettings
        How the 3D view and the heatmaps colour light (evented; saved in a project).
    view : ViewState
        What the 3D view colours the canopy by and the camera preset asked (evented; the
        viewport renders it): the study picks the light once computed and falls back to the
        leaves when the canopy shown has none (:meth:`colour_view_by`).
    selection : Selection
        The plant or leaf selected (evented; the 3D view and the plants table follow it).

    Signals
    -------
    points_changed(loaded) : new points (and layout) opened; results cleared.
    mesh_opened(path) : a canopy read from a mesh file replaces the points; results cleared.
    layout_changed(layout) : the layout edited; results of the previous layout set aside
        (those of this layout's stands, set aside before, back).
    canopy_changed(built) : a canopy built for the current points and layout.
    built_shown(label) : that canopy is shown with the light results it has (a project's
        results adopted).
    build_pending(text) : what is being built ('': nothing, or not built: ``text`` says why).
    runs_changed(runs, info) : a light result added (``info``: what was traced), or cleared.
    light_running(text) : a light computation started ('' : none runs any more).
    light_added(run) : a new light result is in the table (``light_shown`` follows once
        its figures are drawn, when they are).
    light_shown() : the light results shown are complete (table, figures, colours).
    view_light(colour) : the light to paint on the canopy shown changed (``colour``: switch
        the view's colouring to light).
    summary_changed(text), plants_changed(run) : the day's totals, the light per plant.
    project_changed(path) : the study opened from or saved to ``path`` (None: no project).
    project_saved(path), exported(path) : a file written.
    modified_changed(bool) : unsaved work appeared or was saved.
    said(text, error, status_only) : a line for the user.
    failed(text, doing, quantity, mode) : an error the user was told about (``quantity``: the
        setting it is about, ``mode``: the light it was computed for).
    """

    points_changed = Signal(object)
    mesh_opened = Signal(str)
    layout_changed = Signal(object)
    canopy_changed = Signal(object)
    built_shown = Signal(str)
    build_pending = Signal(str)
    runs_changed = Signal(object, str)
    light_running = Signal(str)
    light_added = Signal(object)
    light_shown = Signal()
    view_light = Signal(bool)
    summary_changed = Signal(str)
    plants_changed = Signal(object)
    project_changed = Signal(object)
    project_saved = Signal(str)
    exported = Signal(str)
    modified_changed = Signal(bool)
    said = Signal(str, bool, bool)
    failed = Signal(str, str, object, object)

    def __init__(self, tile: int = 3, runner: Runner | None = None) -> None:
        self.settings = StudySettings()
        self.settings.canopy.tile = tile
        self.runner: Runner = runner if runner is not None else InlineRunner()
        self.loaded: Loaded | None = None
        self.points_bytes = b""
        self.points_origin = ""
        self.built: Built | None = None
        self.measures_rows: dict[str, dict] = {}
        self.runs = LightRuns()
        self.figures = Figures()
        self.draw_figures = False               # the window sets it: it shows them
        self.draft = LayoutDraft()
        self.layout_options = LayoutOptions()
        self.layout_notes: tuple[str, ...] = ()     # the layout's notes already said
        self.summary = ""
        self.plants_run: Run | None = None
        self.pending_runs: list[StoredRun] = []     # a project's results, waiting for a canopy
        #: light results of earlier layouts, by their stands (:func:`stands_key`), the
        #: oldest first: they come back when the layout returns to those stands
        self.runs_set_aside: dict[tuple[int, str], tuple[LightRuns, str]] = {}
        self.brought_back = False           # the runs shown were set aside, not yet drawn
        #: what the last layout edit did to the light results (:data:`SET_ASIDE`,
        #: :data:`BROUGHT_BACK`; '': nothing), until light is computed or points opened
        self.light_note = ""
        self.project_path: str | None = None
        self.mesh_path: str | None = None
        self.layout_edited = False
        self.project_layout = False             # the opening project stores its layout
        self.serial = 0
        self.canopy_key = 0
        self.modified = False
        self.closing = False
        self.cache_folder = str(Path.home() / ".cache" / "maizeviz" / "projects")
        self.confirm_slow: Callable[[str], bool] = lambda estimate: False
        self.mesher: Callable[..., Any] | None = None
        self.applying = 0                       # settings being set by the model itself
        self.colour = ColourSettings()
        self.view = ViewState()
        #: the colouring a project was saved with, restored once its results are complete
        self.colouring_to_restore: str | None = None
        #: what the last result added said it was (the light panel's text)
        self.runs_info = ""
        self.selection = Selection()
        self.probe = Probe()           # a distance or area probe (View > Measure)
        self.history = History()
        self._watch_history()
        self.settings.together = self.history.step      # settings.set: one step
        self.view_light.connect(self._light_colouring)
        self.canopy_changed.connect(lambda _built: self._check_colouring())

    # ------------------------------------------------------------------ reading
    @property
    def canopy(self) -> Canopy | None:
        """The canopy on screen (:class:`maizeviz.canopy.build.Canopy`) or None."""
        return self.built.canopy if self.built is not None else None

    @property
    def tile(self) -> int:
        """The tiling a points file is opened with (``settings.canopy.tile``)."""
        return self.settings.canopy.tile

    @property
    def tile_n(self) -> int:
        """Tiles along each side of the layout (a square tiling), else the starting tiling."""
        from maizeviz_app.options import tiling_of

        tiles = tiling_of(self.loaded.layout) if self.loaded is not None else None
        if tiles is not None and tiles[0] == tiles[1]:
            return tiles[0]
        return self.tile

    def signature(self, label: str) -> tuple[int, str]:
        """What identifies a canopy: the points and layout (serial) and the level label."""
        return (self.serial, label)

    @property
    def shown_signature(self) -> tuple[int, str] | None:
        """The signature of the canopy shown (None: none)."""
        return self.signature(self.built.label) if self.built is not None else None

    @property
    def title(self) -> str:
        """The window title: the project's or points file's name, ``[*]`` where Qt marks
        unsaved work."""
        if self.mesh_path is not None:
            return f"maizeviz — {Path(self.mesh_path).name}[*]"
        if self.loaded is None:
            return "maizeviz"
        name = Path(self.project_path or self.loaded.path).name
        return f"maizeviz — {name}[*]"

    # ------------------------------------------------------------------ messages
    def say(self, text: str, error: bool | None = None, status_only: bool = False) -> None:
        """A line for the user (``error``: default when the line starts with "error")."""
        if self.closing:
            return
        self.said.emit(text, text.startswith("error") if error is None else error,
                       status_only)

    def fail(self, exc: BaseException, doing: str, mode: str | None = None) -> None:
        """An error from an action: one line for people; the traceback on stderr if it is a
        bug (not a MaizevizError, an OSError or a MemoryError)."""
        if self.closing:
            return
        if not isinstance(exc, (MaizevizError, OSError, MemoryError)):
            describe_internal(exc)
        text = user_message(exc, doing)
        self.say(f"error: {text}", error=True)
        self.failed.emit(text, doing, getattr(exc, "quantity", None), mode)

    def affordable(self, stages: list, doing: str) -> bool:
        """Whether to start work estimated as ``stages`` (lists of ``maizeviz.cost.Cost``):
        no, with a message, when it would not fit in this machine's memory; when merely slow,
        as :attr:`confirm_slow` answers."""
        from maizeviz.cost import TooSlow, check

        try:
            check(stages)
        except TooSlow as exc:
            if self.confirm_slow(exc.estimate):
                return True
            self.say(f"not started: {exc.estimate}", status_only=True)
            return False
        except MaizevizError as exc:
            self.fail(exc, doing)
            return False
        return True

    # ------------------------------------------------------------------ changing
    def set_points(self, loaded: Loaded, points_bytes: bytes, origin: str,
                   project: str | None = None, layout_edited: bool = False) -> None:
        """New points (from a points file, or a project at ``project``): every result of the
        previous points is dropped; the study starts unsaved-clean."""
        self.loaded = loaded
        self.mesh_path = None
        self.points_bytes = points_bytes
        self.points_origin = str(Path(origin).resolve())
        self.project_path = project
        self.layout_edited = layout_edited
        self.runs_set_aside.clear()
        self._renew()
        self.draft.start(loaded.layout, loaded.plants)
        self.history.clear()
        self.points_changed.emit(loaded)
        self.project_changed.emit(project)
        self._set_modified(False)

    def set_mesh(self, path: str) -> None:
        """A canopy read from a mesh file (OBJ, PLY with plant and leaf ids) is studied instead
        of digitized points: no points, no layout to edit, one mesh level (the file's); its
        canopy arrives by :meth:`show_built`. Nothing of it goes into a project."""
        self.loaded = None
        self.points_bytes = b""
        self.points_origin = ""
        self.project_path = None
        self.mesh_path = str(path)
        self.layout_edited = False
        self.runs_set_aside.clear()
        self._renew()
        self.draft.start(None, set())
        self.history.clear()
        self.mesh_opened.emit(self.mesh_path)
        self.project_changed.emit(None)
        self._set_modified(False)

    def edit_layout(self, layout: CanopyLayout) -> bool:
        """The layout edited; True if light results were set aside (they belong to the
        previous layout: kept under its stands, they come back when the layout returns to
        those stands, by Undo or by moving a plant back, without tracing again)."""
        if self.loaded is None:
            return False
        before = stands_key(self.loaded.layout)
        kept = self.runs.copy() if self.runs.runs else None
        colouring = self.view.colouring
        self.loaded = replace(self.loaded, layout=layout)
        if tuple(self.draft.placements) != tuple(layout.placements):
            self.draft.start(layout, self.loaded.plants)    # laid out by a script
        self.layout_edited = True
        self._renew()
        if kept is not None:
            self._set_aside(before, (kept, colouring))
        back = self.runs_set_aside.pop(stands_key(layout), None)
        if back is not None:
            self._bring_back(back)
        self.layout_changed.emit(layout)
        self._set_modified(True)
        n = len(layout.placements)
        self.light_note = BROUGHT_BACK if back is not None else \
            SET_ASIDE if kept is not None else ""
        if back is not None:
            self.say(f"layout applied: {n} plants, those its {len(back[0].runs)} light "
                     "result(s) were traced on: they are back")
        elif kept is not None:
            self.runs_info = SET_ASIDE
            self.runs_changed.emit(self.runs, SET_ASIDE)
            self.say(f"layout applied: {n} plants; {SET_ASIDE}")
        else:
            self.say(f"layout applied: {n} plants")
        return kept is not None

    def show_built(self, built: Built) -> bool:
        """A canopy built; False (and nothing changes) if it was built for older points or
        an older layout."""
        if built.serial != self.serial:
            return False
        self.built = built
        self.canopy_key += 1
        self.measures_rows[built.label] = built.row
        self.canopy_changed.emit(built)
        self.build_pending.emit("")
        return True

    def add_run(self, run: Run, settings: Any, sampling: Any, info: str = "", *,
                saved: bool = False) -> bool:
        """Keep a light result (``info``: what was traced; ``saved``: read from the project,
        not new work); True if it replaced results traced with other settings. A result for
        older points or layout is ignored (False)."""
        if run.signature[0] != self.serial:
            return False
        dropped = self.runs.add(run, settings, sampling)
        self.runs_info = info
        self.light_note = ""
        self.runs_changed.emit(self.runs, info)
        if not saved:
            self._set_modified(True)
        return dropped

    def mark_saved(self, path: str) -> None:
        """The study was written to ``path``."""
        self.project_path = path
        self.project_changed.emit(path)
        self._set_modified(False)

    def set_summary(self, text: str) -> None:
        if text != self.summary:
            self.summary = text
            self.summary_changed.emit(text)

    def set_plants_run(self, run: Run | None) -> None:
        self.plants_run = run
        self.plants_changed.emit(run)

    @contextmanager
    def quietly(self) -> Iterator[None]:
        """Settings set by the model itself (a project read, a level refused): no rebuild,
        no undo step (:attr:`applying` is not 0 meanwhile)."""
        self.applying += 1
        try:
            yield
        finally:
            self.applying -= 1

    def apply_settings(self, name: str, values: dict[str, Any]) -> None:
        """Set a settings group from the model itself (see :meth:`quietly`)."""
        with self.quietly():
            self.settings.set(name, values)

    # ------------------------------------------------------------------ the view
    def can_colour(self, what: str) -> bool:
        """Whether the canopy shown can be coloured by ``what`` (light and assimilation need
        a result of it: a sun's classes or light per leaf; a leaf model's CO2)."""
        ViewState.check_colouring(what)
        if what in ("plant", "leaf"):
            return True
        run = self.runs.latest(self.shown_signature) if self.built is not None else None
        if run is None:
            return False
        if what == "light":
            return run.classes is not None or \
                getattr(run.extra, "leaf_value", None) is not None
        return getattr(run.extra, "gross_value", None) is not None

    def colour_view_by(self, what: str) -> bool:
        """Colour the canopy shown by ``what`` (the View menu, a script); False, and said
        why, when the canopy shown has no such result."""
        if not self.can_colour(what):
            self.say("no CO₂ assimilation for the canopy shown: trace a sun with leaf optics "
                     "(PAR) and a photosynthesis model in the Light panel"
                     if what == "assimilation" else
                     "no light result for the canopy shown: compute direct light first "
                     "(Ctrl+L)")
            return False
        self.view.colouring = what
        return True

    def _light_colouring(self, colour: bool) -> None:
        """New light on the canopy shown: coloured by it (``colour``) unless by its CO2."""
        if colour and self.view.colouring != "assimilation" and self.can_colour("light"):
            self.view.colouring = "light"
        else:
            self._check_colouring()

    def _check_colouring(self) -> None:
        """A colouring the canopy shown cannot have falls back: CO2 to light, light to the
        leaves."""
        what = self.view.colouring
        if what == "assimilation" and not self.can_colour(what):
            what = "light"
        if what == "light" and not self.can_colour(what):
            what = "leaf"
        self.view.colouring = what

    # ------------------------------------------------------------------ history
    def edit_groups(self) -> dict[str, Any]:
        """The groups whose edits the history records, by the name it gives them."""
        c = self.colour
        groups = {name: self.settings.groups[name] for name in UNDOABLE}
        groups.update(zip(COLOUR_GROUPS, (c.view, c.heatmap, c)))
        return groups

    def _watch_history(self) -> None:
        groups = self.edit_groups()

        def apply(group: str, name: str, value: Any) -> None:
            target = groups[group]
            if group in UNDOABLE:
                value = self.settings.check(group, name, value)
            setattr(target, name, value)

        def skip() -> bool:
            return bool(self.applying or self.closing)

        for name, group in groups.items():
            fields = [f for f in field_names(group) if (name, f) != ("canopy", "tile")]
            watch(self.history, name, group, fields, apply, skip)
        self.draft.edited.connect(self._draft_edited)

    def _draft_edited(self, change: Change, text: str, merge: Any) -> None:
        if not self.closing:
            self.history.record(DraftEdit(change, text, merge, self.draft.replay))

    # ------------------------------------------------------------------ inside
    def _set_aside(self, key: tuple[int, str], kept: tuple[LightRuns, str]) -> None:
        """Keep the light results of the stands ``key`` and the 3D view's colouring with
        them (the last few layouts')."""
        self.runs_set_aside.pop(key, None)
        self.runs_set_aside[key] = kept
        while len(self.runs_set_aside) > KEPT_LAYOUTS:
            self.runs_set_aside.pop(next(iter(self.runs_set_aside)))

    def _bring_back(self, kept: tuple[LightRuns, str]) -> None:
        """The light results traced on the stands the layout is back to: the same results
        (the same objects, not traced again), signed for the current serial; shown whole
        (heatmaps, plants, colours) once the canopy is built
        (:func:`maizeviz_app.lighting.show_brought_back`)."""
        runs, self.colouring_to_restore = kept
        for run in runs.runs.values():
            run.signature = self.signature(run.label)
        self.runs.take(runs)
        self.brought_back = True
        self.runs_info = BROUGHT_BACK
        self.runs_changed.emit(self.runs, BROUGHT_BACK)

    def _renew(self) -> None:
        self.serial += 1
        self.brought_back = False
        self.light_note = ""
        self.runs_info = ""
        self.measures_rows.clear()
        self.runs.clear()
        self.figures.clear()
        self.set_summary("")
        self.set_plants_run(None)
        self.runs_changed.emit(self.runs, "")

    def _set_modified(self, value: bool) -> None:
        if value != self.modified:
            self.modified = value
            self.modified_changed.emit(value)
