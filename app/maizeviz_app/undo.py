"""Qt's view of the study's undo history: Edit > Undo/Redo and the history view work through a
``QUndoStack`` that mirrors the model's own history (:class:`maizeviz_app.history.History`),
which decides everything: what a step is, its name, what undoing it does.

The mirror holds one command per step of the history, named as the step; undoing or redoing a
command (the menu, Ctrl+Z, a click in the history view) moves the history, and a history moved
by anything else (a script, a test, the model) moves the mirror. In the window, consecutive edits
of one field closer than :data:`MERGE_S` are one step (typing a number, holding a spin box's
arrow, dragging the slider); a script's history keeps every edit a step of its own.
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QObject
from PySide6.QtGui import QUndoCommand, QUndoStack

from maizeviz_app.history import DraftEdit, History
from maizeviz_app.layout_draft import Change, LayoutDraft

#: Edits of one field closer than this (s) are one step in the window.
MERGE_S = 1.5


class _Mirror(QUndoCommand):
    """One step of the history, as the stack shows it."""

    def __init__(self, recorder: UndoRecorder, text: str) -> None:
        super().__init__(text)
        self.recorder = recorder

    def undo(self) -> None:
        self.recorder._from_stack(self.recorder.history.undo)

    def redo(self) -> None:
        self.recorder._from_stack(self.recorder.history.redo)


class UndoRecorder(QObject):
    """A ``QUndoStack`` (:attr:`stack`) mirroring ``study.history``; without a study, the
    history of ``draft``'s edits alone (the layout editor on its own).

    Parameters
    ----------
    study : maizeviz_app.model.StudyModel or None
    merge_s : float
        Set as the history's :attr:`~maizeviz_app.history.History.merge_s`.
    """

    def __init__(self, study=None, parent=None, draft: LayoutDraft | None = None,
                 merge_s: float = MERGE_S):
        super().__init__(parent)
        self.study = study
        if study is not None:
            self.history: History = study.history
        else:
            self.history = History()
            if draft is not None:
                replay: Callable[[Change, int], None] = draft.replay
                draft.edited.connect(lambda change, text, merge: self.history.record(
                    DraftEdit(change, text, merge, replay)))
        self.history.merge_s = merge_s
        self.stack = QUndoStack(self)
        self._syncing = False
        self.history.changed.connect(self._sync)
        self.destroyed.connect(lambda *_: self._disconnect())
        self._sync()

    def _disconnect(self) -> None:
        try:
            self.history.changed.disconnect(self._sync)
        except (ValueError, RuntimeError):
            pass

    def _from_stack(self, move: Callable[[], bool]) -> None:
        """The stack undid or redid a command: the history follows (the stack is already
        where it should be)."""
        if self._syncing:
            return
        self._syncing = True
        try:
            move()
        finally:
            self._syncing = False

    def _sync(self) -> None:
        """The history changed: the stack becomes its mirror (its steps, named, and where
        the study is among them)."""
        if self._syncing:
            return
        self._syncing = True
        try:
            self.stack.clear()
            for step in self.history.steps:
                self.stack.push(_Mirror(self, step.text))
            self.stack.setIndex(self.history.index)
        finally:
            self._syncing = False
