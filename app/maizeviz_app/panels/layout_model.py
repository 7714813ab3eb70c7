"""The layout being edited, its table, and the undoable edits.

The model keeps every placement as the exact floats it came with; the table shows them rounded
(0.1 cm, 0.1 deg) but hands the exact value to an editor, so a plant moves only when someone
moves it. Every change goes through a :class:`QUndoCommand` on the panel's stack: move, turn,
change plant, and replace the whole layout (a tiling preset, a layout file).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from PySide6.QtCore import QAbstractTableModel, QModelIndex, QObject, Qt, Signal
from PySide6.QtGui import QUndoCommand

from maizeviz.canopy.layout import (
    CanopyLayout,
    LayoutError,
    Placement,
    layout_from_dict,
    layout_to_dict,
)

COLUMNS = ("x cm", "y cm", "plant", "azimuth °")


def fmt(value: float, decimals: int = 1) -> str:
    """A number for a label: rounded, and never '-0'."""
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


@dataclass(frozen=True)
class Snapshot:
    """Everything a whole-layout change replaces (for its undo)."""

    base: CanopyLayout | None
    placements: tuple
    tiling: tuple[int, int] | None


class EditedLayout(QObject):
    """The ground (``base``: field, cells, spacings of the last tiling or layout file) and the
    placements as edited. ``changed(i)``: placement ``i`` changed; -1: everything did."""

    changed = Signal(int)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.base: CanopyLayout | None = None
        self.placements: list[Placement] = []
        self.tiling: tuple[int, int] | None = None      # tiles of the digitized block
        self.plants: set[int] = set()

    def snapshot(self) -> Snapshot:
        return Snapshot(self.base, tuple(self.placements), self.tiling)

    def restore(self, snap: Snapshot) -> None:
        self.base, self.placements, self.tiling = snap.base, list(snap.placements), snap.tiling
        self.changed.emit(-1)

    def set(self, index: int, placement: Placement) -> None:
        self.placements[index] = placement
        self.changed.emit(index)

    def edits(self) -> int:
        """Placements that differ from the tiling or file they came from."""
        if self.base is None:
            return 0
        return sum(a != b for a, b in zip(self.placements, self.base.placements))

    def document(self) -> dict:
        """The layout document (schema of the README) of the edited placements."""
        if self.base is None:
            raise LayoutError("no layout to edit yet: open a points file first")
        return layout_to_dict(self.base, self.placements)

    def layout(self) -> CanopyLayout:
        """The edited layout, checked like a layout file (LayoutError names the problem).

        The ground (cells, ground area) is the base's, and the placements are the edited ones
        themselves, in their order and to the last bit: a layout applied without an edit is the
        layout it was.
        """
        checked = layout_from_dict(self.document(), self.plants, "layout")
        assert self.base is not None                    # document() refused otherwise
        return replace(self.base, placements=tuple(self.placements), warnings=checked.warnings)


class EditPlacement(QUndoCommand):
    """One plant moved, turned or swapped for another digitized plant.

    Wheel turns of the same plant merge into one step (``merge=True``).
    """

    MERGE_ID = 1

    def __init__(self, model: EditedLayout, index: int, new: Placement, text: str,
                 merge: bool = False):
        super().__init__(text)
        self.model, self.index, self.new = model, index, new
        self.old = model.placements[index]
        self.merge = merge

    def redo(self) -> None:
        self.model.set(self.index, self.new)

    def undo(self) -> None:
        self.model.set(self.index, self.old)

    def id(self) -> int:  # noqa: A003 - Qt's name
        return self.MERGE_ID if self.merge else -1

    def mergeWith(self, other) -> bool:  # noqa: N802 - Qt's name
        if not (isinstance(other, EditPlacement) and other.merge and other.index == self.index):
            return False
        self.new = other.new
        return True


class ReplaceLayout(QUndoCommand):
    """A tiling preset or a layout file in place of the whole layout."""

    def __init__(self, model: EditedLayout, layout: CanopyLayout,
                 tiling: tuple[int, int] | None, text: str):
        super().__init__(text)
        self.model = model
        self.before = model.snapshot()
        self.after = Snapshot(layout, tuple(layout.placements), tiling)

    def redo(self) -> None:
        self.model.restore(self.after)

    def undo(self) -> None:
        self.model.restore(self.before)


class PlacementTable(QAbstractTableModel):
    """The placements as rows x, y (cm), plant, azimuth (deg).

    Shown rounded, edited exactly: the edit role is the full value. An accepted edit is handed
    to ``edit(index, placement, text)`` (the panel pushes it on its undo stack); a refused one
    to ``refuse(message)``.
    """

    def __init__(self, model: EditedLayout, edit, refuse, parent=None):
        super().__init__(parent)
        self.model = model
        self._edit, self._refuse = edit, refuse
        model.changed.connect(self._on_changed)

    def _on_changed(self, index: int) -> None:
        if index < 0:
            self.beginResetModel()
            self.endResetModel()
        else:
            self.dataChanged.emit(self.index(index, 0), self.index(index, len(COLUMNS) - 1))

    def rowCount(self, parent=QModelIndex()) -> int:  # noqa: N802, B008 - Qt's API
        return 0 if parent.isValid() else len(self.model.placements)

    def columnCount(self, parent=QModelIndex()) -> int:  # noqa: N802, B008
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802
        if role != Qt.ItemDataRole.DisplayRole:
            return None
        return COLUMNS[section] if orientation == Qt.Orientation.Horizontal else str(section + 1)

    def flags(self, index):
        return Qt.ItemFlag.ItemIsSelectable | Qt.ItemFlag.ItemIsEnabled | Qt.ItemFlag.ItemIsEditable

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        p = self.model.placements[index.row()]
        value = (p.x, p.y, p.plant, p.azimuth_deg)[index.column()]
        if role == Qt.ItemDataRole.DisplayRole:
            return str(value) if index.column() == 2 else fmt(value)
        if role == Qt.ItemDataRole.EditRole:
            return str(value) if index.column() == 2 else repr(float(value))
        if role == Qt.ItemDataRole.TextAlignmentRole:
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        return None

    def setData(self, index, value, role=Qt.ItemDataRole.EditRole) -> bool:  # noqa: N802
        if role != Qt.ItemDataRole.EditRole or not index.isValid():
            return False
        row, col = index.row(), index.column()
        name = COLUMNS[col]
        text = str(value).strip()
        p = self.model.placements[row]
        try:
            number = int(text) if col == 2 else float(text)
        except ValueError:
            self._refuse(f"row {row + 1}, {name}: '{text}' is not a number")
            return False
        if col != 2 and not math.isfinite(number):
            self._refuse(f"row {row + 1}, {name}: '{text}' is not a finite number")
            return False
        if col == 2:
            if self.model.plants and number not in self.model.plants:
                self._refuse(f"row {row + 1}: plant {number} is not in the points file (it has "
                             f"{', '.join(map(str, sorted(self.model.plants)))})")
                return False
            new, what = replace(p, plant=number), f"plant {p.plant} → {number} in row {row + 1}"
        elif col == 3:
            new, what = replace(p, azimuth_deg=number), f"turn the plant in row {row + 1}"
        else:
            xy = {"x": number} if col == 0 else {"y": number}
            new, what = replace(p, **xy), f"move the plant in row {row + 1}"
        if new == p:
            return True                     # the same value typed again: no edit
        self._edit(row, new, what)
        return True

