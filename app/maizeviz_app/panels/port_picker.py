"""The serial port chooser of the digitizer panel, as a digitizer vendor's program has it: the
ports the system lists (pyserial's ``list_ports``, likely FASTRAK ports first), a refresh
button, and *Find FASTRAK*, which asks each port in turn for a status record.

Listing and probing run in a worker (a silent port takes its whole timeout to give up): the
window stays live, and what each port answered goes to the panel's log.
"""

from __future__ import annotations

import threading

from PySide6.QtCore import Qt, QThreadPool, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QPushButton,
    QSizePolicy,
    QToolButton,
    QWidget,
)

from maizeviz_app.workers import JobRunner

#: Accessible name of the port list (screen readers; tests find it by this name).
PORT_NAME = "serial port"


class PortPicker(QWidget):
    """An editable list of serial ports with Refresh and Find FASTRAK.

    Signals
    -------
    listed(list) : the ports were listed again ([PortInfo])
    searching(int) : a search began over that many ports
    probed(object) : one port's answer (a :class:`~maizeviz.digitizer.detect.Probe`)
    searched(list) : the search ended ([Probe]; empty when it was stopped)
    """

    listed = Signal(list)
    searching = Signal(int)
    probed = Signal(object)
    searched = Signal(list)

    def __init__(self, port: str = "", parent=None):
        super().__init__(parent)
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._runner = JobRunner(self, pool=self._pool)
        self._cancel: threading.Event | None = None
        self.baud = 115200
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        self.box = QComboBox()
        self.box.setEditable(True)
        self.box.setInsertPolicy(QComboBox.InsertPolicy.NoInsert)
        self.box.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.box.setMinimumContentsLength(12)
        self.box.setAccessibleName(PORT_NAME)
        self.box.setToolTip("the serial port the FASTRAK is plugged into: choose one the system "
                            "lists, or type its path")
        self.box.setEditText(port)
        self.refresh_button = QToolButton()             # a glyph: as small as a tool button
        self.refresh_button.setText("↻")
        self.refresh_button.setAccessibleName("refresh ports")
        self.refresh_button.setToolTip("list the serial ports again (after plugging an adapter in)")
        self.refresh_button.clicked.connect(self.refresh)
        self.find_button = QPushButton("Find FASTRAK")
        self.find_button.setAccessibleName("Find FASTRAK")
        self.find_button.setToolTip("ask each listed port (and the one typed) for a FASTRAK status "
                                    "record, and choose the port that answers")
        self.find_button.clicked.connect(self.search)
        lay.addWidget(self.box, 1)
        lay.addWidget(self.refresh_button)
        lay.addWidget(self.find_button)
        self.ports: list = []                     # [PortInfo] last listed
        self.refresh()

    # ------------------------------------------------------------------ the port
    @property
    def port(self) -> str:
        """The port chosen or typed."""
        return self.box.currentText().strip()

    def set_port(self, port: str) -> None:
        index = self.box.findText(port)
        if index >= 0:
            self.box.setCurrentIndex(index)
        self.box.setEditText(port)

    def candidates(self) -> list[str]:
        """What Find FASTRAK tries: the port typed, then every listed port."""
        listed = [self.box.itemText(i) for i in range(self.box.count())]
        return [p for p in [self.port, *listed] if p]

    @property
    def busy(self) -> bool:
        """A search is under way."""
        return self._cancel is not None

    def set_locked(self, locked: bool) -> None:
        """While recording the port cannot change (a key typed there changes nothing)."""
        self.box.setEnabled(not locked)
        self.refresh_button.setEnabled(not locked)
        self.find_button.setEnabled(not locked and not self.busy)

    # ------------------------------------------------------------------ listing
    def refresh(self) -> None:
        """List the ports again, in a worker; the port typed stays."""
        from maizeviz.digitizer.ports import list_serial_ports

        self._runner.run("list", "listing serial ports", lambda job: list_serial_ports(),
                         on_done=self._fill, on_error=lambda exc: self._fill([]))

    def _fill(self, ports: list) -> None:
        typed = self.port
        self.ports = list(ports)
        self.box.blockSignals(True)
        self.box.clear()
        for info in self.ports:
            self.box.addItem(info.device)
            self.box.setItemData(self.box.count() - 1, info.label + (
                " · Polhemus" if info.polhemus else ""), Qt.ItemDataRole.ToolTipRole)
        self.box.setEditText(typed)
        self.box.blockSignals(False)
        self.listed.emit(self.ports)

    # ------------------------------------------------------------------ searching
    def search(self) -> None:
        """Probe every candidate port in a worker; the first that answers as a FASTRAK is
        chosen. Each answer is :attr:`probed`; the end is :attr:`searched`."""
        if self.busy:
            return
        from maizeviz.digitizer.detect import detect

        ports = self.candidates()
        cancel = threading.Event()
        self._cancel = cancel
        self.find_button.setEnabled(False)
        self.find_button.setText("Searching…")
        self.searching.emit(len(ports))
        baud, probed = self.baud, self.probed

        def work(job):
            return detect(ports, baud, cancel=cancel, progress=lambda p: _emit(probed, p))

        self._runner.run("find", "searching for a FASTRAK", work, on_done=self._found,
                         on_error=lambda exc: self._found([]))

    def stop_search(self) -> None:
        """End a search after the port being probed (at most one probe's timeout)."""
        if self._cancel is not None:
            self._cancel.set()

    def _found(self, results: list) -> None:
        stopped = self._cancel is None or self._cancel.is_set()
        self._cancel = None
        self.find_button.setText("Find FASTRAK")
        self.find_button.setEnabled(self.refresh_button.isEnabled())
        hit = next((r for r in results if r.found), None)
        if hit is not None and not stopped:
            self.set_port(hit.port)
        self.searched.emit([] if stopped else results)

    def wait(self, msecs: int = 10_000) -> bool:
        """Wait for a listing or search under way (tests, closing)."""
        return self._pool.waitForDone(msecs)


def _emit(signal, value) -> None:
    try:
        signal.emit(value)
    except RuntimeError:                          # the panel is gone
        pass
