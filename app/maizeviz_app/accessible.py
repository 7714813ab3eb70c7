"""Every control named for screen readers (and tests): its accessible name is its label.

A control's label is the text a person reads to know what it is: a button's or check box's
own text, the title of a checkable group, the form label beside a field (the label's buddy).
:func:`name_controls` gives each control under a widget that name when it has none yet; the
panels name the few controls whose label is elsewhere (a row of two fields) themselves.
:func:`controls` lists the controls a person can act on, as the tests check them.
"""

from __future__ import annotations

import re

from PySide6.QtWidgets import (
    QAbstractButton,
    QAbstractItemView,
    QAbstractSlider,
    QAbstractSpinBox,
    QComboBox,
    QGroupBox,
    QHeaderView,
    QLabel,
    QLineEdit,
    QTabBar,
    QWidget,
)


def label_text(text: str) -> str:
    """A label as a name: no mnemonic ampersand, no trailing colon, no key written after it
    (``Next leaf   [N]``: the key is the button's shortcut, not its name)."""
    text = text.replace("&&", "\0").replace("&", "").replace("\0", "&").strip().rstrip(":")
    return re.sub(r"\s+\[[^\[\]]{1,12}\]$", "", text)


def controls(root: QWidget) -> list[QWidget]:
    """The controls under ``root`` a person can act on (Qt's own parts left out: a spin
    box's line edit, a table's corner button, scroll bars)."""
    kinds = (QAbstractButton, QAbstractSpinBox, QComboBox, QLineEdit, QAbstractSlider,
             QAbstractItemView, QGroupBox)
    found: list[QWidget] = []
    window = root.window()
    for w in root.findChildren(QWidget):
        if not isinstance(w, kinds) or w.objectName().startswith("qt_"):
            continue
        if w.window() is not window or isinstance(w, QHeaderView):
            continue                            # a combo's popup list; a table's header
        if isinstance(w.parent(), QTabBar):
            continue                            # a tab bar's scroll arrows
        if isinstance(w, QGroupBox) and not w.isCheckable():
            continue
        if isinstance(w, QLineEdit) and isinstance(w.parent(), (QAbstractSpinBox, QComboBox)):
            continue
        if isinstance(w, QAbstractSlider) and type(w).__name__ == "QScrollBar":
            continue
        found.append(w)
    return found


def name_controls(root: QWidget) -> None:
    """Name each unnamed control under ``root`` by its label (see the module docstring)."""
    for label in root.findChildren(QLabel):
        buddy = label.buddy()
        if buddy is not None and not buddy.accessibleName() and label.text():
            buddy.setAccessibleName(label_text(label.text()))
    for w in controls(root):
        if w.accessibleName():
            continue
        if isinstance(w, QAbstractButton) and w.text():
            w.setAccessibleName(label_text(w.text()))
        elif isinstance(w, QGroupBox):
            w.setAccessibleName(label_text(w.title()))
