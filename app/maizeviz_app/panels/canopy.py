"""The canopy panel: the points file, area preservation, the mesh-complexity slider and Table 2.
(The tiling is chosen in the layout panel, its one place.)

The slider and the area-preservation box are bound to the study's canopy settings
(:class:`maizeviz_app.settings.CanopySettings`): the slider sets the level once it rests, and
a level set elsewhere (a project, an undo, a refused build) moves it. The slider says what is
asked; the level label says what the 3D view shows. Both change together with the table when
the study shows a built canopy (:meth:`CanopyPanel.show_built`), so the label never names a
level the view does not show yet.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QItemSelectionModel, Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QSizePolicy,
    QSlider,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from maizeviz.mesh.levels import COMPLEXITY_STOPS, parse_level
from maizeviz_app.bind import bind
from maizeviz_app.building import MESH_LEVEL
from maizeviz_app.settings import StudySettings

#: What the slider does.
SLIDER_TIP = ("fine (K=4, the paper's reference mesh) to coarse (4 triangles per leaf); the "
              "canopy is rebuilt when the slider rests")


def describe(level: str) -> str:
    """A slider stop in words."""
    if level == MESH_LEVEL:
        return "the mesh file's triangles"
    return parse_level(level).description


class CanopyPanel(QWidget):
    """The points file, the slider and Table 2 of the study in ``study`` (a
    :class:`~maizeviz_app.model.StudyModel`, followed: new points clear the table, a built
    canopy shows its level and row). Without a study the panel edits ``settings`` (default:
    settings of its own).

    Signals: ``open_requested()``."""

    open_requested = Signal()

    def __init__(self, study=None, settings: StudySettings | None = None, parent=None):
        super().__init__(parent)
        self.study = study
        self.settings = study.settings if study is not None else settings or StudySettings()
        canopy = self.settings.canopy
        lay = QVBoxLayout(self)
        row = QHBoxLayout()
        self.file_label = QLabel("no file")
        self.file_label.setWordWrap(True)
        self.file_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.open_button = QPushButton("Open points…")
        self.open_button.setToolTip("open a digitized points CSV (Ctrl+O)")
        self.open_button.clicked.connect(self.open_requested)
        row.addWidget(self.file_label, 1)
        row.addWidget(self.open_button)
        lay.addLayout(row)
        form = QFormLayout()
        self.preserve = QCheckBox("keep leaf area below the standard mesh")
        self.preserve.setToolTip("widen the kept cross-sections so a coarse leaf keeps the "
                                 "reference mesh's area (off: the paper's plain splitting)")
        bind(self.preserve, canopy, "preserve_area")
        form.addRow(self.preserve)
        lay.addLayout(form)

        group = QGroupBox("mesh complexity")
        g = QVBoxLayout(group)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, len(COMPLEXITY_STOPS) - 1)
        self.slider.setValue(COMPLEXITY_STOPS.index(canopy.level))
        self.slider.setAccessibleName("mesh complexity")
        self.slider.setTickPosition(QSlider.TickPosition.TicksBelow)
        self.slider.setPageStep(1)
        self.slider.setToolTip(SLIDER_TIP)
        ends = QHBoxLayout()
        ends.addWidget(QLabel("fine: K=4"))
        ends.addStretch(1)
        ends.addWidget(QLabel("coarse: 4 triangles"))
        g.addWidget(self.slider)
        g.addLayout(ends)
        self.asked_label = QLabel("")
        self.asked_label.setStyleSheet("color: #555;")
        self.level_label = QLabel("no canopy yet")
        self.level_label.setWordWrap(True)
        self.level_label.setStyleSheet("font-weight: bold;")
        g.addWidget(self.level_label)
        g.addWidget(self.asked_label)
        lay.addWidget(group)
        lay.addWidget(QLabel("canopy measures per level (the paper's Table 2)"))
        self.table = QTableWidget(0, 0)
        self.table.setAccessibleName("canopy measures per level")
        self.table.setToolTip("each level built: its triangles, leaf area, area projected on "
                              "the ground, ground cover, leaf area index and build time")
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        lay.addWidget(self.table, 1)
        self.rows: dict[str, list[str]] = {}
        self.columns: list[str] = []
        self._debounce = QTimer(self, singleShot=True, interval=250)
        self._debounce.timeout.connect(self._commit_level)
        self.slider.valueChanged.connect(self._on_slider)
        canopy.events.level.connect(self.set_level)
        self.destroyed.connect(lambda *_: canopy.events.level.disconnect(self.set_level))
        if study is not None:
            self._follow(study)

    # ------------------------------------------------------------------ state
    @property
    def level(self) -> str:
        """The slider's stop (``"K4"`` ... ``"4"``)."""
        return COMPLEXITY_STOPS[self.slider.value()]

    def set_level(self, level: str, *_old) -> None:
        """Move the slider to the level set (a project, an undo, a refused build) without
        asking for it again."""
        if level in COMPLEXITY_STOPS:
            self._debounce.stop()
            self.slider.blockSignals(True)
            self.slider.setValue(COMPLEXITY_STOPS.index(level))
            self.slider.blockSignals(False)

    def _commit_level(self) -> None:
        """The slider rested: its stop becomes the level set (which rebuilds the canopy)."""
        self.settings.canopy.level = self.level

    def _follow(self, study) -> None:
        study.points_changed.connect(self._on_points)
        study.mesh_opened.connect(self._on_mesh)
        study.canopy_changed.connect(
            lambda built: self.show_built(built.level, list(built.columns), built.row))
        study.build_pending.connect(self.set_pending)

    def _on_mesh(self, path: str) -> None:
        self.clear_rows()
        self.set_file(Path(path).name, path)
        self.slider.setEnabled(False)
        self.slider.setToolTip("a canopy read from a mesh file has one level: the file's "
                               "triangles (open digitized points to choose a level)")
        self.preserve.setEnabled(False)

    def _on_points(self, loaded) -> None:
        self.slider.setEnabled(True)
        self.slider.setToolTip(SLIDER_TIP)
        self.preserve.setEnabled(True)
        self.clear_rows()
        from_project = self.study.project_path is not None
        self.set_file(loaded.shown_name if from_project else Path(loaded.shown_name).name,
                      loaded.path)

    def set_file(self, name: str, tooltip: str = "") -> None:
        self.file_label.setText(name)
        self.file_label.setToolTip(tooltip or name)

    def _on_slider(self, _value: int) -> None:
        self.asked_label.setText(f"asked: {describe(self.level)}")
        self._debounce.start()

    def set_pending(self, text: str) -> None:
        """What is being built (empty when the view shows what the slider asks)."""
        self.asked_label.setText(text)

    # ------------------------------------------------------------------ results
    def clear_rows(self) -> None:
        self.rows.clear()
        self.table.setRowCount(0)

    def show_built(self, level: str, columns: list[tuple[str, str]], row: dict[str, str]) -> None:
        """A new canopy is on screen: its level label and its Table 2 row, together."""
        self.level_label.setText(f"showing: {describe(level)}")
        self.asked_label.setText("")
        # units on a second line: the table fits a 400 px panel without scrolling sideways
        # a word a line in the headers, the level wrapped in its cell: the table fits a
        # 400 px panel (1366 x 768) without scrolling sideways
        headers = [h.replace(" ", "\n") for _, h in columns]
        if headers != self.columns:
            self.columns = headers
            self.table.setColumnCount(len(headers))
            self.table.setHorizontalHeaderLabels(headers)
            head = self.table.horizontalHeader()
            head.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
            head.setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        values = [row[k] for k, _ in columns]
        self.rows[values[0]] = values
        self.table.setRowCount(len(self.rows))
        for r, vals in enumerate(self.rows.values()):
            for c, v in enumerate(vals):
                item = QTableWidgetItem(v)
                align = Qt.AlignmentFlag
                item.setTextAlignment((align.AlignLeft if c == 0 else align.AlignRight)
                                      | align.AlignVCenter)
                self.table.setItem(r, c, item)
        self.table.resizeRowsToContents()
        shown = list(self.rows).index(values[0])
        # the level shown alone: selectRow follows the keyboard's modifiers, and with Ctrl
        # held (Ctrl+Z undoing a level) it added the row to the last one
        flags = QItemSelectionModel.SelectionFlag
        self.table.selectionModel().select(
            self.table.model().index(shown, 0), flags.ClearAndSelect | flags.Rows)
