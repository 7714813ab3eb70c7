"""The study open in the app as one object, without Qt: its state (:mod:`maizeviz_app.state`)
and the actions over it, for the window and for scripts (napari's ``ViewerModel`` pattern).

The actions are functions in three modules, one per kind of work, that import the state and
not this module: :mod:`maizeviz_app.building` (points, mesh files, canopies),
:mod:`maizeviz_app.lighting` (light and what is shown of it) and
:mod:`maizeviz_app.studyfiles` (projects and exports). Each validates, hands its work to the
runner (:mod:`maizeviz_app.runner`) and keeps the results in the state, which says what
changed through psygnal signals. The window only wires the model to the panels, the 3D view
and the menus. Everything here runs on the GUI thread (or a script's thread), and a whole study
can be driven and checked without a window::

    runner = InlineRunner()                 # each job at once (the window: a thread pool)
    model = StudyModel(runner=runner)
    model.open_points("plants.csv")         # read, laid out, built at settings.canopy.level
    model.settings.canopy.level = "8"       # rebuilt at 8 triangles a leaf
    model.settings.light.mode = "day"
    model.compute_light()
    with model.history.step("C4 at 30 °C"): # one named step of the undo history
        model.settings.photosynthesis.model = "c4"
        model.settings.photosynthesis.temperature_c = 30.0
    model.history.undo()
    model.save_project("study.maizeviz")
"""

from __future__ import annotations

from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from maizeviz.canopy.layout import LayoutError
from maizeviz_app import building, lighting, studyfiles
from maizeviz_app.runner import Runner
from maizeviz_app.state import COLOUR_GROUPS, UNDOABLE, StudyState  # noqa: F401 - the app's names

if TYPE_CHECKING:
    from maizeviz.canopy.layout import CanopyLayout
    from maizeviz_app.digitizing import DigitizingSession


class StudyModel(StudyState):
    """The study (:class:`~maizeviz_app.state.StudyState`) and its actions; a canopy setting
    changed (the slider, area preservation, an undo) rebuilds the canopy, and so does an edit
    of the layout while ``layout_options.follow`` (:meth:`apply_draft`).

    Parameters
    ----------
    tile : int
        Tiles along each side of the canopy until a layout is loaded (the app's ``--tile``).
    runner : Runner, optional
        Where jobs run (the window's thread pool); default an
        :class:`~maizeviz_app.runner.InlineRunner`.
    """

    def __init__(self, tile: int = 3, runner: Runner | None = None) -> None:
        super().__init__(tile, runner)
        events: Any = self.settings.canopy.events       # psygnal's, made by @evented
        events.level.connect(self._canopy_setting)
        events.preserve_area.connect(self._canopy_setting)
        self.draft.edited.connect(self._draft_moved)
        self.draft.replayed.connect(self._draft_moved)
        self.figures.canvas_changed.connect(self._refit_figures)

    @cached_property
    def digitizing(self) -> DigitizingSession:
        """The digitizing session (the recorder's process, what is on disk, the counts and
        warnings); the digitizer panel shows it (:mod:`maizeviz_app.digitizing`)."""
        from maizeviz_app.digitizing import DigitizingSession

        return DigitizingSession()

    def _refit_figures(self, which: str) -> None:
        lighting.refit_figures(self, which)

    def _canopy_setting(self, *_values: Any) -> None:
        if not self.applying:
            self.build()

    def _draft_moved(self, *_edit: Any) -> None:
        """The layout edited, or an edit undone or redone: applied when it follows."""
        if self.layout_options.follow and not self.closing:
            self.apply_draft()

    # ------------------------------------------------------------------ canopy
    def open_points(self, path: str | Path, layout: CanopyLayout | None = None) -> None:
        """Read a points file and build it (:func:`maizeviz_app.building.open_points`)."""
        building.open_points(self, path, layout)

    def open_mesh(self, path: str | Path, unit: str | None = None, up: str = "z",
                  field: str | tuple[float, float, float, float] | None = None) -> None:
        """Read a canopy mesh instead of points (:func:`maizeviz_app.building.open_mesh`)."""
        building.open_mesh(self, path, unit, up, field)

    def build(self) -> None:
        """Build the canopy at the settings (:func:`maizeviz_app.building.build`)."""
        building.build(self)

    def apply_layout(self, layout: CanopyLayout) -> bool:
        """Build the canopy on an edited layout (:meth:`edit_layout`, then :meth:`build`);
        True if light results were dropped."""
        dropped = self.edit_layout(layout)
        if self.loaded is not None and self.loaded.layout is layout:
            self.build()
        return dropped

    def apply_draft(self) -> bool:
        """The layout being edited (:attr:`draft`), checked and built: at every edit while
        ``layout_options.follow``, else when asked (the layout editor's *Apply*). A layout the
        core refuses is said (one line naming the problem), its notes once; False when it
        cannot be used or is the layout already built."""
        if self.loaded is None or self.draft.base is None:
            return False
        try:
            new = self.draft.layout()
        except LayoutError as exc:
            self.say(f"error: {exc}", error=True)
            return False
        if new.warnings != self.layout_notes:
            for w in new.warnings:
                self.say(f"note: {w}")
            self.layout_notes = new.warnings
        current = self.loaded.layout
        if new.placements == current.placements and new.cells is current.cells:
            return False
        self.apply_layout(new)
        return True

    def cancel(self, kind: str | None = None) -> list[str]:
        """Stop the jobs of ``kind`` (:func:`maizeviz_app.building.cancel`)."""
        return building.cancel(self, kind)

    # ------------------------------------------------------------------ light
    def compute_light(self) -> bool:
        """Compute the light the settings choose (:func:`maizeviz_app.lighting.compute_light`);
        False if it did not start."""
        return lighting.compute_light(self)

    def draw_heatmap(self, kind: str, index: int) -> None:
        """The heatmap of another height (:func:`maizeviz_app.lighting.draw_heatmap`)."""
        lighting.draw_heatmap(self, kind, index)

    def sun_from_place(self) -> None:
        """Sun angles from the place and time (:func:`maizeviz_app.lighting.sun_from_place`)."""
        lighting.sun_from_place(self)

    def choose_weather(self, path: str) -> None:
        """A weather file and its place (:func:`maizeviz_app.lighting.choose_weather`)."""
        lighting.choose_weather(self, path)

    # ------------------------------------------------------------------ files
    def open_project(self, path: str | Path) -> None:
        """Read a project (:func:`maizeviz_app.studyfiles.open_project`)."""
        studyfiles.open_project(self, path)

    def save_project(self, path: str | Path) -> bool:
        """Write the project (:func:`maizeviz_app.studyfiles.save_project`)."""
        return studyfiles.save_project(self, path)

    def export(self, what: str, path: str | Path) -> bool:
        """Write ``what`` to ``path`` (:func:`maizeviz_app.studyfiles.export`)."""
        return studyfiles.export(self, what, path)
