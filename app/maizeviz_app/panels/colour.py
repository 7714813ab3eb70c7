"""Colour: the range, colour map and log scale of the 3D view's light colours and of the
heatmaps, bound both ways to the study's :class:`~maizeviz_app.colour.ColourSettings` (a
change in the settings, from a project or a script, shows here; a change here goes to the
settings, and the views follow them)."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext

from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QSizePolicy,
    QVBoxLayout,
    QWidget,
)

from maizeviz_app.colour import CMAPS, PAINTINGS, RANGES, ColourError, ColourScale, tick_text


def _named(widget: QWidget, name: str, tip: str) -> QWidget:
    """A control with its accessible name (what screen readers say, and tests find it by) and
    tooltip; a combo box as narrow as the dock needs (its longest choice may be cut)."""
    widget.setAccessibleName(name)
    widget.setToolTip(tip)
    if isinstance(widget, QComboBox):
        widget.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        widget.setMinimumContentsLength(8)
    return widget


class ScaleEditor(QGroupBox):
    """The controls of one :class:`ColourScale`: range (auto, typed, percentile clip), min and
    max, the clip, the colour map, log. In auto and percentile ranges the min and max show the
    range in use (:meth:`show_limits`), so that switching to a typed range starts from it.
    ``step()``: a context whose edits are one step of the undo history (a range and its limits
    together; :meth:`maizeviz_app.history.History.step`)."""

    def __init__(self, title: str, scale: ColourScale, parent=None,
                 step: Callable[[], AbstractContextManager] = nullcontext):
        super().__init__(title, parent)
        self.scale = scale
        self.step = step
        self._shown: tuple[float, float] | None = None
        self.form = form = QFormLayout(self)
        form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        self.range = QComboBox()
        for key, text in RANGES.items():
            self.range.addItem(text, key)
        _named(self.range, f"{title} range",
               "auto: from the smallest to the largest value shown; typed: the min and max "
               "below; percentile clip: leave out a share of the values at each end")
        form.addRow("Range", self.range)
        limits = QHBoxLayout()
        self.vmin, self.vmax = QDoubleSpinBox(), QDoubleSpinBox()
        for box, end in ((self.vmin, "min"), (self.vmax, "max")):
            box.setDecimals(4)
            box.setRange(-1e6, 1e6)
            box.setKeyboardTracking(False)          # applied on Enter or leaving the field
            box.setSingleStep(0.05)
            box.setMinimumWidth(70)
            box.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)
            verb = "starts" if end == "min" else "ends"
            _named(box, f"{title} {end}", f"the value the colour map {verb} at (a typed "
                                          "range); values beyond take the end colour")
            limits.addWidget(box, 1)
        dash = QLabel("to")
        limits.insertWidget(1, dash)
        form.addRow("Min, max", limits)
        self.clip = QDoubleSpinBox()
        self.clip.setRange(0.0, 49.0)
        self.clip.setDecimals(1)
        self.clip.setSuffix(" %")
        self.clip.setKeyboardTracking(False)
        _named(self.clip, f"{title} clip each end",
               "percent of the values left out at each end (percentile clip): a few bright "
               "or dark bins do not flatten the rest")
        form.addRow("Clip each end", self.clip)
        self.cmap = QComboBox()
        self.cmap.addItems(list(CMAPS))
        _named(self.cmap, f"{title} colour map",
               "viridis and cividis read in order and for colour-blind eyes; inferno; greys "
               "from black (least) to white (most)")
        form.addRow("Colour map", self.cmap)
        self.log = QCheckBox("log scale")
        _named(self.log, f"{title} log scale", "colours spaced by the logarithm of the value: "
                                               "small values spread out")
        form.addRow("", self.log)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        form.addRow(self.note)

        self.range.currentIndexChanged.connect(lambda _i: self._set_range())
        self.vmin.valueChanged.connect(lambda _v: self._set_limits())
        self.vmax.valueChanged.connect(lambda _v: self._set_limits())
        self.clip.valueChanged.connect(lambda v: self._apply(clip=float(v)))
        self.cmap.currentTextChanged.connect(lambda t: self._apply(cmap=t))
        self.log.toggled.connect(lambda on: self._apply(log=bool(on)))
        scale.events.connect(self._follow)
        self._follow()

    # ------------------------------------------------------------------ widget -> scale
    def _apply(self, **changes) -> bool:
        """Set ``changes`` on the scale if they make a usable scale, else say why here."""
        trial = ColourScale(**{**self.scale.to_doc(), **changes})
        try:
            trial.check()
        except ColourError as exc:
            self.note.setText(f"<span style='color:#b3261e'>{exc}</span>")
            return False
        with self.step(), self.scale.events.paused():     # one step, one repaint
            for name, value in changes.items():
                setattr(self.scale, name, value)
        self._follow()
        return True

    def _set_range(self) -> None:
        key = self.range.currentData()
        if key == "fixed" and self.scale.range != "fixed" and self._shown is not None:
            lo, hi = self._shown                       # start from the range in use
            if not self._apply(range=key, vmin=lo, vmax=hi):
                self._follow()
            return
        if not self._apply(range=key):
            self._follow()

    def _set_limits(self) -> None:
        if self.range.currentData() != "fixed":
            return
        if not self._apply(vmin=float(self.vmin.value()), vmax=float(self.vmax.value())):
            return                                     # the note says why; the view waits

    # ------------------------------------------------------------------ scale -> widget
    def _follow(self, *_args) -> None:
        s = self.scale
        widgets = (self.range, self.vmin, self.vmax, self.clip, self.cmap, self.log)
        for w in widgets:
            w.blockSignals(True)
        self.range.setCurrentIndex(max(self.range.findData(s.range), 0))
        fixed = s.range == "fixed"
        if fixed or self._shown is None:
            self.vmin.setValue(s.vmin)
            self.vmax.setValue(s.vmax)
        else:
            self.vmin.setValue(self._shown[0])
            self.vmax.setValue(self._shown[1])
        self.vmin.setEnabled(fixed)
        self.vmax.setEnabled(fixed)
        self.clip.setValue(s.clip)
        self.clip.setEnabled(s.range == "percentile")
        self.cmap.setCurrentText(s.cmap)
        self.log.setChecked(s.log)
        for w in widgets:
            w.blockSignals(False)
        self._say()

    def show_limits(self, lo: float, hi: float) -> None:
        """The range the view uses now (shown in the min and max when not typed)."""
        self._shown = (float(lo), float(hi))
        self._follow()

    def _say(self) -> None:
        if self._shown is None:
            self.note.setText("")
            return
        lo, hi = self._shown
        self.note.setText(f"colours span {tick_text(lo)} to {tick_text(hi)}"
                          + (", log scale" if self.scale.log else ""))


class ColourPanel(QWidget):
    """The colours of the 3D view and of the heatmaps, over ``settings`` (a
    :class:`~maizeviz_app.colour.ColourSettings`); ``step`` as :class:`ScaleEditor`'s."""

    def __init__(self, settings, parent=None,
                 step: Callable[[], AbstractContextManager] = nullcontext):
        super().__init__(parent)
        self.settings = settings
        lay = QVBoxLayout(self)
        self.view_editor = ScaleEditor("3D view", settings.view, step=step)
        self.painting = QComboBox()
        for key, text in PAINTINGS.items():
            self.painting.addItem(text, key)
        _named(self.painting, "sun painted as",
               "a sun's light on the canopy: each triangle's class (direct, second class, "
               "none) where triangles are large enough for rays to sample each, else the "
               "sunlit share of each leaf")
        self.view_editor.form.addRow("Sun painted as", self.painting)
        self.painting_note = QLabel("")
        self.painting_note.setWordWrap(True)
        self.view_editor.form.addRow(self.painting_note)
        lay.addWidget(self.view_editor)
        self.heatmap_editor = ScaleEditor("Heatmaps", settings.heatmap, step=step)
        self.shared = QCheckBox("one scale for every height and light")
        _named(self.shared, "one scale for every height and light",
               "the heatmaps of every height and every light shown take one range, so their "
               "colours compare")
        self.heatmap_editor.form.addRow("", self.shared)
        lay.addWidget(self.heatmap_editor)
        lay.addStretch(1)
        self.painting.currentIndexChanged.connect(
            lambda _i: setattr(settings, "painting", self.painting.currentData()))
        self.shared.toggled.connect(lambda on: setattr(settings, "shared", bool(on)))
        settings.events.connect(self._follow)
        self._follow()

    def show_painting(self, note: str) -> None:
        """What the 3D view paints of a sun and why."""
        self.painting_note.setText(note)

    def _follow(self, *_args) -> None:
        for w in (self.painting, self.shared):
            w.blockSignals(True)
        self.painting.setCurrentIndex(max(self.painting.findData(self.settings.painting), 0))
        self.shared.setChecked(self.settings.shared)
        for w in (self.painting, self.shared):
            w.blockSignals(False)
