"""The canopy-layout editor: where each plant stands, which digitized plant it is, its turn.

A top view of the field (:class:`FieldView`) beside the table of placements. Drag a plant to
move it, turn it with the wheel or its arrow's knob, or type in the table; every edit is one
step of an undo stack (Ctrl+Z, Ctrl+Shift+Z). Tiling presets repeat the digitized block (the
paper's 3 x 3 block tiled 3 x 3 gives its 9 x 9 canopy); a preset that would replace edited
positions asks first. Positions are kept exactly as they are until edited (the table only
shows them rounded), so applying an unedited layout changes nothing.

``applied(layout)`` carries the layout to build: on *Apply*, or after each edit when "3D view
follows" is on. *Save*/*Load* use the layout file of the README (written atomically).
"""

from __future__ import annotations

from dataclasses import replace

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QKeySequence, QUndoStack
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QMessageBox,
    QPushButton,
    QSplitter,
    QStyle,
    QTableView,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from maizeviz.canopy.layout import (
    LayoutError,
    block_lattice,
    load_layout,
    save_layout,
    tiled_layout,
)
from maizeviz.errors import MaizevizError
from maizeviz_app.options import TILINGS, tiling_of
from maizeviz_app.panels.field_view import FieldView
from maizeviz_app.panels.layout_model import (
    EditedLayout,
    EditPlacement,
    PlacementTable,
    ReplaceLayout,
    fmt,
)

FOLLOW_DELAY_MS = 400


