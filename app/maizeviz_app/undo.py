"""One undo history for the study: every edit of a setting (level, area preservation, light,
sky, day, optics) and of the layout is a step of one ``QUndoStack`` (Qt's undo framework, as
the Edit menu and its history view need), whatever panel it was made in.

:class:`UndoRecorder` listens to the study's evented settings and pushes a
:class:`SettingsEdit` for each change a person makes (not for those the study makes itself
while opening a project). Undoing sets the old values back through the same settings, so an
undo has exactly the consequences of an edit: an undone level rebuilds the canopy, an undone
light setting makes the next light run start a new comparison, an undone layout edit is
applied like any layout edit.

What makes one step: everything that changed in one turn of the event loop (a band and the
optics it sets, a sky split and its directions), and consecutive changes of one field less
than :data:`MERGE_S` apart (typing a number, holding a spin box's arrow, dragging the slider).
"""

from __future__ import annotations

import time
from typing import Any

from PySide6.QtCore import QObject, QTimer
from PySide6.QtGui import QUndoCommand, QUndoStack

from maizeviz_app.layout_draft import Change, LayoutDraft
from maizeviz_app.settings import field_names

#: Settings groups whose edits are undoable (the digitizer's connection is not an edit of the
#: study).
UNDOABLE = ("canopy", "light", "sun", "sampling", "sky", "day", "optics", "photosynthesis")
#: The colour settings' groups (:class:`maizeviz_app.colour.ColourSettings`): the 3D view's
#: scale, the heatmaps' and the rest; undoable too (as ParaView's colour map edits), though
#: they change no result.
COLOUR_GROUPS = ("view colours", "heatmap colours", "colours")
#: Edits of one field closer than this (s) are one step.
MERGE_S = 1.5
#: Merge ids of settings edits and of layout edits.
SETTINGS_ID = 1000
LAYOUT_ID = 1001
#: What a field is called in the Edit menu and the history.
NAMES = {"level": "mesh level", "preserve_area": "area preservation", "mode": "light",
         "zenith_deg": "sun zenith", "azimuth_deg": "sun azimuth", "place": "place",
         "heights": "heights", "density": "ray density", "periodic": "infinite field",
         "kind": "sky", "split": "sky directions", "directions": "sky directions",
         "date": "date", "latitude": "latitude", "longitude": "longitude", "tz": "time zone",
         "step_min": "time step", "start": "hours from", "end": "hours to",
         "source": "irradiance source", "linke_turbidity": "Linke turbidity",
         "weather": "weather file", "par_factor": "PAR factor", "diffuse": "diffuse light",
         "enabled": "leaf optics", "band": "band", "reflectance": "leaf reflectance",
         "transmittance": "leaf transmittance", "ground_reflectance": "soil reflectance",
         "direct_w_m2": "direct irradiance", "diffuse_w_m2": "diffuse irradiance",
         "depth": "scattering depth", "tile": "tiling", "range": "colour range",
         "vmin": "colour min", "vmax": "colour max", "clip": "colour clip",
         "cmap": "colour map", "log": "log scale", "shared": "one heatmap scale",
         "painting": "sun painted", "model": "photosynthesis",
         "temperature_c": "leaf temperature", "alpha": "C4 quantum yield",
         "co2_ppm": "CO₂", "amax": "WOFOST AMAX", "eff": "WOFOST EFF",
         "c4_temperature": "C4 temperature response",
         # a field whose name another group uses too: by group and field
         "photosynthesis.vmax": "C4 Vmax"}


def _named(group: str, name: str) -> str:
    """What field ``name`` of settings group ``group`` is called in the Edit menu."""
    return NAMES.get(f"{group}.{name}", NAMES.get(name, name))


def _shown(value: Any) -> str:
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        return f"{value:g}"
    text = str(value)
    return text if len(text) <= 24 else text[:23] + "…"


class SettingsEdit(QUndoCommand):
    """Settings changed by one person's action: ``changes`` (group, field) -> (old, new)."""

    def __init__(self, recorder: UndoRecorder, group: str, name: str, old: Any, new: Any):
        super().__init__()
        self.recorder = recorder
        self.changes: dict[tuple[str, str], tuple[Any, Any]] = {(group, name): (old, new)}
        self.turn = recorder.turn
        self.at = time.monotonic()
        self._pushed = False
        self._name()

    def _name(self) -> None:
        (group, name), (_old, new) = next(reversed(self.changes.items()))
        names = {_named(g, f) for g, f in self.changes}
        where = {"view colours": "3D view ", "heatmap colours": "heatmap "}.get(group, "")
        if len(names) == 1:
            self.setText(f"{where}{_named(group, name)} {_shown(new)}")
        else:
            self.setText(f"{where}{_named(group, name)} {_shown(new)} and "
                         f"{len(names) - 1} more")

    def id(self) -> int:  # noqa: A003 - Qt's name
        return SETTINGS_ID

    def mergeWith(self, other) -> bool:  # noqa: N802 - Qt's name
        if not isinstance(other, SettingsEdit):
            return False
        same_turn = other.turn == self.turn
        typing = set(other.changes) == set(self.changes) and len(self.changes) == 1 and \
            other.at - self.at < MERGE_S
        if not (same_turn or typing):
            return False
        for key, (old, new) in other.changes.items():
            first = self.changes.get(key, (old, new))[0]
            self.changes[key] = (first, new)
        self.at = other.at
        self.changes = {k: v for k, v in self.changes.items() if v[0] != v[1]}
        if not self.changes:
            self.setObsolete(True)                 # back where it started: no step
        else:
            self._name()
        return True

    def redo(self) -> None:
        if not self._pushed:                       # pushed after the change was made
            self._pushed = True
            return
        self.recorder.apply(self.changes, 1)

    def undo(self) -> None:
        self.recorder.apply(self.changes, 0)


