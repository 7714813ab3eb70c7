"""The canopy-layout editor: where each plant stands, which digitized plant it is, its turn.

A top view of the field (:class:`FieldView`) beside the table of placements, over the study's
layout draft (:class:`maizeviz_app.layout_draft.LayoutDraft`). Edit by hand: drag a plant to
move it (on a grid when *snap* is on), turn it about its stalk with the wheel, its arrow's knob
or the rotate buttons, type in the table; add, duplicate or remove a plant. Edit by
parameters: rows x plants per row at a row and plant spacing, or a tiling of the digitized
block (the paper's 3 x 3 block tiled 3 x 3 gives its 9 x 9 canopy); replacing edited positions
asks first. Every edit is one step of the study's undo history (Edit > Undo, Ctrl+Z from
anywhere). Plants standing on each other's ground are drawn red and listed. Positions are kept
exactly as they are until edited (the table only shows them rounded), so applying an unedited
layout changes nothing.

In the window, the study decides when the layout is applied
(:meth:`maizeviz_app.model.StudyModel.apply_draft`: at every edit and undo while its
``layout_options.follow``, which "3D view follows" shows and sets, else on *Apply*); the panel
only shows the draft and says ``applied(layout)`` once the study has it. On its own (no study)
the panel says ``applied(layout)`` itself, on *Apply* or at each edit when "3D view follows"
is on. *Save*/*Load* use the layout file of the README (written atomically).
"""

from __future__ import annotations

from typing import TypeVar

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QKeySequence, QShortcut, QUndoStack
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QPushButton,
    QSizePolicy,
    QSpinBox,
    QSplitter,
    QStyle,
    QTableView,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from maizeviz.canopy.layout import LayoutError, load_layout, save_layout
from maizeviz.errors import MaizevizError
from maizeviz_app.bind import bind
from maizeviz_app.layout_draft import LayoutDraft
from maizeviz_app.options import TILINGS
from maizeviz_app.panels.field_view import FieldView
from maizeviz_app.panels.layout_model import PlacementTable, fmt

#: The rotate buttons' step, degrees.
ROTATE_STEP_DEG = 15.0
#: Overlaps listed at most (the field view draws them all).
OVERLAPS_LISTED = 50


W = TypeVar("W", bound=QWidget)


def _named(widget: W, name: str, tip: str) -> W:
    widget.setAccessibleName(name)
    widget.setToolTip(tip)
    return widget


def _count(n: int, noun: str) -> str:
    """``3, "plant"`` -> "3 plants"; one is "1 plant"."""
    return f"{n:,} {noun}{'' if n == 1 else 's'}"


def _tool(text: str) -> QToolButton:
    button = QToolButton()
    button.setText(text)
    return button


