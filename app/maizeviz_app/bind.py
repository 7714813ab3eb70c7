"""Widgets bound to evented settings both ways (as napari's ``QtDims`` mirrors ``Dims``).

:func:`bind` connects one widget to one field of a settings group
(:mod:`maizeviz_app.settings`): the user's edit sets the field; a change of the field (a
project opened, an undo, a script) sets the widget, without the widget echoing it back. The
widget gets the field's range where it has one, and an accessible name (its label, what screen
readers say and tests find it by) when it has none yet.

Ctrl+Z and Ctrl+Shift+Z in a bound spin box or line edit are the study's Undo and Redo (the
Edit menu's), not the box's own undo of its text: what was typed is already a step of the
study's history (:mod:`maizeviz_app.history`), and the box's undo would change the text
without the history knowing.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from PySide6.QtCore import QDate, QEvent, QObject, QSignalBlocker
from PySide6.QtGui import QKeyEvent, QKeySequence
from PySide6.QtWidgets import (
    QAbstractButton,
    QAbstractSpinBox,
    QButtonGroup,
    QCheckBox,
    QComboBox,
    QDateEdit,
    QDoubleSpinBox,
    QGroupBox,
    QLineEdit,
    QSpinBox,
    QWidget,
)

from maizeviz_app.settings import field_range


def bind(widget: QWidget, group: Any, name: str, label: str = "") -> None:
    """Keep ``widget`` and ``group.<name>`` equal, both ways (see the module docstring).

    Supported: spin boxes (value), line edits (text as typed), check boxes and checkable
    group boxes (checked), combo boxes (the item whose data is the value), date edits
    (``YYYY-MM-DD``). ``label``: the accessible name, if the widget has none.
    """
    setter = _attach(widget, group, name)

    def follow(value: Any, *_old: Any) -> None:
        with QSignalBlocker(widget):
            setter(value)

    getattr(group.events, name).connect(follow)
    widget.destroyed.connect(lambda *_: _disconnect(group, name, follow))
    if label and not widget.accessibleName():
        widget.setAccessibleName(label)
    if isinstance(widget, QAbstractSpinBox):
        widget.setKeyboardTracking(True)
    if isinstance(widget, (QAbstractSpinBox, QLineEdit)):
        widget.installEventFilter(_study_undo_keys(widget))


class _StudyUndoKeys(QObject):
    """Lets Undo and Redo keys pass a text box to the window's shortcuts."""

    KEYS = (QKeySequence.StandardKey.Undo, QKeySequence.StandardKey.Redo)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802 - Qt's name
        if event.type() == QEvent.Type.ShortcutOverride and isinstance(event, QKeyEvent) \
                and any(event.matches(k) for k in self.KEYS):
            event.ignore()                      # not overridden: the shortcut runs
            return True
        return False


def _study_undo_keys(widget: QWidget) -> _StudyUndoKeys:
    """The filter, one per application (parented to it, so it lives as long)."""
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance()
    found = app.findChild(_StudyUndoKeys) if app is not None else None
    if found is None:
        found = _StudyUndoKeys(app if app is not None else widget)
    return found


def _attach(widget: QWidget, group: Any, name: str) -> Callable[[Any], None]:
    """Show ``group.<name>`` in ``widget`` and send the user's edits to it; returns the
    widget's setter (the model's changes shown)."""
    setter: Callable[[Any], None]
    if isinstance(widget, (QDoubleSpinBox, QSpinBox)):
        _set_range(widget, group, name)
        widget.setValue(getattr(group, name))
        setter = widget.setValue
        widget.valueChanged.connect(lambda v: _set(group, name, v))
    elif isinstance(widget, QLineEdit):
        widget.setText(getattr(group, name))

        def set_text(v: str) -> None:
            widget.setText(v)
            widget.setCursorPosition(0)           # the start shows, not the end
        setter = set_text
        set_text(getattr(group, name))
        widget.textChanged.connect(lambda v: _set(group, name, v))
    elif isinstance(widget, (QCheckBox, QGroupBox)):
        widget.setChecked(getattr(group, name))
        setter = widget.setChecked
        widget.toggled.connect(lambda v: _set(group, name, bool(v)))
    elif isinstance(widget, QComboBox):
        def set_data(v: Any) -> None:
            k = widget.findData(v)
            if k >= 0:
                widget.setCurrentIndex(k)
        setter = set_data
        set_data(getattr(group, name))
        widget.currentIndexChanged.connect(
            lambda i: _set(group, name, widget.itemData(i)) if i >= 0 else None)
    elif isinstance(widget, QDateEdit):
        def set_date(v: str) -> None:
            date = QDate.fromString(v, "yyyy-MM-dd")
            if date.isValid():
                widget.setDate(date)
        setter = set_date
        set_date(getattr(group, name))
        widget.dateChanged.connect(lambda d: _set(group, name, d.toString("yyyy-MM-dd")))
    else:
        raise TypeError(f"cannot bind a {type(widget).__name__}")
    return setter


def _set_range(widget: QDoubleSpinBox | QSpinBox, group: Any, name: str) -> None:
    """A spin box's range, the setting's own."""
    low_high = field_range(group, name)
    if low_high is None:
        return
    if isinstance(widget, QSpinBox):
        widget.setRange(int(low_high[0]), int(low_high[1]))
    else:
        widget.setRange(float(low_high[0]), float(low_high[1]))


def bind_text(box: QComboBox, group: Any, name: str) -> None:
    """An editable combo box's text (a choice or what is typed) bound to ``group.<name>``,
    both ways (the digitizer's serial port: listed ports, or one typed); the box starts with
    the field's value."""

    def follow(value: Any, *_old: Any) -> None:
        if box.currentText().strip() != value:
            with QSignalBlocker(box):
                k = box.findText(value)
                if k >= 0:
                    box.setCurrentIndex(k)
                box.setEditText(value)

    follow(getattr(group, name))
    box.currentTextChanged.connect(lambda v: _set(group, name, v.strip()))
    getattr(group.events, name).connect(follow)
    box.destroyed.connect(lambda *_: _disconnect(group, name, follow))


def bind_choice(buttons: Mapping[Any, QAbstractButton], group: Any, name: str) -> QButtonGroup:
    """Exclusive buttons (``value -> button``) bound to ``group.<name>``: the checked button
    is the value."""
    box = QButtonGroup(next(iter(buttons.values())))
    box.setExclusive(True)
    for value, b in buttons.items():
        b.setCheckable(True)
        box.addButton(b)
        b.toggled.connect(lambda on, v=value: _set(group, name, v) if on else None)

    def follow(value: Any, *_old: Any) -> None:
        b = buttons.get(value)
        if b is not None and not b.isChecked():
            with QSignalBlocker(b):
                b.setChecked(True)
            # the exclusive group unchecks the other button itself, quietly
    follow(getattr(group, name))
    getattr(group.events, name).connect(follow)
    first = next(iter(buttons.values()))
    first.destroyed.connect(lambda *_: _disconnect(group, name, follow))
    return box


def _set(group: Any, name: str, value: Any) -> None:
    if getattr(group, name) != value:
        setattr(group, name, value)


def _disconnect(group: Any, name: str, slot: Callable) -> None:
    try:
        getattr(group.events, name).disconnect(slot)
    except (ValueError, RuntimeError):
        pass
