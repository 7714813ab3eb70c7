"""The study's undo history, without Qt: steps of edits, named, grouped explicitly.

A step is what one Undo takes back: one edit, or the edits made inside one
``with history.step("name"):`` block (napari's Labels layer groups the edits of one gesture
with ``block_history`` the same way). A script's steps are therefore the steps it names, and
nothing depends on an event loop: a script that sets three settings without a block makes
three steps, named after what changed ("sun zenith 30").

Two rules join edits without a block, both explicit:

- an edit made *while another edit is being handled* belongs to that edit's step (choosing a
  band sets the optics to the band's defaults; one Undo takes back both). The settings are
  watched with a callback run before and one run after every other callback of a field's
  change (:func:`watch`), so what those callbacks change is known to be a reaction;
- consecutive edits of one field closer than :attr:`History.merge_s` seconds are one step, and
  so are consecutive edits that carry the same merge key (a wheel turning one plant). A script's
  history has ``merge_s = 0`` (every edit a step); the window sets it, so that typing a number,
  holding a spin box's arrow or dragging the slider is one step.

Undoing sets the old values back through the same settings, so an undo has exactly the
consequences of an edit (an undone level rebuilds the canopy). Qt's ``QUndoStack`` and the
history view only mirror this history (:mod:`maizeviz_app.undo`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Protocol

from psygnal import Signal

from maizeviz_app.layout_draft import Change

#: What a field is called in the Edit menu and the history.
NAMES = {"level": "mesh level", "preserve_area": "area preservation", "mode": "light",
         "stalks": "stalks take light",
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
#: Where a colour group's edits are said to be made ("3D view colour map greys").
WHERE = {"view colours": "3D view ", "heatmap colours": "heatmap "}
#: Most steps kept (the oldest are forgotten).
LIMIT = 500


def field_name(group: str, name: str) -> str:
    """What field ``name`` of settings group ``group`` is called in the Edit menu."""
    return NAMES.get(f"{group}.{name}", NAMES.get(name, name))


def shown(value: Any) -> str:
    """A value as the Edit menu shows it (``on``, ``45``, a long text cut)."""
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        return f"{value:g}"
    text = str(value)
    return text if len(text) <= 24 else text[:23] + "…"


class Edit(Protocol):
    """One change the history can take back and make again."""

    key: Hashable
    """What it changes: consecutive edits of one key may join (see :meth:`joined`)."""

    @property
    def text(self) -> str:
        """What it did, in a few words ("sun zenith 45")."""

    @property
    def empty(self) -> bool:
        """It changes nothing (an edit and its reverse joined)."""

    def undo(self) -> None: ...

    def redo(self) -> None: ...

    def joined(self, later: Any, merge_s: float) -> Edit | None:
        """This edit and the ``later`` one as one edit, or None if they stay two steps."""


@dataclass
class SettingEdit:
    """A field of a settings group changed: ``group.<name>`` from ``old`` to ``new``.

    ``apply(group, name, value)`` sets a value back without it being recorded again.
    """

    group: str
    name: str
    old: Any
    new: Any
    apply: Callable[[str, str, Any], None]
    at: float = field(default_factory=time.monotonic)

    @property
    def key(self) -> tuple[str, str]:
        return (self.group, self.name)

    @property
    def text(self) -> str:
        return f"{WHERE.get(self.group, '')}{field_name(self.group, self.name)} {shown(self.new)}"

    @property
    def empty(self) -> bool:
        return bool(self.old == self.new)

    def undo(self) -> None:
        self.apply(self.group, self.name, self.old)

    def redo(self) -> None:
        self.apply(self.group, self.name, self.new)

    def joined(self, later: Any, merge_s: float) -> SettingEdit | None:
        if not isinstance(later, SettingEdit) or later.key != self.key or \
                later.at - self.at >= merge_s:
            return None
        return SettingEdit(self.group, self.name, self.old, later.new, self.apply, later.at)


@dataclass
class DraftEdit:
    """An edit of the layout being edited (:class:`maizeviz_app.layout_draft.Change`), made
    again or taken back by ``replay(change, which)`` (1: again, 0: back). Edits with the same
    ``merge`` key (not None: the wheel turning one plant) are one step."""

    change: Change
    words: str
    merge: Hashable
    replay: Callable[[Change, int], None]

    @property
    def key(self) -> Hashable:
        return ("layout", self.merge) if self.merge is not None else ("layout", id(self))

    @property
    def text(self) -> str:
        return self.words

    @property
    def empty(self) -> bool:
        return bool(self.change.before == self.change.after)

    def undo(self) -> None:
        self.replay(self.change, 0)

    def redo(self) -> None:
        self.replay(self.change, 1)

    def joined(self, later: Any, merge_s: float) -> DraftEdit | None:
        if not isinstance(later, DraftEdit) or self.merge is None or later.merge != self.merge:
            return None
        change = Change(self.change.index, self.change.before, later.change.after)
        return DraftEdit(change, later.words, self.merge, self.replay)


@dataclass
class Step:
    """What one Undo takes back: its edits in the order made, and its name (given by the
    block that made it, else said from its edits)."""

    edits: list[Any] = field(default_factory=list)
    name: str = ""

    @property
    def text(self) -> str:
        if self.name:
            return self.name
        if not self.edits:
            return ""
        first = self.edits[0]                   # the edit the others reacted to
        others = len({e.key for e in self.edits} - {first.key})
        return first.text if not others else f"{first.text} and {others} more"

    @property
    def empty(self) -> bool:
        return all(e.empty for e in self.edits)

    def add(self, edit: Any) -> None:
        """Keep ``edit``, joined to an earlier edit of the same key (its first old value
        and this new one) so that the step sets each thing once."""
        for k, e in enumerate(self.edits):
            if e.key == edit.key and isinstance(e, SettingEdit):
                joined = e.joined(edit, float("inf"))
                if joined is not None:
                    del self.edits[k]
                    self.edits.append(joined)
                    return
        self.edits.append(edit)

    def undo(self) -> None:
        """Other edits (a layout's) backwards; settings in the order made, a cause before
        its reactions (a band, then the optics it had set), so that a reaction's old
        values are the last word."""
        for e in reversed(self.edits):
            if not isinstance(e, SettingEdit):
                e.undo()
        for e in self.edits:
            if isinstance(e, SettingEdit):
                e.undo()

    def redo(self) -> None:
        for e in self.edits:
            e.redo()


class History:
    """The steps of the study's edits and where the study is among them.

    Parameters
    ----------
    merge_s : float
        Consecutive edits of one field closer than this (s) are one step (0: never; the
        window sets 1.5 s).
    limit : int
        Most steps kept.

    Attributes
    ----------
    steps : list[Step]
        Every step kept, oldest first.
    index : int
        How many of them are done (``steps[index:]`` are undone: Redo makes them again).

    Signals
    -------
    changed() : a step recorded, joined, undone, redone or forgotten.
    """

    changed = Signal()

    def __init__(self, merge_s: float = 0.0, limit: int = LIMIT) -> None:
        self.merge_s = merge_s
        self.limit = limit
        self.steps: list[Step] = []
        self.index = 0
        self.replaying = False          # an undo or redo under way: its changes not recorded
        self._block: Step | None = None
        self._blocks = 0
        self._reacting = 0              # handlers of an edit running: their edits join it
        self._last: Step | None = None  # the step a reaction or a merge may join

    # ------------------------------------------------------------------ reading
    @property
    def can_undo(self) -> bool:
        return self.index > 0

    @property
    def can_redo(self) -> bool:
        return self.index < len(self.steps)

    @property
    def undo_text(self) -> str:
        """The name of the step Undo takes back ("" when none)."""
        return self.steps[self.index - 1].text if self.can_undo else ""

    @property
    def redo_text(self) -> str:
        return self.steps[self.index].text if self.can_redo else ""

    @property
    def texts(self) -> list[str]:
        """Every step's name, oldest first."""
        return [s.text for s in self.steps]

    # ------------------------------------------------------------------ recording
    @contextmanager
    def step(self, name: str = "") -> Iterator[None]:
        """Every edit made inside is one step, called ``name`` (else named from its edits);
        a block inside another joins it. A block that changed nothing leaves no step."""
        if self._blocks:
            self._blocks += 1
            try:
                yield
            finally:
                self._blocks -= 1
            return
        self._blocks, self._block = 1, Step(name=name)
        try:
            yield
        finally:
            block, self._block, self._blocks = self._block, None, 0
            block.edits = [e for e in block.edits if not e.empty]
            if block.edits:
                self._push(block)
            self._last = None                   # a named step is not merged into

    @contextmanager
    def reacting(self) -> Iterator[None]:
        """Edits made inside are reactions to the edit just recorded and join its step."""
        self._reacting += 1
        try:
            yield
        finally:
            self._reacting -= 1

    def record(self, edit: Any) -> None:
        """Keep an edit just made (nothing while an undo or redo replays)."""
        if self.replaying:
            return
        if self._block is not None:
            self._block.add(edit)
            return
        last = self._last
        if last is not None and self.index == len(self.steps) and self.steps and \
                self.steps[-1] is last:
            if self._reacting:
                last.add(edit)
                self._settle(last)
                return
            joined = last.edits[-1].joined(edit, self.merge_s) if len(last.edits) == 1 \
                else None
            if joined is not None:
                last.edits[-1] = joined
                self._settle(last)
                return
        if edit.empty:
            return
        self._push(Step([edit]))

    def _push(self, step: Step) -> None:
        del self.steps[self.index:]
        self.steps.append(step)
        if len(self.steps) > self.limit:
            del self.steps[0]
        self.index = len(self.steps)
        self._last = step if not step.name else None
        self.changed.emit()

    def _settle(self, step: Step) -> None:
        """A step joined: one that came back where it started is no step."""
        if step.empty:
            self.steps.remove(step)
            self.index = len(self.steps)
            self._last = None
        self.changed.emit()

    def clear(self) -> None:
        """Forget every step (a new study opened)."""
        self.steps.clear()
        self.index = 0
        self._last = None
        self.changed.emit()

    def forget_merging(self) -> None:
        """The next edit starts a step of its own (a gesture ended)."""
        self._last = None

    # ------------------------------------------------------------------ moving
    def undo(self) -> bool:
        """Take back the last step done; False when there is none."""
        if not self.can_undo:
            return False
        self.index -= 1
        self._replay(self.steps[self.index].undo)
        return True

    def redo(self) -> bool:
        """Make the next undone step again; False when there is none."""
        if not self.can_redo:
            return False
        self.index += 1
        self._replay(self.steps[self.index - 1].redo)
        return True

    def go_to(self, index: int) -> None:
        """Undo or redo until ``index`` steps are done."""
        index = max(0, min(index, len(self.steps)))
        while self.index > index:
            self.undo()
        while self.index < index:
            self.redo()

    def _replay(self, action: Callable[[], None]) -> None:
        self._last = None
        self.replaying = True
        try:
            action()
        finally:
            self.replaying = False
        self.changed.emit()


def watch(history: History, name: str, group: Any, fields: Sequence[str],
          apply: Callable[[str, str, Any], None],
          skip: Callable[[], bool] = lambda: False) -> None:
    """Record the changes of ``fields`` of an evented settings ``group`` (psygnal's
    ``@evented``) in ``history`` as :class:`SettingEdit` of group ``name``.

    Each field gets a first callback, which records the change, and a last one: what the
    callbacks between them change (a band's optics, a rebuild's level refused) is recorded
    as a reaction joined to the change's step. ``skip()`` True: the change is the study's own
    (a project read), not recorded.
    """
    for f in fields:
        signal = getattr(group.events, f)
        recorded: list[bool] = []               # nested changes of this field, innermost last

        def first(new: Any, old: Any, f: str = f, recorded: list[bool] = recorded) -> None:
            made = not skip()
            if made:
                history.record(SettingEdit(name, f, old, new, apply))
                history._reacting += 1
            recorded.append(made)

        def last(*_args: Any, recorded: list[bool] = recorded) -> None:
            if recorded and recorded.pop():
                history._reacting = max(history._reacting - 1, 0)

        signal.connect(first, priority=10**6)
        signal.connect(last, priority=-(10**6))