class LayoutPanel(QWidget):
    """Edit the layout of ``study`` (a :class:`~maizeviz_app.model.StudyModel`: its draft,
    shown for the points it opens; what is applied is built); without a study, a draft of
    its own. ``stack``: the undo history edits go to (the Edit menu's; default: the panel's
    own). ``applied`` carries the layout applied, ``problem`` a line for the technician (a
    refused edit, a note from the checks)."""

    applied = Signal(object)
    problem = Signal(str)

    def __init__(self, study=None, stack: QUndoStack | None = None, parent=None):
        super().__init__(parent)
        from maizeviz_app.undo import UndoRecorder

        self.study = study
        self.draft: LayoutDraft = study.draft if study is not None else LayoutDraft()
        shared = stack is not None
        if stack is None:                       # a history of the panel's own
            self._recorder = UndoRecorder(None, self, draft=self.draft)
            stack = self._recorder.stack
        self.undo_stack = stack
        self.history = study.history if study is not None else self._recorder.history
        self._said: tuple = ()
        self._applied: tuple | None = None
        self._split = False

        lay = QVBoxLayout(self)
        self.info = QLabel("no canopy")
        self.info.setWordWrap(True)
        lay.addWidget(self.info)
        lay.addLayout(self._history_bar(shared))
        lay.addWidget(self._parameters())
        lay.addLayout(self._plant_bar())

        self.overlaps = QListWidget()
        _named(self.overlaps, "overlapping plants", "plants whose ground cells (a row "
               "spacing by a plant spacing, centred on the stalk) overlap by more than a "
               "tenth of a spacing across and along the rows; click one to pick it")
        self.overlaps.setStyleSheet("color: #b3261e;")
        self.overlaps.itemClicked.connect(
            lambda item: self.select(int(item.data(Qt.ItemDataRole.UserRole))))
        self.overlaps.hide()
        # above the view: seen without scrolling the panel
        lay.addWidget(self.overlaps)

        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.view = FieldView()
        self.view.setAccessibleName("field seen from above")
        self.view.setToolTip("drag a plant to move it; the wheel or the arrow's knob turns it; "
                             "the wheel elsewhere zooms, a double click fits the field")
        self.view.moved.connect(lambda i, x, y: self._edit(self.draft.move, i, x, y))
        self.view.turned.connect(lambda i, az, wheel: self._edit(self.draft.turn, i, az, wheel))
        self.view.picked.connect(self._on_picked)
        self.table = QTableView()
        _named(self.table, "plant positions", "each plant's position (cm), digitized plant "
               "and turn (°); type to edit (exactly: the table shows values rounded)")
        self.rows = PlacementTable(self.draft, self.problem.emit, self)
        self.table.setModel(self.rows)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.verticalHeader().setDefaultSectionSize(22)
        # fixed rows: 700 rows stay fast
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Fixed)
        self.table.selectionModel().currentRowChanged.connect(
            lambda cur, _prev: self._on_selected(cur.row()))
        self.splitter.addWidget(self.view)
        self.splitter.addWidget(self.table)
        self.splitter.setStretchFactor(0, 3)
        self.splitter.setStretchFactor(1, 2)
        # the view and table take what the dock leaves, down to their minimum, and ask for no
        # more: a height asked for the sizes the splitter was given (60 % / 40 % of the
        # panel's own height) made the panel taller than a laptop's dock, its state and
        # Apply below the bottom edge
        self.splitter.setSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Ignored)
        self.splitter.setMinimumHeight(self.view.minimumHeight() + 80)
        lay.addWidget(self.splitter, 1)

        row = QHBoxLayout()
        self.state = QLabel("")
        self.state.setWordWrap(True)
        row.addWidget(self.state, 1)
        self.apply_button = QPushButton("Apply")
        _named(self.apply_button, "Apply", "check the layout and rebuild the canopy with it")
        self.apply_button.clicked.connect(self.apply)
        self.load_button = _named(QPushButton("Load…"), "Load…", "replace the layout with a "
                                  "layout file (JSON, see the README)")
        self.load_button.clicked.connect(self._load)
        self.save_button = _named(QPushButton("Save…"), "Save…", "write the edited layout as "
                                  "a layout file (JSON)")
        self.save_button.clicked.connect(self._save)
        for b in (self.apply_button, self.load_button, self.save_button):
            row.addWidget(b)
        lay.addLayout(row)

        self._sync_buttons()
        self.draft.changed.connect(self._on_changed)
        self.draft.edited.connect(self._on_edit)
        self.draft.replayed.connect(self._on_edit)
        self.destroyed.connect(lambda *_: self._forget(self.draft))
        self._overlap_timer = QTimer(self, singleShot=True, interval=60)
        self._overlap_timer.timeout.connect(self._show_overlaps)
        if study is not None:
            bind(self.follow, study.layout_options, "follow")
            study.layout_changed.connect(self._on_applied)
            study.mesh_opened.connect(self._on_mesh)
            study.points_changed.connect(self._on_points)
        if self.draft.base is not None:
            self._on_changed(-1)

    def _forget(self, draft: LayoutDraft) -> None:
        for signal, slot in ((draft.changed, self._on_changed), (draft.edited, self._on_edit),
                             (draft.replayed, self._on_edit)):
            try:
                signal.disconnect(slot)
            except (ValueError, RuntimeError):
                pass

    # ------------------------------------------------------------------ building
    def _history_bar(self, shared: bool) -> QHBoxLayout:
        bar = QHBoxLayout()
        bar.addWidget(QLabel("tiling"))
        self.tiling = QComboBox()
        _named(self.tiling, "tiling", "repeat the digitized block; the paper tiles its 3 x 3 "
               "block 3 x 3 times (9 x 9 plants)")
        self.tiling.activated.connect(self._on_tiling_chosen)
        self.tiling.setSizeAdjustPolicy(
            QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.tiling.setMinimumContentsLength(10)
        bar.addWidget(self.tiling, 1)
        self.undo_action = self.undo_stack.createUndoAction(self, "Undo")
        self.redo_action = self.undo_stack.createRedoAction(self, "Redo")
        for action, icon, keys in (
                (self.undo_action, QStyle.StandardPixmap.SP_ArrowBack,
                 [QKeySequence(QKeySequence.StandardKey.Undo)]),
                (self.redo_action, QStyle.StandardPixmap.SP_ArrowForward,
                 [QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])):
            if not shared:                       # the Edit menu's shortcuts act everywhere
                action.setShortcuts(keys)
                action.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
                self.addAction(action)
            action.setIcon(self.style().standardIcon(icon))
            button = QToolButton()
            button.setDefaultAction(action)
            button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonIconOnly)
            button.setAccessibleName(action.text().split(" ")[0])
            bar.addWidget(button)
        return bar

    def _parameters(self) -> QGroupBox:
        """Rows x plants per row at a row and a plant spacing: a regular field."""
        box = QGroupBox("rows x plants")
        grid = QGridLayout(box)
        self.rows_box = _named(QSpinBox(minimum=1, maximum=1000, value=3), "rows",
                               "rows of plants (across x)")
        self.per_row_box = _named(QSpinBox(minimum=1, maximum=1000, value=3),
                                  "plants per row", "plants in each row (along y)")
        self.row_spacing_box = _named(
            QDoubleSpinBox(decimals=1, minimum=1.0, maximum=1000.0, value=60.0, suffix=" cm"),
            "row spacing", "distance between rows, cm (the paper: 60)")
        self.plant_spacing_box = _named(
            QDoubleSpinBox(decimals=1, minimum=1.0, maximum=1000.0, value=30.0, suffix=" cm"),
            "plant spacing", "distance between the plants of a row, cm (the paper: 30)")
        self.lay_out_button = _named(QPushButton("Lay out"), "Lay out",
                                     "replace the layout with rows x plants at these "
                                     "spacings, the digitized block repeated")
        self.lay_out_button.clicked.connect(self.lay_out)
        grid.addWidget(QLabel("rows"), 0, 0)
        grid.addWidget(self.rows_box, 0, 1)
        grid.addWidget(QLabel("× plants"), 0, 2)
        grid.addWidget(self.per_row_box, 0, 3)
        grid.addWidget(QLabel("spacing"), 1, 0)
        grid.addWidget(self.row_spacing_box, 1, 1)
        grid.addWidget(QLabel("×"), 1, 2, alignment=Qt.AlignmentFlag.AlignCenter)
        grid.addWidget(self.plant_spacing_box, 1, 3)
        grid.addWidget(self.lay_out_button, 0, 4, 2, 1)
        # the boxes show the layout's grid as most of its rows are; this says what is not
        self.grid_note = _named(QLabel(), "irregular grid",
                                "the layout is not a full rows x plants grid")
        self.grid_note.setWordWrap(True)
        self.grid_note.hide()
        grid.addWidget(self.grid_note, 2, 0, 1, 5)
        grid.setColumnStretch(1, 1)
        grid.setColumnStretch(3, 1)
        return box

    def _plant_bar(self) -> QVBoxLayout:
        """Add, duplicate, remove, rotate the plant picked; snap; the view following."""
        rows = QVBoxLayout()
        bar = QHBoxLayout()
        self.add_button = _named(QPushButton("Add"), "Add", "a new plant one plant spacing "
                                 "beyond the end of the picked plant's row (or the last row)")
        self.add_button.clicked.connect(self.add_plant)
        self.duplicate_button = _named(QPushButton("Duplicate"), "Duplicate",
                                       "a copy of the picked plant (the same plant, turned "
                                       "the same) at the end of its row")
        self.duplicate_button.clicked.connect(
            lambda: self._edit(self.draft.duplicate, self.picked, select_new=True))
        self.remove_button = _named(QPushButton("Remove"), "Remove", "take the picked plant "
                                    "out of the layout (Delete)")
        self.remove_button.clicked.connect(lambda: self._edit(self.draft.remove, self.picked))
        # Delete removes the picked plant only while the layout editor has the focus (a
        # button's shortcut is the whole window's: Delete in the 3D view removed a plant)
        self.remove_shortcut = QShortcut(QKeySequence(QKeySequence.StandardKey.Delete), self)
        self.remove_shortcut.setContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
        self.remove_shortcut.activated.connect(self.remove_button.click)
        self.left_button = _named(_tool("⟲"), "rotate left",
                                  f"turn the picked plant {ROTATE_STEP_DEG:g}° about its "
                                  "stalk, counter-clockwise seen from above")
        self.left_button.clicked.connect(
            lambda: self._edit(self.draft.rotate, self.picked, ROTATE_STEP_DEG))
        self.right_button = _named(_tool("⟳"), "rotate right",
                                   f"turn the picked plant {ROTATE_STEP_DEG:g}° about its "
                                   "stalk, clockwise seen from above")
        self.right_button.clicked.connect(
            lambda: self._edit(self.draft.rotate, self.picked, -ROTATE_STEP_DEG))
        for b in (self.add_button, self.duplicate_button, self.remove_button,
                  self.left_button, self.right_button):
            bar.addWidget(b)
        rows.addLayout(bar)
        bar2 = QHBoxLayout()
        self.snap = _named(QCheckBox("snap to a grid of"), "snap to a grid of",
                           "plants dragged, added or duplicated land on a grid")
        self.snap_step = _named(QDoubleSpinBox(decimals=1, minimum=0.5, maximum=100.0,
                                               value=5.0, suffix=" cm"),
                                "grid step", "the snapping grid's step, cm")
        self.snap.toggled.connect(self._on_snap)
        self.snap_step.valueChanged.connect(self._on_snap)
        self.follow = _named(QCheckBox("3D view follows"), "3D view follows",
                             "rebuild the canopy after each edit")
        self.follow.setChecked(True)
        bar2.addWidget(self.snap)
        bar2.addWidget(self.snap_step)
        bar2.addStretch(1)
        bar2.addWidget(self.follow)
        rows.addLayout(bar2)
        return rows

    # ------------------------------------------------------------------ the study
    def _on_points(self, loaded) -> None:
        self.setEnabled(True)
        self._applied = tuple(loaded.layout.placements)
        self._said = ()
        self._show_state()

    def _on_applied(self, layout) -> None:
        """The study applied a layout (an edit followed, *Apply*, a script)."""
        self._applied = tuple(layout.placements)
        self._show_state()
        self.applied.emit(layout)

    def _on_mesh(self, _path: str) -> None:
        self.setEnabled(False)                  # a mesh file's canopy has no layout to edit

    @property
    def layout_(self):
        return self.draft.base

    @property
    def plants(self) -> set[int]:
        return self.draft.plants

    def show_layout(self, layout, plants: set[int],
                    bases: dict[int, tuple[float, float]] | None = None) -> None:
        """A new canopy: its layout, the ids of its digitized plants and their stalk bases
        (cm, for the tiling presets; read from the layout's central tile when it is a tiling
        and they are not given). Clears the undo history."""
        self.history.clear()
        self._applied = tuple(layout.placements)
        self._said = ()
        self.draft.start(layout, plants, bases)

    def document(self) -> dict:
        """The edited layout as a layout document (schema 1)."""
        return self.draft.document()

    def edited_layout(self):
        """The edited layout, checked (raises LayoutError naming the problem)."""
        return self.draft.layout()

    # ------------------------------------------------------------------ showing
    def _on_changed(self, index: int) -> None:
        base = self.draft.base
        if index >= 0:
            self.view.update_plant(index, self.draft.placements[index])
        else:
            picked = self.picked
            self.view.show_layout(base, self.draft.placements)
            self._fill_tilings()
            self._fill_parameters()
            if 0 <= picked < len(self.draft.placements):
                self.select(picked)
        self._overlap_timer.start()
        self._sync_buttons()
        if base is None:
            self.info.setText("no canopy")
            return
        x0, y0, x1, y1 = base.bounds
        self.info.setText(
            f"{_count(len(self.draft.placements), 'plant')} on "
            f"{fmt(base.ground_area_cm2 / 1e4, 2)} m², "
            f"field x {fmt(x0, 0)}..{fmt(x1, 0)} cm, y {fmt(y0, 0)}..{fmt(y1, 0)} cm; rows "
            f"{base.row_spacing:g} cm apart, plants {base.plant_spacing:g} cm")
        self._show_state()

    def _show_state(self) -> None:
        edits = self.draft.edits()
        applied = self._applied == tuple(self.draft.placements)
        text = f"{edits} plant{'s' if edits != 1 else ''} edited"
        self.state.setText(text + ("" if applied else " · not applied yet"))
        # the whole state where the dock is narrow: the label wraps, the tooltip says it all
        self.state.setToolTip(f"{text} since the layout was opened or tiled; "
                              + ("the canopy is built with it" if applied else
                                 "Apply rebuilds the canopy with it"))

    def _show_overlaps(self) -> None:
        """Plants standing on each other's ground: red in the view and the table, listed."""
        pairs = self.draft.overlaps()
        involved = {i for i, j, _d in pairs} | {j for i, j, _d in pairs}
        self.view.set_overlapping(involved)
        self.rows.overlapping = involved
        if self.rows.rowCount():
            self.rows.dataChanged.emit(self.rows.index(0, 0),
                                       self.rows.index(self.rows.rowCount() - 1, 3))
        self.overlaps.clear()
        for i, j, _d in pairs[:OVERLAPS_LISTED]:
            text = self.draft.overlap_text(i, j)
            item = QListWidgetItem(text)
            base = self.draft.base
            if base is not None:
                item.setToolTip(f"{text}; a ground cell is {base.row_spacing:g} x "
                                f"{base.plant_spacing:g} cm, centred on the stalk")
            item.setData(Qt.ItemDataRole.UserRole, j)
            self.overlaps.addItem(item)
        if len(pairs) > OVERLAPS_LISTED:
            self.overlaps.addItem(f"… and {_count(len(pairs) - OVERLAPS_LISTED, 'more pair')}")
        if pairs:                               # as tall as its lines, three at most
            rows = min(self.overlaps.count(), 3)
            self.overlaps.setFixedHeight(rows * self.overlaps.sizeHintForRow(0)
                                         + 2 * self.overlaps.frameWidth() + 2)
        self.overlaps.setVisible(bool(pairs))

    def _fill_tilings(self) -> None:
        self.tiling.blockSignals(True)
        self.tiling.clear()
        block = self.draft.block()
        for n in TILINGS:
            if block is None:
                break
            text = f"{n} x {n} tiles: {block[0] * n} x {block[1] * n} plants"
            if n == 1:
                text += " (the digitized block)"
            elif n == 3 and block == (3, 3):
                text += " (the paper)"
            self.tiling.addItem(text, n)
        current = self.draft.tiling
        if current is not None and current[0] == current[1] and current[0] in TILINGS \
                and block is not None:
            self.tiling.setCurrentIndex(TILINGS.index(current[0]))
        else:
            self.tiling.addItem(self.draft.source or ("from a layout file" if current is None
                                                      else f"{current[0]} x {current[1]} "
                                                      "tiles"), None)
            self.tiling.setCurrentIndex(self.tiling.count() - 1)
        self.tiling.setEnabled(block is not None)
        self.tiling.blockSignals(False)

    def _fill_parameters(self) -> None:
        """The parameter fields say the layout shown: its rows x plants and spacings."""
        base = self.draft.base
        if base is None:
            return
        rows, per_row = self.draft.grid()
        self.rows_box.setValue(rows)
        self.per_row_box.setValue(per_row)
        note = self.draft.grid_note()
        self.grid_note.setText(note)
        self.grid_note.setVisible(bool(note))
        self.row_spacing_box.setValue(base.row_spacing)
        self.plant_spacing_box.setValue(base.plant_spacing)

    def _sync_buttons(self) -> None:
        picked = 0 <= self.picked < len(self.draft.placements)
        for b in (self.duplicate_button, self.remove_button, self.left_button,
                  self.right_button):
            b.setEnabled(picked)
        self.add_button.setEnabled(self.draft.base is not None)

    # ------------------------------------------------------------------ picking
    @property
    def picked(self) -> int:
        """The placement picked (the table's current row), -1 when none."""
        index = self.table.currentIndex()
        return index.row() if index.isValid() else -1

    def select(self, index: int) -> None:
        """Pick placement ``index`` in the table and the view."""
        if 0 <= index < self.rows.rowCount():
            self.table.selectRow(index)

    def _on_picked(self, index: int) -> None:
        self.table.selectRow(index)

    def _on_selected(self, index: int) -> None:
        self.view.select(index)
        self._sync_buttons()

    # ------------------------------------------------------------------ edits
    def _edit(self, action, *args, select_new: bool = False) -> bool:
        """An edit of the draft; one refused is said (``problem``) and changes nothing."""
        try:
            done = action(*args)
        except (LayoutError, IndexError) as exc:
            self.problem.emit(f"layout: {exc}")
            return False
        if done and select_new:
            self.select(len(self.draft.placements) - 1)
        return bool(done)

    def _on_edit(self, *_edit) -> None:
        self._show_state()
        if self.study is None and self.follow.isChecked():
            self.apply()                        # in the window, the study applies it

    def _on_snap(self, *_args) -> None:
        self.draft.snap_cm = self.snap_step.value() if self.snap.isChecked() else 0.0

    def add_plant(self) -> bool:
        """A new plant (the lowest digitized plant id) one plant spacing beyond the end of
        the picked plant's row (or of the last row); it is picked."""
        ps = self.draft.placements
        if self.draft.base is None or not ps:
            return False
        at = self.picked if 0 <= self.picked < len(ps) else \
            max(range(len(ps)), key=lambda i: ps[i].x)
        return self._edit(self.draft.add, *self.draft.row_end(at), select_new=True)

    def lay_out(self) -> bool:
        """Rows x plants at the spacings typed (asks first over edits)."""
        if not self._replace_ok("The new rows x plants replace every plant position"):
            return False
        return self._edit(self.draft.regular, self.rows_box.value(), self.per_row_box.value(),
                          self.row_spacing_box.value(), self.plant_spacing_box.value())

    def set_tiling(self, n: int) -> bool:
        """Tile the digitized block ``n`` x ``n`` times; asks first when it would replace
        edited positions. Returns whether the tiling changed."""
        if self.draft.block() is None or self.draft.tiling == (n, n) or \
                not self._replace_ok("The new tiling replaces every plant position"):
            self._fill_tilings()
            return False
        return self._edit(self.draft.tile, n)

    def _replace_ok(self, what: str) -> bool:
        edits = self.draft.edits()
        return not edits or self._confirm(
            f"{what}: your edits to {edits} plant{'s' if edits != 1 else ''} will be gone "
            "(Undo brings them back).")

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
        """Check the edited layout and hand it on: to the study (which says any problem), or
        on its own as ``applied`` (problems go to ``problem``)."""
        if self.study is not None:
            self.study.apply_draft()
            return
        if self.draft.base is None:
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
            new = load_layout(path, self.draft.plants)
        except LayoutError as exc:
            self.problem.emit(str(exc))
            return False
        if not self._replace_ok("The layout file replaces every plant position"):
            return False
        return self._edit(self.draft.replace_layout, new, None, "load layout file")

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