class LayoutEdit(QUndoCommand):
    """An edit of the layout draft (a :class:`~maizeviz_app.layout_draft.Change`); edits with
    the same ``merge`` key (the wheel turning one plant) are one step."""

    def __init__(self, draft: LayoutDraft, change: Change, text: str, merge: Any = None):
        super().__init__(text)
        self.draft, self.change, self.merge = draft, change, merge
        self._pushed = False

    def id(self) -> int:  # noqa: A003 - Qt's name
        return LAYOUT_ID if self.merge is not None else -1

    def mergeWith(self, other) -> bool:  # noqa: N802 - Qt's name
        if not isinstance(other, LayoutEdit) or other.merge != self.merge:
            return False
        self.change = Change(self.change.index, self.change.before, other.change.after)
        if self.change.before == self.change.after:
            self.setObsolete(True)
        return True

    def redo(self) -> None:
        if not self._pushed:                       # pushed after the edit was made
            self._pushed = True
            return
        self.draft.replay(self.change, 1)

    def undo(self) -> None:
        self.draft.replay(self.change, 0)


class UndoRecorder(QObject):
    """Records the study's settings edits and its layout draft's edits on :attr:`stack` (see
    the module docstring); the history starts again with every study opened. Without a study,
    the edits of ``draft`` alone."""

    def __init__(self, study, parent=None, draft: LayoutDraft | None = None):
        super().__init__(parent)
        self.study = study
        self.stack = QUndoStack(self)
        self.stack.setUndoLimit(500)
        self.turn = 0
        self._replaying = False
        self._turn_pending = False
        self.draft = study.draft if study is not None else draft
        if self.draft is not None:
            self.draft.edited.connect(self._edited)
        if study is None:
            return
        for name in UNDOABLE:
            group = study.settings.groups[name]
            group.events.connect(lambda info, name=name: self._changed(name, info))
        for name, group in self._colour_groups().items():
            group.events.connect(lambda info, name=name: self._changed(name, info))
        study.points_changed.connect(self._clear)
        study.mesh_opened.connect(self._clear)

    def _clear(self, *_args) -> None:
        self.stack.clear()

    def _edited(self, change: Change, text: str, merge: Any) -> None:
        if self.study is not None and self.study.closing:
            return
        self.stack.push(LayoutEdit(self.draft, change, text, merge))  # type: ignore[arg-type]
        self._new_turn_soon()

    def _changed(self, group: str, info) -> None:
        if self._replaying or self.study.applying or self.study.closing:
            return
        name = info.signal.name
        if group == "canopy" and name == "tile":
            return                                 # set by opening, not an edit
        new, old = info.args[0], info.args[1]
        self.stack.push(SettingsEdit(self, group, name, old, new))
        self._new_turn_soon()

    def _new_turn_soon(self) -> None:
        if not self._turn_pending:                 # the next turn of the loop: a new step
            self._turn_pending = True
            QTimer.singleShot(0, self._next_turn)

    def _next_turn(self) -> None:
        self._turn_pending = False
        self.turn += 1

    def apply(self, changes: dict[tuple[str, str], tuple[Any, Any]], which: int) -> None:
        """Set the ``which`` values (0: old, 1: new) of ``changes``, group by group in the
        fields' order (a band before the optics it sets), without recording them."""
        settings = self.study.settings
        self._replaying = True
        try:
            for group in UNDOABLE:
                values = {f: v[which] for (g, f), v in changes.items() if g == group}
                if values:
                    order = field_names(settings.groups[group])
                    settings.set(group, dict(sorted(values.items(),
                                                    key=lambda kv: order.index(kv[0]))))
            for name, colours in self._colour_groups().items():
                values = {f: v[which] for (g, f), v in changes.items() if g == name}
                with colours.events.paused():          # a range and its limits at once
                    for f, value in values.items():
                        setattr(colours, f, value)
        finally:
            self._replaying = False

    def _colour_groups(self) -> dict[str, Any]:
        c = self.study.colour
        return dict(zip(COLOUR_GROUPS, (c.view, c.heatmap, c)))
