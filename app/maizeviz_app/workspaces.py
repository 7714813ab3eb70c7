"""Workspaces: the window's docks arranged for one task, switched from View > Workspace.

*Digitize* gives the 3D view (the plant being digitized) most of the window and keeps only the
digitizer beside it; *Analyse* shows the canopy, light and layout panels with the light results
and messages under the view. The light-result docks are hidden while digitizing: empty, they
took half the screen. Each workspace remembers how the user arranged its docks (QMainWindow's
``saveState``, kept per workspace in QSettings), and the window starts in the workspace it
was closed in. Recording switches to Digitize; the window goes back to Analyse when a light
result is shown.

Only dock visibility and sizes live here; what the view shows when the workspace changes is the
window's business (:attr:`Workspaces.changed`).
"""

from __future__ import annotations

from PySide6.QtCore import QObject, QSettings, Qt, Signal
from PySide6.QtGui import QAction, QActionGroup, QKeySequence

#: name -> (menu text, shortcut, docks shown ("*": all but the digitizer), the dock raised in
#: each tab group, what it is for)
WORKSPACES = {
    "analyse": ("&Analyse", "Ctrl+Alt+1", "*", ("canopy", "results"),
                "the canopy, light and layout panels with the light results under the view"),
    "digitize": ("&Digitize", "Ctrl+Alt+2", ("digitizer",), ("digitizer",),
                 "the view large with the digitizer beside it; the light results hidden"),
}
DEFAULT = "analyse"
#: The digitizer's width in the Digitize workspace: its big buttons, two to a row.
DIGITIZER_PX = 460


class Workspaces(QObject):
    """The window's workspaces; :meth:`show` switches, :attr:`current` is the one shown.

    Parameters
    ----------
    window : a QMainWindow with ``docks`` ({object name: QDockWidget})
    settings : where the current workspace and each one's arrangement are remembered
    version : the window's dock-state version (an arrangement saved with another is not
        applied: the docks have changed since)
    sizes : sets the docks of Analyse to their first-start sizes (the window's)

    Signals
    -------
    changed(str) : the workspace shown changed (its name)
    """

    changed = Signal(str)

    def __init__(self, window, settings: QSettings, version: int = 0, sizes=None):
        super().__init__(window)
        self.window = window
        self.settings = settings
        self.version = version
        self._sizes = sizes
        name = str(settings.value("workspace", DEFAULT))
        self.current = name if name in WORKSPACES else DEFAULT
        #: The workspace whose arrangement the window restored at start-up (None: none).
        self._restored_as: str | None = self.current
        self._settled = False
        self.actions: dict[str, QAction] = {}

    # ------------------------------------------------------------------ menu
    def fill_menu(self, menu) -> dict[str, QAction]:
        """Add View > Workspace > Analyse / Digitize; returns the actions by name."""
        sub = menu.addMenu("&Workspace")
        group = QActionGroup(self.window)
        for name, (text, shortcut, _docks, _raised, tip) in WORKSPACES.items():
            act = QAction(text, self.window)
            act.setShortcut(QKeySequence(shortcut))
            act.setCheckable(True)
            act.setChecked(name == self.current)
            act.setStatusTip(tip)
            act.setToolTip(tip)
            act.triggered.connect(lambda _c=False, n=name: self.show(n))
            group.addAction(act)
            sub.addAction(act)
            self.actions[name] = act
        return {f"workspace_{n}": a for n, a in self.actions.items()}

    # ------------------------------------------------------------------ switching
    def show(self, name: str) -> None:
        """Switch to workspace ``name``: its remembered arrangement, else its default. Before
        the window is first laid out (:meth:`settle`) only the name changes."""
        if name not in WORKSPACES:
            raise ValueError(f"no workspace {name!r}: {', '.join(WORKSPACES)}")
        if name == self.current:
            return
        if self._settled:
            self._remember(self.current)
        self.current = name
        if self._settled:
            self._arrange()
        self._check()
        self.settings.setValue("workspace", name)
        self.changed.emit(name)

    def settle(self, restored: bool) -> None:
        """The window's first layout is done (``restored``: it restored the arrangement it was
        closed with, which is the arrangement of the workspace it was closed in). From now on
        switching re-arranges the docks; until now it could not (docks not yet shown do not
        know whether they are open)."""
        self._settled = True
        if not restored or self._restored_as != self.current:
            self._arrange()

    def _arrange(self) -> None:
        state = self.settings.value(f"workspace_state/{self.current}")
        if not (state and self.window.restoreState(state, self.version)):
            self.apply_default()

    def apply_default(self) -> None:
        """The current workspace's docks shown, the others hidden, at their first sizes."""
        _text, _shortcut, shown, raised, _tip = WORKSPACES[self.current]
        docks = self.window.docks
        for name, dock in docks.items():
            want = name != "digitizer" if shown == "*" else name in shown
            # by the dock's open state: a tab behind another is not visible, yet open (asking
            # it to show again re-lays its tab bar out)
            if dock.toggleViewAction().isChecked() != want:
                dock.setVisible(want)
        for name in raised:
            if name in docks:
                docks[name].raise_()
        if self.current == "digitize" and "digitizer" in docks:
            self.window.resizeDocks([docks["digitizer"]], [DIGITIZER_PX],
                                    Qt.Orientation.Horizontal)
        elif self._sizes is not None:
            self._sizes()

    def reset(self) -> None:
        """Forget the arrangements the user made; the current workspace at its default."""
        for name in WORKSPACES:
            self.settings.remove(f"workspace_state/{name}")
        self.apply_default()

    def save(self) -> None:
        """Remember the current arrangement and workspace (the window is closing)."""
        self._remember(self.current)
        self.settings.setValue("workspace", self.current)

    def _remember(self, name: str) -> None:
        self.settings.setValue(f"workspace_state/{name}", self.window.saveState(self.version))

    def _check(self) -> None:
        for name, act in self.actions.items():
            act.setChecked(name == self.current)
