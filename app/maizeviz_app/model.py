"""The study open in the window, without Qt: points, layout, canopy, light results, project.

The window and its panels share one :class:`StudyModel`. The model holds the state and says
when it changes (psygnal signals, as napari's ``ViewerModel``); panels take the model and
follow it (as napari's ``QtDims(dims)`` takes ``Dims``); the window only wires the model to
the panels, the workers and the menus. Everything here runs on the GUI thread, and can be
driven and checked from a test or a script without a window::

    model = StudyModel()
    model.modified_changed.connect(print)
    model.open_points(loaded, data, origin)          # a points file read by the core
    model.edit_layout(layout)                        # True: the edit dropped light results

What counts as unsaved work (:attr:`StudyModel.modified`): an edited layout and light results
not yet in a project. Opening a points file or a project, and saving, start clean; the
digitized points themselves are journalled by the recorder as they arrive and never depend on
saving a project.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from psygnal import Signal

from maizeviz_app.colour import ColourSettings
from maizeviz_app.runs import LightRuns, Run
from maizeviz_app.selection import Selection


class StudyModel:
    """What the window shows and a project saves.

    Parameters
    ----------
    tile : int
        Tiles along each side of the canopy until a layout is loaded (the app's ``--tile``).

    Attributes
    ----------
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
    project_path : str or None
        The ``.maizeviz`` file the study was opened from or saved to.
    layout_edited : bool
        The layout is not the plain tiling of the settings (saved into the project).
    serial : int
        Changes whenever the points or the layout change: a canopy or light result carries
        the serial it was made for, and one made for an older serial is dropped.
    modified : bool
        There is work a project does not hold yet (see the module docstring).
    colour : ColourSettings
        How the 3D view and the heatmaps colour light (evented; saved in a project).
    selection : Selection
        The plant or leaf selected (evented; the 3D view and the plants table follow it).

    Signals
    -------
    points_changed(loaded) : new points (and layout) opened; results cleared.
    mesh_opened(path) : a canopy read from a mesh file replaces the points; results cleared.
    layout_changed(layout) : the layout edited; results of the previous layout cleared.
    canopy_changed(built) : a canopy built for the current points and layout.
    runs_changed(runs, info) : a light result added (``info``: what was traced, for the
        light panel), or results cleared.
    project_changed(path) : the study opened from or saved to ``path`` (None: no project).
    modified_changed(bool) : unsaved work appeared or was saved.
    """

    points_changed = Signal(object)
    mesh_opened = Signal(str)
    layout_changed = Signal(object)
    canopy_changed = Signal(object)
    runs_changed = Signal(object, str)
    project_changed = Signal(object)
    modified_changed = Signal(bool)

    def __init__(self, tile: int = 3) -> None:
        self.tile = tile
        self.loaded: Any = None
        self.points_bytes = b""
        self.points_origin = ""
        self.built: Any = None
        self.measures_rows: dict[str, dict] = {}
        self.runs = LightRuns()
        self.project_path: str | None = None
        self.mesh_path: str | None = None
        self.layout_edited = False
        self.serial = 0
        self.modified = False
        self.colour = ColourSettings()
        self.selection = Selection()

    # ------------------------------------------------------------------ reading
    @property
    def canopy(self) -> Any:
        """The canopy on screen (:class:`maizeviz.canopy.scene.Canopy`) or None."""
        return self.built.canopy if self.built is not None else None

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
    def title(self) -> str:
        """The window title: the project's or points file's name, ``[*]`` where Qt marks
        unsaved work."""
        if self.mesh_path is not None:
            return f"maizeviz — {Path(self.mesh_path).name}[*]"
        if self.loaded is None:
            return "maizeviz"
        name = Path(self.project_path or self.loaded.path).name
        return f"maizeviz — {name}[*]"

    # ------------------------------------------------------------------ changing
    def open_points(self, loaded: Any, points_bytes: bytes, origin: str,
                    project: str | None = None, layout_edited: bool = False) -> None:
        """New points (from a points file, or a project at ``project``): every result of the
        previous points is dropped; the study starts unsaved-clean."""
        self.loaded = loaded
        self.mesh_path = None
        self.points_bytes = points_bytes
        self.points_origin = str(Path(origin).resolve())
        self.project_path = project
        self.layout_edited = layout_edited
        self._renew()
        self.points_changed.emit(loaded)
        self.project_changed.emit(project)
        self._set_modified(False)

    def open_mesh(self, path: str) -> None:
        """A canopy read from a mesh file (OBJ, PLY with plant and leaf ids) is studied instead
        of digitized points: no points, no layout to edit, one mesh level (the file's); its
        canopy arrives by :meth:`show_built`. Nothing of it goes into a project."""
        self.loaded = None
        self.points_bytes = b""
        self.points_origin = ""
        self.project_path = None
        self.mesh_path = str(path)
        self.layout_edited = False
        self._renew()
        self.mesh_opened.emit(self.mesh_path)
        self.project_changed.emit(None)
        self._set_modified(False)

    def edit_layout(self, layout: Any) -> bool:
        """The layout edited in the layout panel; True if light results were dropped."""
        if self.loaded is None:
            return False
        dropped = bool(self.runs.runs)
        self.loaded = replace(self.loaded, layout=layout)
        self.layout_edited = True
        self._renew()
        self.layout_changed.emit(layout)
        self._set_modified(True)
        return dropped

    def show_built(self, built: Any) -> bool:
        """A canopy built; False (and nothing changes) if it was built for older points or
        an older layout."""
        if built.serial != self.serial:
            return False
        self.built = built
        self.measures_rows[built.label] = built.row
        self.canopy_changed.emit(built)
        return True

    def add_run(self, run: Run, settings: Any, sampling: Any, info: str = "", *,
                saved: bool = False) -> bool:
        """Keep a light result (``info``: what was traced; ``saved``: read from the project,
        not new work); True if it replaced results traced with other settings. A result for
        older points or layout is ignored (False)."""
        if run.signature[0] != self.serial:
            return False
        dropped = self.runs.add(run, settings, sampling)
        self.runs_changed.emit(self.runs, info)
        if not saved:
            self._set_modified(True)
        return dropped

    def saved(self, path: str) -> None:
        """The study was written to ``path``."""
        self.project_path = path
        self.project_changed.emit(path)
        self._set_modified(False)

    # ------------------------------------------------------------------ inside
    def _renew(self) -> None:
        self.serial += 1
        self.measures_rows.clear()
        self.runs.clear()
        self.runs_changed.emit(self.runs, "")

    def _set_modified(self, value: bool) -> None:
        if value != self.modified:
            self.modified = value
            self.modified_changed.emit(value)
