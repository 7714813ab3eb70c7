"""The canopy-layout editor: where each plant stands, which digitized plant it is, its turn.

A table of the layout's positions (x, y in cm, plant id, azimuth in degrees); *Apply* checks
it with the same validation as a layout file and asks the window to rebuild the canopy;
*Save*/*Load* read and write the documented layout JSON (schema 1).
"""

from __future__ import annotations

import json

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import write_text

from PySide6.QtCore import Signal
from PySide6.QtWidgets import (QFileDialog, QHBoxLayout, QLabel, QPushButton, QTableWidget,
                               QTableWidgetItem, QVBoxLayout, QWidget)

from maizeviz.canopy.layout import (LayoutError, Placement, layout_from_dict, layout_to_dict,
                                    load_layout)

COLUMNS = ("x cm", "y cm", "plant", "azimuth °")


class LayoutPanel(QWidget):
    """Edit a :class:`~maizeviz.canopy.layout.CanopyLayout`; ``applied`` carries the new one."""

    applied = Signal(object)
    problem = Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.layout_ = None
        self.plants: set[int] = set()
        lay = QVBoxLayout(self)
        self.info = QLabel("no canopy")
        self.info.setWordWrap(True)
        lay.addWidget(self.info)
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        lay.addWidget(self.table, 1)
        row = QHBoxLayout()
        self.apply_button = QPushButton("Apply")
        self.apply_button.clicked.connect(self.apply)
        load = QPushButton("Load layout…")
        load.clicked.connect(self._load)
        save = QPushButton("Save layout…")
        save.clicked.connect(self._save)
        for b in (self.apply_button, load, save):
            row.addWidget(b)
        lay.addLayout(row)

    def show_layout(self, layout, plants: set[int]) -> None:
        self.layout_ = layout
        self.plants = set(plants)
        self.table.setRowCount(len(layout.placements))
        for i, p in enumerate(layout.placements):
            for j, v in enumerate((f"{p.x:.1f}", f"{p.y:.1f}", str(p.plant),
                                   f"{p.azimuth_deg:g}")):
                self.table.setItem(i, j, QTableWidgetItem(v))
        x0, y0, x1, y1 = layout.bounds
        self.info.setText(f"{len(layout.placements)} plants on {layout.ground_area_cm2 / 1e4:.2f} "
                          f"m², field x {x0:.0f}..{x1:.0f} cm, y {y0:.0f}..{y1:.0f} cm; "
                          f"rows {layout.row_spacing:g} cm, plants {layout.plant_spacing:g} cm")

    def document(self) -> dict:
        """The table as a layout document (raises LayoutError naming the cell)."""
        placements = []
        for i in range(self.table.rowCount()):
            vals: list[float] = []
            for j, name in enumerate(COLUMNS):
                item = self.table.item(i, j)
                text = item.text().strip() if item is not None else ""
                try:
                    vals.append(int(text) if name == "plant" else float(text))
                except ValueError:
                    raise LayoutError(f"row {i + 1}, {name}: '{text}' is not a number") from None
            x, y, plant, az = vals
            placements.append(Placement(int(plant), x, y, az))
        return layout_to_dict(self.layout_, placements)

    def apply(self) -> None:
        if self.layout_ is None:
            return
        try:
            new = layout_from_dict(self.document(), self.plants, "layout table")
        except LayoutError as exc:
            self.problem.emit(str(exc))
            return
        if self.layout_.ground_area is not None:     # a tiling: keep its exact ground
            from dataclasses import replace
            new = replace(new, cells=self.layout_.cells, centre_cells=self.layout_.centre_cells,
                          ground_area=self.layout_.ground_area)
        for w in new.warnings:
            self.problem.emit(f"note: {w}")
        self.layout_ = new
        self.applied.emit(new)

    def _load(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Load layout", "", "Layout (*.json)")
        if not path:
            return
        try:
            new = load_layout(path, self.plants)
        except LayoutError as exc:
            self.problem.emit(str(exc))
            return
        self.show_layout(new, self.plants)
        self.layout_ = new
        self.applied.emit(new)

    def _save(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save layout", "layout.json",
                                              "Layout (*.json)")
        if path:
            self.save(path)

    def save(self, path) -> None:
        try:
            doc = self.document()
            layout_from_dict(doc, self.plants, "layout table")
            write_text(path, json.dumps(doc, indent=1) + "\n")
        except MaizevizError as exc:
            self.problem.emit(f"cannot save the layout: {exc}")

