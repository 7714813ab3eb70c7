"""The main window's frame: its docks, the status bar's job label and Cancel, the window's
size and dock layout remembered between sessions, and the 3D view's native window.
"""

from __future__ import annotations

from PySide6.QtCore import QByteArray, QSettings, Qt, QTimer
from PySide6.QtGui import QFont, QFontMetrics
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QPlainTextEdit,
    QPushButton,
    QScrollArea,
    QSizeGrip,
    QStatusBar,
    QWidget,
)

#: Version of the saved dock layout; bump when docks change so an old layout is not applied.
STATE_VERSION = 5


def scrolled(widget: QWidget) -> QScrollArea:
    """``widget`` in a frameless scroll area that scrolls only up and down: a panel narrower
    than its dock wraps its text rather than scrolling sideways."""
    area = QScrollArea()
    area.setWidget(widget)
    area.setWidgetResizable(True)
    area.setFrameShape(QScrollArea.Shape.NoFrame)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAsNeeded)
    return area


def own_window(centre: QWidget) -> None:
    """Give the 3D view's place a native window of its own (on X11), before the window shows.

    The 3D view is a QOpenGLWidget (pyvistaqt): Qt then composes the window it lies in through
    OpenGL at every repaint, and on software OpenGL (Mesa llvmpipe) composing the whole main
    window costs 20-30 ms, for a label or a progress bar as for a frame of the view. In a
    native window of its own, only the view's area is composed and the other widgets paint as
    plain raster (a status message: under 1 ms instead of 15-25). Its siblings (the docks)
    stay non-native. The view must be made inside it: a QOpenGLWidget that is ever a child of
    the main window itself makes Qt compose the whole window again."""
    if QApplication.platformName() != "xcb":
        return
    QApplication.setAttribute(Qt.ApplicationAttribute.AA_DontCreateNativeWidgetSiblings)
    centre.setAttribute(Qt.WidgetAttribute.WA_NativeWindow)


def messages_widget() -> QPlainTextEdit:
    box = QPlainTextEdit(readOnly=True)
    box.setMaximumBlockCount(1000)
    box.setAccessibleName("messages")
    box.setToolTip("what the app did and what went wrong, newest last")
    return box


def _dock(window: QMainWindow, docks: dict, name: str, title: str, widget: QWidget, area,
          scroll: bool = True) -> QDockWidget:
    dock = QDockWidget(title, window)
    dock.setObjectName(name)
    dock.setWidget(scrolled(widget) if scroll else widget)
    feature = QDockWidget.DockWidgetFeature
    dock.setFeatures(feature.DockWidgetMovable | feature.DockWidgetFloatable
                     | feature.DockWidgetClosable)
    window.addDockWidget(area, dock)
    docks[name] = dock
    return dock


