"""The live digitizer panel, made for a technician in the field with gloves on.

The path of a press: the port's reader thread parses the record into the recorder's queue; a
50 ms GUI timer drains the queue (:meth:`Recorder.poll`), which writes the point to the journal
(fsync) before anything shows; then the panel says what happened (a colour band, a beep on
trouble, ``alert`` for the window's status bar) and :class:`GrowingPlant` re-meshes the leaf
whose cross-section just finished, in a worker.

While recording, N, P, R and U (next leaf, next plant, end row, undo) are application-wide
shortcuts: they act wherever the focus is, and the connection fields are locked, so a letter
can never end up typed into the file name. Connecting runs in a worker too (a unit that does
not answer takes 3 s to give up), and so the window stays live.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

from PySide6.QtCore import QEvent, QObject, QSettings, Qt, QThreadPool, QTimer, Signal
from PySide6.QtGui import QKeySequence, QShortcut
from PySide6.QtWidgets import (
    QApplication,
    QCheckBox,
    QFileDialog,
    QFormLayout,
    QFrame,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QPushButton,
    QScrollArea,
    QSizePolicy,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.recorder import Recorder, Update
from maizeviz.digitizer.session import Session
from maizeviz.errors import MaizevizError
from maizeviz.resources import example_points
from maizeviz_app.panels.growing_plant import GrowingPlant
from maizeviz_app.workers import JobRunner

#: The technician's controls: key, button text.
CONTROLS = (("n", "Next leaf"), ("p", "Next plant"), ("r", "End row"), ("u", "Undo"))
#: Band colours (background, text) per state.
BAND = {"idle": ("#dcdcdc", "#202020"), "busy": ("#90caf9", "#102030"),
        "ok": ("#2e7d32", "#ffffff"), "warn": ("#f9a825", "#000000"),
        "error": ("#c62828", "#ffffff")}
BIG_BUTTON_PX = 56
STOP_REASONS = {"finished": "finished", "lost": "port lost", "failed": "cannot write",
                "signal": "stopped"}


class StatusBand(QFrame):
    """A coloured band: where the next point goes, in big letters, and what just happened."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setObjectName("band")
        self.state = "idle"
        lay = QVBoxLayout(self)
        lay.setContentsMargins(12, 8, 12, 8)
        self.where = QLabel("not recording")
        self.where.setWordWrap(True)
        font = self.where.font()
        font.setPointSize(max(font.pointSize(), 9) + 7)
        font.setBold(True)
        self.where.setFont(font)
        self.message = QLabel("Connect the FASTRAK, or press Demo to try a simulated one.")
        self.message.setWordWrap(True)
        font = self.message.font()
        font.setPointSize(max(font.pointSize(), 9) + 2)
        self.message.setFont(font)
        lay.addWidget(self.where)
        lay.addWidget(self.message)
        self.set_state("idle")

    def set_state(self, state: str, message: str | None = None, where: str | None = None):
        if state != self.state or not self.styleSheet():
            self._paint(state)
        self.state = state
        if message is not None:
            self.message.setText(message)
        if where is not None:
            self.where.setText(where)

    def _paint(self, state: str) -> None:
        bg, fg = BAND[state]
        self.setStyleSheet(f"QFrame#band {{ background: {bg}; border-radius: 6px; }} "
                           f"QFrame#band QLabel {{ color: {fg}; }}")


class _ControlKeys(QObject):
    """An application event filter, installed while recording: a text field that would take
    N, P, R or U as a letter is not asked (its ShortcutOverride is swallowed unaccepted), so
    the application shortcut fires instead, wherever the focus is."""

    KEYS = {Qt.Key.Key_N, Qt.Key.Key_P, Qt.Key.Key_R, Qt.Key.Key_U}

    def eventFilter(self, obj, ev) -> bool:  # noqa: N802 - Qt's name
        if ev.type() == QEvent.Type.ShortcutOverride and ev.key() in self.KEYS:
            mods = ev.modifiers() & ~Qt.KeyboardModifier.KeypadModifier
            return mods == Qt.KeyboardModifier.NoModifier
        return False


