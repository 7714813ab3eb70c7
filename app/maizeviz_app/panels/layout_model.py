"""The placements of the layout being edited as a table.

The draft (:class:`maizeviz_app.layout_draft.LayoutDraft`) keeps every placement as the exact
floats it came with; the table shows them rounded (0.1 cm, 0.1 deg) but hands the exact value to
an editor, so a plant moves only when someone moves it. A value typed is an edit of the draft
(undoable, as every edit of the draft is); a value refused is said in one line.
"""

from __future__ import annotations

import math

from PySide6.QtCore import QAbstractTableModel, QModelIndex, Qt
from PySide6.QtGui import QColor

from maizeviz.canopy.layout import LayoutError
from maizeviz.numbers import number as read_number
from maizeviz.numbers import whole
from maizeviz_app.layout_draft import LayoutDraft

COLUMNS = ("x cm", "y cm", "plant", "azimuth °")


def fmt(value: float, decimals: int = 1) -> str:
    """A number for a label: rounded, and never '-0'."""
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


class PlacementTable(QAbstractTableModel):
    """The placements as rows x, y (cm), plant, azimuth (deg); rows of plants standing on
    another's ground in red (``overlapping``: their indices, set by the panel).

    Shown rounded, edited exactly: the edit role is the full value. An accepted value is an
    edit of the draft; a refused one goes to ``refuse(message)``.
    """

    def __init__(self, model: LayoutDraft, refuse, parent=None):
        super().__init__(parent)
        self.model = model
        self._refuse = refuse
        self.overlapping: set[int] = set()
        model.changed.connect(self._on_changed)

    def _on_changed(self, index: int) -> None:
        if index < 0 or index >= self.rowCount():
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
        if role == Qt.ItemDataRole.ForegroundRole and index.row() in self.overlapping:
            return QColor("#c62828")
        if role == Qt.ItemDataRole.ToolTipRole and index.row() in self.overlapping:
            return "this plant stands on another's ground (see the overlaps listed)"
        return None

    def setData(self, index, value, role=Qt.ItemDataRole.EditRole) -> bool:  # noqa: N802
        if role != Qt.ItemDataRole.EditRole or not index.isValid():
            return False
        row, col = index.row(), index.column()
        name = COLUMNS[col]
        text = str(value).strip()
        p = self.model.placements[row]
        try:
            number = whole(text) if col == 2 else read_number(text)
        except ValueError:
            self._refuse(f"row {row + 1}, {name}: '{text}' is not a number")
            return False
        if col != 2 and not math.isfinite(number):
            self._refuse(f"row {row + 1}, {name}: '{text}' is not a finite number")
            return False
        try:
            if col == 2:
                self.model.set_plant(row, int(number))
            elif col == 3:
                self.model.turn(row, number)
            else:
                self.model.move(row, number if col == 0 else p.x, number if col == 1 else p.y,
                                snap=False)
        except LayoutError as exc:
            self._refuse(str(exc))
            return False
        return True