def make_docks(window: QMainWindow, panels: dict[str, tuple[str, QWidget | None]],
               plots: QWidget, messages: QWidget, history: QWidget) -> dict[str, QDockWidget]:
    """The panels tabbed on the right (``panels``: name -> (title, widget); None: a panel
    made later, such as the layout editor and the digitizer), the figures, messages and undo
    history tabbed at the bottom."""
    window.setCorner(Qt.Corner.BottomRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
    window.setCorner(Qt.Corner.TopRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
    window.setDockOptions(QMainWindow.DockOption.AnimatedDocks
                          | QMainWindow.DockOption.AllowTabbedDocks)
    docks: dict[str, QDockWidget] = {}
    right = Qt.DockWidgetArea.RightDockWidgetArea
    made = [_dock(window, docks, name, title,
                  widget if widget is not None else QLabel("starting…"), right)
            for name, (title, widget) in panels.items()]
    for d in made[1:]:
        window.tabifyDockWidget(made[0], d)
    made[0].raise_()
    bottom = Qt.DockWidgetArea.BottomDockWidgetArea
    results = _dock(window, docks, "results", "Light results", plots, bottom, scroll=False)
    said = _dock(window, docks, "messages", "Messages", messages, bottom, scroll=False)
    edits = _dock(window, docks, "history", "Undo history", history, bottom, scroll=False)
    window.tabifyDockWidget(results, said)
    window.tabifyDockWidget(said, edits)
    results.raise_()
    return docks


def status_widgets(window: QMainWindow) -> tuple[QLabel, QPushButton]:
    """What is running, how far, and Cancel: always in place (showing or hiding widgets
    relayouts the window), updated as text (a QProgressBar repaints synchronously, and
    every repaint recomposes the whole window with the 3D view: 50-100 ms on software
    OpenGL)."""
    box = QWidget()
    lay = QHBoxLayout(box)
    lay.setContentsMargins(0, 0, 0, 0)
    label = QLabel("")
    label.setFixedWidth(300)
    label.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
    label.setAccessibleName("work under way")
    cancel = QPushButton("Cancel")
    cancel.setToolTip("stop the work under way (Esc)")
    cancel.setAccessibleName("Cancel")
    cancel.setEnabled(False)
    lay.addWidget(label)
    lay.addWidget(cancel)
    window.statusBar().addPermanentWidget(box)
    return label, cancel


def status_line(bar: QStatusBar, text: str, bold: bool) -> str:
    """``text``'s first line as the status bar has room for it: cut in the middle with an
    ellipsis when too long (Qt clips it at the right edge), the whole line then in the bar's
    tooltip (and in Messages unless it was a status-only line)."""
    line = text.splitlines()[0] if text else ""
    right = [w.geometry().left() for w in bar.findChildren(QWidget)
             if w.parent() is bar and w.isVisible() and not isinstance(w, QSizeGrip)]
    room = (min(right) if right else bar.width()) - 16      # the bar's margins and a gap
    font = QFont(bar.font())
    font.setBold(bold)
    shown = QFontMetrics(font).elidedText(line, Qt.TextElideMode.ElideMiddle, max(room, 40))
    bar.setToolTip(line if shown != line else "")
    return shown


def restore_window(window: QMainWindow, settings: QSettings) -> bool:
    """The size and docks of the last session (a first start: 94 % of the screen, at most
    1600 x 1000); True if a dock layout was restored."""
    geometry = settings.value("geometry")
    restored = bool(geometry) and window.restoreGeometry(geometry)
    if not restored:
        screen = QApplication.primaryScreen()
        avail = screen.availableGeometry() if screen is not None else None
        if avail is not None:
            w = min(1600, int(avail.width() * 0.94))
            h = min(1000, int(avail.height() * 0.92))
            window.resize(w, h)
            window.move(avail.x() + (avail.width() - w) // 2,
                        avail.y() + (avail.height() - h) // 2)
        else:
            window.resize(1280, 720)
    state = settings.value("window_state")
    return bool(state) and window.restoreState(state, STATE_VERSION)


def save_window(window: QMainWindow, settings: QSettings) -> None:
    settings.setValue("geometry", window.saveGeometry())
    settings.setValue("window_state", window.saveState(STATE_VERSION))
    settings.sync()


def first_show(window, restored: bool) -> None:
    """At the first show, once the docks have their sizes: take the default layout (what
    View > Reset window layout goes back to)."""
    if getattr(window, "_default_state", None) is None:
        window._default_state = None
        QTimer.singleShot(50, lambda: _size_docks(window, restored))


def _size_docks(window, restored: bool) -> None:
    """First show: the panels a third of the width, the figures a third of the height."""
    if window._closing or window._default_state is not None:
        return
    if not restored:
        default_sizes(window)
    kept = window.saveState(STATE_VERSION)
    default_sizes(window)
    window._default_state = window.saveState(STATE_VERSION)
    if restored:
        window.restoreState(kept, STATE_VERSION)
    window.workspaces.settle(restored)


def default_sizes(window) -> None:
    w, h = window.width(), window.height()
    window.resizeDocks([window.docks["canopy"]], [max(380, min(480, int(w * 0.33)))],
                       Qt.Orientation.Horizontal)
    window.resizeDocks([window.docks["results"]], [max(200, min(380, int(h * 0.36)))],
                       Qt.Orientation.Vertical)


def reset(window) -> None:
    """Docks back to where they are on a first start."""
    state: QByteArray | None = getattr(window, "_default_state", None)
    if state is None:
        return
    window.restoreState(state, STATE_VERSION)
    for dock in window.docks.values():
        dock.setFloating(False)
        dock.show()
    window.docks["canopy"].raise_()
    window.docks["results"].raise_()
    window.workspaces.reset()