class DigitizerPanel(QWidget):
    """Connect to a FASTRAK (or a simulated one), record presses, show the plant growing.

    Signals
    -------
    started : recording began (the port is configured, the reader runs)
    recorded(int) : points recorded so far
    alert(str) : something went wrong (refused point, garbled record, lost port, write
        failure, no connection); for the window's status bar
    stopped(str) : the session ended, and why; the canopy can come back
    """

    started = Signal()
    recorded = Signal(int)
    alert = Signal(str)
    stopped = Signal(str)

    def __init__(self, viewport=None, parent=None):
        super().__init__(parent)
        self._viewport = viewport
        self.recorder: Recorder | None = None
        self.sim = None
        self.beeps = 0
        self.demo_file = example_points()
        self.demo_pace = 0.5
        self._replay: threading.Thread | None = None
        self._connecting: tuple[FastrakPort, Session] | None = None
        self._connect_pool = QThreadPool(self)
        self._connect_pool.setMaxThreadCount(1)
        self._runner = JobRunner(self, pool=self._connect_pool)
        self._shortcuts: list[QShortcut] = []
        self._keys = _ControlKeys(self)
        self._settings = QSettings("maizeviz", "maizeviz")
        self.plant = GrowingPlant(viewport, self)

        outer = QVBoxLayout(self)
        outer.setContentsMargins(0, 0, 0, 0)
        self.scroll_area = QScrollArea()
        self.scroll_area.setWidgetResizable(True)
        self.scroll_area.setFrameShape(QFrame.Shape.NoFrame)
        outer.addWidget(self.scroll_area)
        body = QWidget()
        self.scroll_area.setWidget(body)
        lay = QVBoxLayout(body)

        self.band = StatusBand()
        lay.addWidget(self.band)
        grid = QGridLayout()
        self.control_buttons: list[QPushButton] = []
        for k, (key, text) in enumerate(CONTROLS):
            b = self._big_button(f"{text}   [{key.upper()}]")
            b.setToolTip(f"key {key.upper()}, wherever the focus is while recording")
            b.clicked.connect(lambda _=False, c=key: self.control(c))
            b.setEnabled(False)
            grid.addWidget(b, k // 2, k % 2)
            self.control_buttons.append(b)
        lay.addLayout(grid)
        run = QHBoxLayout()
        self.connect_button = self._big_button("Connect")
        self.connect_button.clicked.connect(lambda: self.start(demo=False))
        self.demo_button = self._big_button("Demo")
        self.demo_button.setToolTip("a simulated FASTRAK replaying the bundled 3 x 3 block")
        self.demo_button.clicked.connect(lambda: self.start(demo=True))
        self.stop_button = self._big_button("Stop")
        self.stop_button.clicked.connect(lambda: self.stop("stopped"))
        self.stop_button.setEnabled(False)
        for b in (self.connect_button, self.demo_button, self.stop_button):
            run.addWidget(b)
        lay.addLayout(run)

        self.settings_box = QGroupBox("connection (locked while recording)")
        form = QFormLayout(self.settings_box)
        self.port_edit = QLineEdit(str(self._settings.value("port", "/dev/ttyUSB0")))
        form.addRow("serial port", self.port_edit)
        self.baud = QSpinBox(minimum=1200, maximum=115200, value=115200, singleStep=9600)
        form.addRow("baud", self.baud)
        self.cols = QSpinBox(minimum=2, maximum=15, value=5)
        form.addRow("points per cross-section", self.cols)
        out_row = QHBoxLayout()
        stamp = time.strftime("%Y%m%d-%H%M%S")
        self.out_edit = QLineEdit(str(Path.home() / f"maizeviz-session-{stamp}.csv"))
        self.browse = QPushButton("…")
        self.browse.setToolTip("choose the file to record to")
        self.browse.clicked.connect(self._choose_out)
        out_row.addWidget(self.out_edit, 1)
        out_row.addWidget(self.browse)
        form.addRow("record to", out_row)
        self.resume = QCheckBox("continue this file (resume)")
        form.addRow(self.resume)
        self.reference = QCheckBox("receiver 2 on the stalk (motion compensation)")
        form.addRow(self.reference)
        lay.addWidget(self.settings_box)
        self.counts = QLabel("")
        self.counts.setWordWrap(True)
        lay.addWidget(self.counts)
        self.log = QListWidget()
        self.log.setUniformItemSizes(True)          # scrolling 400 lines stays instant
        self.log.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        # the band shows the whole last line
        self.log.setTextElideMode(Qt.TextElideMode.ElideMiddle)
        self.log.setMinimumHeight(90)
        lay.addWidget(self.log, 1)

        self.timer = QTimer(self, interval=50)
        self.timer.timeout.connect(self._drain)

    def _big_button(self, text: str) -> QPushButton:
        b = QPushButton(text)
        b.setMinimumHeight(BIG_BUTTON_PX)
        b.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        font = b.font()
        font.setPointSize(max(font.pointSize(), 9) + 5)
        font.setBold(True)
        b.setFont(font)
        return b

    # -------------------------------------------------------------------------- ui
    def _choose_out(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Record to", self.out_edit.text(),
                                              "Points CSV (*.csv)")
        if path:
            self.out_edit.setText(path)

    def _say(self, text: str) -> None:
        self.log.addItem(text)
        self.log.scrollToBottom()
        while self.log.count() > 400:
            self.log.takeItem(0)

    def _beep(self) -> None:
        QApplication.beep()
        self.beeps += 1

    def _loud(self, state: str, text: str) -> None:
        """Trouble the technician must notice without looking: band colour, beep, status bar."""
        self.band.set_state(state, text)
        self._beep()
        self.alert.emit(text)

    def _lock(self, running: bool, connecting: bool = False) -> None:
        busy = running or connecting
        self.connect_button.setEnabled(not busy)
        self.demo_button.setEnabled(not busy)
        self.stop_button.setEnabled(busy)
        for b in self.control_buttons:
            b.setEnabled(running)
        # read-only rather than disabled: the fields stay legible and can hold the focus,
        # but a key typed there changes nothing
        for edit in (self.port_edit, self.out_edit):
            edit.setReadOnly(busy)
        for w in (self.baud, self.cols, self.browse, self.resume, self.reference):
            w.setEnabled(not busy)
        if running:
            self._grab_keys()
        else:
            self._release_keys()

    def _grab_keys(self) -> None:
        if self._shortcuts:
            return
        # parented to the window, which is visible even when this dock is a hidden tab
        owner = self.window()
        for key, _ in CONTROLS:
            sc = QShortcut(QKeySequence(key.upper()), owner)
            sc.setContext(Qt.ShortcutContext.ApplicationShortcut)
            sc.activated.connect(lambda c=key: self.control(c))
            self._shortcuts.append(sc)
        app = QApplication.instance()
        if app is not None:
            app.installEventFilter(self._keys)

    def _release_keys(self) -> None:
        app = QApplication.instance()
        if app is not None:
            app.removeEventFilter(self._keys)
        for sc in self._shortcuts:
            sc.setEnabled(False)
            sc.deleteLater()
        self._shortcuts.clear()

    @property
    def viewport(self):
        """The 3D view the plant grows in (also the growing plant's: setting it after the
        panel was made must reach both, or the plant is never drawn)."""
        return self._viewport

    @viewport.setter
    def viewport(self, viewport) -> None:
        self._viewport = viewport
        self.plant.viewport = viewport

    @property
    def session(self) -> Session | None:
        return self.recorder.session if self.recorder is not None else None

    @property
    def recording(self) -> bool:
        return self.recorder is not None

    def _where(self) -> str:
        session = self.session
        if session is None:
            return "not recording"
        p = session.pos
        return f"plant {p.plant} · leaf {p.leaf} · row {p.row} · col {p.col}"

    def _show_counts(self) -> None:
        if self.session is not None:
            self.counts.setText(self.session.summary())

    # ----------------------------------------------------------------------- session
    def start(self, demo: bool = False) -> None:
        """Open the session file, then the port (or a simulator) in a worker; recording
        begins when the unit answered (``started``)."""
        if self.recording or self._connecting is not None:
            return
        ref = 2 if self.reference.isChecked() else None
        try:
            session = Session(self.out_edit.text(), self.cols.value(), self.resume.isChecked(),
                              ref)
        except MaizevizError as exc:
            self._say(f"error: {exc}")
            self._loud("error", f"cannot record: {exc}")
            return
        port_name = self.port_edit.text()
        if demo:
            from maizeviz.digitizer.simulator import FastrakSimulator

            self.sim = FastrakSimulator(stations=(1, 2) if ref else (1,))
            port_name = self.sim.path
            self._say(f"demo: simulated FASTRAK on {port_name}")
        port = FastrakPort(port_name, self.baud.value(), answer_timeout=1.0)
        self._connecting = (port, session)
        self.band.set_state("busy", f"connecting to {port_name} at {self.baud.value()} baud…",
                            "connecting")
        self._lock(False, connecting=True)
        stations = (1,) if ref is None else (1, ref)
        self._runner.run("connect", f"connecting to {port_name}",
                         lambda job: port.configure(stations),
                         on_done=lambda cfg: self._connected(port, session, cfg, demo),
                         on_error=lambda exc: self._not_connected(port, session, exc))

    def _connected(self, port: FastrakPort, session: Session, cfg, demo: bool) -> None:
        if self._connecting is None or self._connecting[0] is not port:
            port.close()                                # stopped while connecting: stop() has
            return                                      # closed the session already
        self._connecting = None
        for w in cfg.warnings:
            self._say(f"warning: {w}")
        if not demo:
            self._settings.setValue("port", port.port_name)
        recorder = Recorder(session, port)
        recorder.start()
        self.begin(recorder)
        if demo:
            self._start_replay(session.reference_station is not None)

    def _not_connected(self, port: FastrakPort, session: Session, exc: BaseException) -> None:
        if self._connecting is None or self._connecting[0] is not port:
            return
        self._connecting = None
        port.close()
        session.close()
        text = str(exc) if isinstance(exc, MaizevizError) else f"{type(exc).__name__}: {exc}"
        self._say(f"error: {text}")
        self._close_demo()
        self._lock(False)
        self._loud("error", f"not connected: {text}")
        self.band.set_state("error", where="not recording (could not connect)")
        self.stopped.emit("could not connect")

    def begin(self, recorder: Recorder) -> None:
        """Drain ``recorder`` from now on (its port, if any, configured and reading)."""
        self.recorder = recorder
        if self.viewport is not None:
            self.viewport.hide_canopy()
        self.plant.clear()
        self._lock(True)
        self._say(f"recording to {recorder.session.path}")
        self.band.set_state("ok", "recording: press the stylus on the next point",
                            self._where())
        self._show_counts()
        if recorder.session.history:
            self.plant.update(recorder.session.history, recorder.session.pos)
        self.timer.start()
        self.started.emit()

    def _start_replay(self, sway: bool) -> None:
        from maizeviz.digitizer.replay import replay_points

        recorder = self.recorder
        assert recorder is not None

        def say(msg):
            for key in ("n", "p", "q"):
                if f"type {key} " in msg:
                    recorder.control(key)
                    return
            recorder.say(msg)

        sim, path, pace = self.sim, self.demo_file, self.demo_pace

        def run():
            try:
                replay_points(sim, path, pace=pace, sway=sway, say=say, wait=False)
            except Exception as exc:  # noqa: BLE001 - reported in the panel
                recorder.say(f"demo stopped: {exc}")

        self._replay = threading.Thread(target=run, name="fastrak-demo", daemon=True)
        self._replay.start()

    def control(self, key: str) -> None:
        """A technician's control (n, p, r, u, q), handled at once."""
        if self.recorder is not None:
            self.recorder.control(key)
            self._drain()

    def _drain(self) -> None:
        """Handle what the reader and the controls queued since the last tick (GUI thread).

        A slot: nothing may escape it, or the process can go down with the journal open.
        """
        if self.recorder is None:
            return
        try:
            updates = self.recorder.poll(limit=2000)
            changed = False
            for update in updates:
                self._show_update(update)
                changed = changed or update.kind in ("recorded", "control")
            if updates:
                self._show_counts()
            if changed and self.session is not None:
                self.band.where.setText(self._where())
                self.plant.update(self.session.history, self.session.pos)
                self.recorded.emit(self.session.count.points)
        except Exception as exc:  # noqa: BLE001 - see the docstring
            self._say(f"error: {type(exc).__name__}: {exc}")
            self._loud("error", f"unexpected error, recording stopped: {exc}")
            self.stop("error")
            return
        final = self.recorder.final if self.recorder is not None else None
        if final is not None:
            self.stop(STOP_REASONS.get(final.kind, final.kind))

    def _show_update(self, update: Update) -> None:
        kind, text = update.kind, update.message
        if kind in ("lost", "failed"):
            self._say(f"error: {text}")
            self._loud("error", text)
        elif kind in ("refused", "garbled"):
            self._say(text)
            self._loud("error" if kind == "refused" else "warn", text)
        elif kind in ("recorded", "control"):
            self._say(text)
            self.band.set_state("ok", text)
        elif text and kind != "finished":
            self._say(text)

    def _close_demo(self) -> None:
        if self.sim is not None:
            self.sim.close()
            self.sim = None
        if self._replay is not None:
            self._replay.join(timeout=5)
            self._replay = None

    def stop(self, why: str = "stopped") -> None:
        """End the session (or the connection attempt); the journal is already on disk."""
        self.timer.stop()
        connecting, self._connecting = self._connecting, None
        if connecting is not None:                      # the unit had not answered yet
            connecting[0].close()
            connecting[1].close()                       # its journal lock goes at once
        recorder, self.recorder = self.recorder, None
        if recorder is not None and recorder.port is not None:
            recorder.port.close()
        self._close_demo()
        self._connect_pool.waitForDone(10_000)
        self.plant.wait()
        self.plant.clear()
        summary = ""
        if recorder is not None:
            summary = recorder.session.summary()
            self._say(summary)
            self.counts.setText(summary)
            recorder.close()
        self._lock(False)
        where = f"not recording ({why})"
        if self.band.state in ("error", "warn") and why != "finished":
            self.band.set_state(self.band.state, where=where)   # keep the trouble in sight
        else:
            self.band.set_state("idle", summary or None, where)
        if recorder is not None or connecting is not None:
            self.stopped.emit(why)