class LayoutPanel(QWidget):
    """Edit a :class:`~maizeviz.canopy.layout.CanopyLayout`; ``applied`` carries the new one,
    ``problem`` a line for the technician (a refused edit, a note from the checks). With a
    ``study`` (:class:`~maizeviz_app.model.StudyModel`) it shows the layout of the points the
    study opens."""

    applied = Signal(object)
    problem = Signal(str)

    def __init__(self, study=None, stack: QUndoStack | None = None, parent=None):
        super().__init__(parent)
        self.study = study
        self.model = EditedLayout(self)
        self.model.changed.connect(self._on_changed)
        self.model.changed.connect(self._on_edit)
        self.bases: dict[int, tuple[float, float]] = {}
        # the study's one history (the Edit menu's), else a history of the panel's own
        self.undo_stack = stack if stack is not None else QUndoStack(self)
        self._quiet = False
        self._said: tuple = ()
        self._applied: tuple | None = None
        self._split = False

        lay = QVBoxLayout(self)
        self.info = QLabel("no canopy")
        self.info.setWordWrap(True)
        lay.addWidget(self.info)

        bar = QHBoxLayout()
        bar.addWidget(QLabel("tiling"))
        self.tiling = QComboBox()
        self.tiling.setToolTip("repeat the digitized block; the paper tiles its 3 x 3 block "
                               "3 x 3 times (9 x 9 plants)")
        self.tiling.activated.connect(self._on_tiling_chosen)
        self.tiling.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.tiling.setMinimumContentsLength(10)
        bar.addWidget(self.tiling, 1)
        self.undo_action = self.undo_stack.createUndoAction(self, "Undo")
        self.undo_action.setShortcut(QKeySequence.StandardKey.Undo)
        self.redo_action = self.undo_stack.createRedoAction(self, "Redo")
        self.redo_action.setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
        for action, icon in ((self.undo_action, QStyle.StandardPixmap.SP_ArrowBack),
                             (self.redo_action, QStyle.StandardPixmap.SP_ArrowForward)):
            if stack is not None:               # the Edit menu's shortcuts act everywhere
                action.setShortcuts([])
            else:
                action.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
                self.addAction(action)
            action.setIcon(self.style().standardIcon(icon))
            button = QToolButton()
            button.setDefaultAction(action)
            button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonIconOnly)
            bar.addWidget(button)
        self.follow = QCheckBox("3D view follows")
        self.follow.setToolTip("rebuild the canopy after each edit")
        self.follow.setChecked(True)
        bar.addWidget(self.follow)
        lay.addLayout(bar)

        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.view = FieldView()
        self.view.moved.connect(self._on_moved)
        self.view.turned.connect(self._on_turned)
        self.view.picked.connect(self._on_picked)
        self.table = QTableView()
        self.rows = PlacementTable(self.model, self._push_edit, self.problem.emit, self)
        self.table.setModel(self.rows)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.verticalHeader().setDefaultSectionSize(22)
        # fixed rows: 700 rows stay fast
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Fixed)
        self.table.selectionModel().currentRowChanged.connect(
            lambda cur, _prev: self.view.select(cur.row()))
        self.splitter.addWidget(self.view)
        self.splitter.addWidget(self.table)
        self.splitter.setStretchFactor(0, 3)
        self.splitter.setStretchFactor(1, 2)
        lay.addWidget(self.splitter, 1)

        row = QHBoxLayout()
        self.state = QLabel("")
        self.state.setWordWrap(True)
        row.addWidget(self.state, 1)
        self.apply_button = QPushButton("Apply")
        self.apply_button.setToolTip("check the layout and rebuild the canopy with it")
        self.apply_button.clicked.connect(self.apply)
        load = QPushButton("Load…")
        load.clicked.connect(self._load)
        save = QPushButton("Save…")
        save.clicked.connect(self._save)
        for b in (self.apply_button, load, save):
            row.addWidget(b)
        lay.addLayout(row)

        self._follow_timer = QTimer(self, singleShot=True, interval=FOLLOW_DELAY_MS)
        self._follow_timer.timeout.connect(self.apply)
        if study is not None:
            self.applied.connect(study.apply_layout)
            study.points_changed.connect(self._on_points)
            # a mesh file's canopy has no layout to edit
            study.mesh_opened.connect(lambda _path: self.setEnabled(False))
            if study.loaded is not None:
                self.show_layout(study.loaded.layout, study.loaded.plants)

    def _on_points(self, loaded) -> None:
        self.setEnabled(True)
        self.show_layout(loaded.layout, loaded.plants)

    # ------------------------------------------------------------------------ state
    @property
    def layout_(self):
        return self.model.base

    @property
    def plants(self) -> set[int]:
        return self.model.plants

    def show_layout(self, layout, plants: set[int],
                    bases: dict[int, tuple[float, float]] | None = None) -> None:
        """A new canopy (a points file was opened): its layout, the ids of its digitized plants
        and their stalk bases (cm, for the tiling presets; read from the layout's central tile
        when it is a tiling and they are not given). Clears the undo history."""
        self._follow_timer.stop()
        tiling = tiling_of(layout)
        if bases is not None:
            self.bases = dict(bases)
        elif tiling is not None:
            self.bases = {p.plant: (p.x, p.y) for p in layout.placements if p.tile == (0, 0)}
        self.model.plants = set(plants)
        self._quiet = True
        try:
            self.undo_stack.clear()
            self.model.base, self.model.tiling = layout, tiling
            self.model.placements = list(layout.placements)
            self._applied = tuple(layout.placements)
            self._said = ()
            self.model.changed.emit(-1)
        finally:
            self._quiet = False

    def document(self) -> dict:
        """The edited layout as a layout document (schema 1)."""
        return self.model.document()

    def edited_layout(self):
        """The edited layout, checked (raises LayoutError naming the problem)."""
        if self.model.base is None:
            raise LayoutError("no layout to edit yet")
        return self.model.layout()

    def _on_changed(self, index: int) -> None:
        base = self.model.base
        if index >= 0:
            self.view.update_plant(index, self.model.placements[index])
        else:
            self.view.show_layout(base, self.model.placements)
            self._fill_tilings()
        if base is None:
            self.info.setText("no canopy")
            return
        x0, y0, x1, y1 = base.bounds
        self.info.setText(
            f"{len(self.model.placements)} plants on {fmt(base.ground_area_cm2 / 1e4, 2)} m², "
            f"field x {fmt(x0, 0)}..{fmt(x1, 0)} cm, y {fmt(y0, 0)}..{fmt(y1, 0)} cm; rows "
            f"{base.row_spacing:g} cm apart, plants {base.plant_spacing:g} cm")
        self._show_state()

    def _show_state(self) -> None:
        edits = self.model.edits()
        applied = self._applied == tuple(self.model.placements)
        self.state.setText(f"{edits} plant{'s' if edits != 1 else ''} edited"
                           + ("" if applied else " · not applied yet"))

    def _fill_tilings(self) -> None:
        self.tiling.blockSignals(True)
        self.tiling.clear()
        block = self._block()
        for n in TILINGS:
            if block is None:
                break
            text = f"{n} x {n} tiles: {block[0] * n} x {block[1] * n} plants"
            if n == 1:
                text += " (the digitized block)"
            elif n == 3 and block == (3, 3):
                text += " (the paper)"
            self.tiling.addItem(text, n)
        current = self.model.tiling
        if current is not None and current[0] == current[1] and current[0] in TILINGS \
                and block is not None:
            self.tiling.setCurrentIndex(TILINGS.index(current[0]))
        else:
            self.tiling.addItem("from a layout file" if current is None
                                else f"{current[0]} x {current[1]} tiles", None)
            self.tiling.setCurrentIndex(self.tiling.count() - 1)
        self.tiling.setEnabled(block is not None)
        self.tiling.blockSignals(False)

    def _block(self) -> tuple[int, int] | None:
        base = self.model.base
        if not self.bases or base is None:
            return None
        return block_lattice(self.bases, base.row_spacing, base.plant_spacing)[0]

    # ------------------------------------------------------------------------ edits
    def _push_edit(self, index: int, placement, text: str, merge: bool = False) -> None:
        self.undo_stack.push(EditPlacement(self.model, index, placement, text, merge))

    def _on_moved(self, index: int, x: float, y: float) -> None:
        p = self.model.placements[index]
        self._push_edit(index, replace(p, x=x, y=y), f"move plant {p.plant}")

    def _on_turned(self, index: int, azimuth: float, by_wheel: bool) -> None:
        p = self.model.placements[index]
        if azimuth != p.azimuth_deg:
            self._push_edit(index, replace(p, azimuth_deg=azimuth), f"turn plant {p.plant}",
                            merge=by_wheel)

    def _on_picked(self, index: int) -> None:
        self.table.selectRow(index)

    def _on_edit(self, _index: int = -1) -> None:
        if self._quiet:
            return
        self._show_state()
        if self.follow.isChecked():
            self._follow_timer.start()

    def set_tiling(self, n: int) -> bool:
        """Tile the digitized block ``n`` x ``n`` times; asks first when it would replace
        edited positions. Returns whether the tiling changed."""
        base = self.model.base
        block = self._block()
        if base is None or block is None or self.model.tiling == (n, n):
            self._fill_tilings()
            return False
        edits = self.model.edits()
        if edits and not self._confirm(
                f"The new tiling replaces every plant position: your edits to {edits} "
                f"plant{'s' if edits != 1 else ''} will be gone (Undo brings them back)."):
            self._fill_tilings()
            return False
        layout = tiled_layout(self.bases, (n, n), base.row_spacing, base.plant_spacing, block,
                              base.north_deg)
        self.undo_stack.push(ReplaceLayout(self.model, layout, (n, n), f"tile {n} x {n}"))
        return True

    def _on_tiling_chosen(self, row: int) -> None:
        n = self.tiling.itemData(row)
        if n is not None:
            self.set_tiling(int(n))

    def _confirm(self, text: str) -> bool:
        box = QMessageBox(QMessageBox.Icon.Warning, "Replace the edited layout?", text,
                          QMessageBox.StandardButton.Discard
                          | QMessageBox.StandardButton.Cancel, self)
        box.button(QMessageBox.StandardButton.Discard).setText("Replace")
        box.setDefaultButton(QMessageBox.StandardButton.Cancel)
        return box.exec() == QMessageBox.StandardButton.Discard

    # ------------------------------------------------------------------ apply, files
    def apply(self) -> None:
        """Check the edited layout and hand it on (``applied``); problems go to ``problem``."""
        self._follow_timer.stop()
        if self.model.base is None:
            return
        try:
            new = self.edited_layout()
        except LayoutError as exc:
            self.problem.emit(str(exc))
            return
        if new.warnings != self._said:
            for w in new.warnings:
                self.problem.emit(f"note: {w}")
            self._said = new.warnings
        self._applied = new.placements
        self._show_state()
        self.applied.emit(new)

    def load(self, path) -> bool:
        """Replace the layout with a layout file (undoable; asks first over edits)."""
        try:
            new = load_layout(path, self.model.plants)
        except LayoutError as exc:
            self.problem.emit(str(exc))
            return False
        edits = self.model.edits()
        if edits and not self._confirm(f"The layout file replaces every plant position: your "
                                       f"edits to {edits} plant(s) will be gone (Undo brings "
                                       "them back)."):
            return False
        self.undo_stack.push(ReplaceLayout(self.model, new, None, "load layout file"))
        return True

    def save(self, path) -> bool:
        """Write the edited layout as a layout file (atomically)."""
        try:
            save_layout(path, self.edited_layout())
        except MaizevizError as exc:
            self.problem.emit(f"cannot save the layout: {exc}")
            return False
        return True

    def _load(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Load layout", "", "Layout (*.json)")
        if path:
            self.load(path)

    def _save(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save layout", "layout.json",
                                              "Layout (*.json)")
        if path:
            self.save(path)

    # --------------------------------------------------------------------- geometry
    def resizeEvent(self, event) -> None:  # noqa: N802
        super().resizeEvent(event)
        # beside the table when there is room, above it in a narrow dock
        wide = self.width() > 1.1 * self.height() and self.width() > 560
        orientation = Qt.Orientation.Horizontal if wide else Qt.Orientation.Vertical
        if orientation != self.splitter.orientation() or not self._split:
            self.splitter.setOrientation(orientation)
            length = self.width() if wide else self.height()
            self.splitter.setSizes([int(0.6 * length), int(0.4 * length)])
            self._split = True

