"""Linked selection: the study's :class:`~maizeviz_app.selection.Selection` shown in the 3D view
(highlighted, described on a card), in the plants table (its row selected) and in the status
bar; a click in the view or a row chosen in the table changes it.

A click on a leaf selects the leaf (the camera stays); a row of the plants table selects the
plant and frames it; a click beside the canopy clears the selection. A new canopy (another
level) keeps the selection, drawn on the new mesh; new points, a new layout or a mesh file
clear it.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from PySide6.QtCore import QObject
from PySide6.QtWidgets import QAbstractItemView, QTableWidget

from maizeviz_app.selection import describe


class LinkedSelection(QObject):
    """Binds ``model.selection`` to ``viewport`` and the plants ``table``; ``say(text)``
    puts a line in the status bar."""

    def __init__(self, model, viewport, table: QTableWidget,
                 say: Callable[[str], None] | None = None, parent=None):
        super().__init__(parent)
        self.model, self.viewport, self.table = model, viewport, table
        self._say = say
        self._frame = False
        #: Milliseconds the last selection took to show (highlight, card, table), GUI thread.
        self.last_ms: float | None = None
        table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        table.itemSelectionChanged.connect(self._on_table)
        viewport.picked.connect(self._on_pick)
        viewport.canopy_set.connect(self.refresh)
        model.selection.changed.connect(self._follow)
        model.runs_changed.connect(lambda *_a: self._describe())
        for signal in (model.points_changed, model.layout_changed, model.mesh_opened):
            signal.connect(lambda *_a: model.selection.clear())

    # ------------------------------------------------------------------ in
    def _on_pick(self, pick) -> None:
        probe = self.model.probe
        if probe.on:                        # a probe under way takes the clicks
            if pick is not None:
                probe.add(pick.point)
            return
        if pick is None:
            self.model.selection.clear()
        else:
            self.model.selection.select(pick.instance, pick.leaf)

    def _on_table(self) -> None:
        rows = {i.row() for i in self.table.selectedIndexes()}
        item = self.table.item(min(rows), 0) if rows else None
        if item is None:
            return
        try:
            instance = int(item.text()) - 1                # the "stand" column
        except ValueError:
            return
        self._frame = True
        self.model.selection.select(instance, -1)
        self._frame = False

    # ------------------------------------------------------------------ out
    def _follow(self, *_args) -> None:
        t0 = time.perf_counter()
        sel = self.model.selection
        self.viewport.highlight(sel.placement, sel.leaf)
        if self._frame and not sel.empty:
            self.viewport.frame_part(sel.placement)
        self._describe()
        self._select_row()
        self.last_ms = 1000 * (time.perf_counter() - t0)

    def refresh(self) -> None:
        """The canopy on screen changed: the selection drawn on its mesh, described anew."""
        sel = self.model.selection
        if sel.empty:
            self.viewport.info.set_lines([])
            return
        self.viewport.highlight(sel.placement, sel.leaf)
        self._describe()

    def _describe(self) -> None:
        sel, model = self.model.selection, self.model
        lines: list[str] = []
        if not sel.empty and model.built is not None:
            here = model.signature(model.built.label)
            runs = [r for r in model.runs.in_order() if r.signature == here]
            lines = describe(model.canopy, model.built.label, runs, sel.placement, sel.leaf)
        self.viewport.info.set_lines(lines)
        if lines and self._say is not None:
            self._say(lines[0])

    def _select_row(self) -> None:
        t, sel = self.table, self.model.selection
        t.blockSignals(True)
        t.clearSelection()
        for r in range(t.rowCount()):
            item = t.item(r, 0)
            if item is not None and item.text() == str(sel.placement + 1):
                t.selectRow(r)
                t.scrollToItem(item)
                break
        t.blockSignals(False)
