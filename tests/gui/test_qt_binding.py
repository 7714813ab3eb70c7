"""The Qt binding itself: a long session must not wear out the interpreter."""

import sys

from PySide6.QtWidgets import QLabel


def test_calls_into_qt_keep_none_alive(qtbot):
    """PySide6 6.12.0 under Python 3.11 took a reference to None away on every call of a
    method returning nothing; after a few thousand (a digitizing session, a 700-plant layout)
    the interpreter aborted with "deallocating None". pyproject.toml keeps it out."""
    label = QLabel()
    qtbot.addWidget(label)
    before = sys.getrefcount(None)
    for _ in range(2000):
        label.setText("x")
    assert sys.getrefcount(None) >= before - 20
