"""The live digitizer panel, made for a technician in the field with gloves on.

The path of a press: the port's reader thread parses the record into the recorder's queue; a
50 ms GUI timer drains the queue (:meth:`Recorder.poll`), which writes the point to the journal
(fsync) before anything shows; then the panel says what happened (a colour band, a beep on
trouble, ``alert`` for the window's status bar) and :class:`GrowingPlant` re-meshes the leaf
whose cross-section just finished, in a worker.

While recording, N, P, R, U and S (next leaf, next plant, end row, undo, pause) are
application-wide shortcuts: they act wherever the focus is, and the connection fields are
locked, so a letter can never end up typed into the file name. While paused a press is not
recorded, and each one is said (amber band, beep). The stylus tip's live position, and its
distance from the last point, show under the band (the reader polls the unit ten times a
second; see :mod:`maizeviz.digitizer.live`).

The port is chosen from the system's list (:class:`PortPicker`, with *Find FASTRAK*); what goes
wrong is said in the core's words (:mod:`maizeviz.digitizer.port_problems`), the same line
``maizeviz record`` prints. Connecting, searching and stopping run in workers (a unit that does
not answer takes 3 s to give up; stopping joins the reader and closes the port), and so the
window stays live: Stop leaves the event loop within a few milliseconds, and the plant just
digitized stays in the view.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from functools import partial
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
    QMessageBox,
    QPushButton,
    QScrollArea,
    QSizePolicy,
    QSpinBox,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.recorder import PAUSE_KEY, LiveTip, Recorder, Update
from maizeviz.digitizer.session import Session
from maizeviz.errors import MaizevizError
from maizeviz.resources import example_points
from maizeviz_app.panels.growing_plant import GrowingPlant
from maizeviz_app.panels.port_picker import PortPicker
from maizeviz_app.workers import JobRunner

#: The technician's controls: key, button text.
CONTROLS = (("n", "Next leaf"), ("p", "Next plant"), ("r", "End row"), ("u", "Undo"))
#: Seconds between the reader's polls for the stylus's live position.
LIVE_EVERY_S = 0.1
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
    N, P, R, U or S as a letter is not asked (its ShortcutOverride is swallowed unaccepted),
    so the application shortcut fires instead, wherever the focus is."""

    KEYS = {Qt.Key.Key_N, Qt.Key.Key_P, Qt.Key.Key_R, Qt.Key.Key_U, Qt.Key.Key_S}

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
        failure, no connection, a press while paused); for the window's status bar
    stopped(str) : the session ended and its port and journal are closed, and why
    """

    started = Signal()
    recorded = Signal(int)
    alert = Signal(str)
    stopped = Signal(str)
    #: Ask before the window closes while recording (tests and benchmarks turn it off).
    confirm_close = True

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
        self._closing = 0                          # sessions whose port is being closed
        self._connect_pool = QThreadPool(self)
        self._connect_pool.setMaxThreadCount(1)
        self._runner = JobRunner(self, pool=self._connect_pool)
        # stopping has a pool of its own: it must not queue behind a connection attempt
        self._close_pool = QThreadPool(self)
        self._close_pool.setMaxThreadCount(1)
        self._closer = JobRunner(self, pool=self._close_pool)
        self._shortcuts: list[QShortcut] = []
        self._keys = _ControlKeys(self)
        self._settings = QSettings("maizeviz", "maizeviz")
        self._live_shown: LiveTip | None = None
        self._paused = False
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
        self.live = QLabel("tip: —")
        self.live.setWordWrap(True)
        self.live.setAccessibleName("stylus tip")
        self.live.setToolTip("where the stylus tip is now (cm, in the recording's frame) and how "
                             "far it is from the last point recorded")
        font = self.live.font()
        font.setPointSize(max(font.pointSize(), 9) + 3)
        font.setFamily("monospace")
        font.setStyleHint(font.StyleHint.Monospace)
        self.live.setFont(font)
        lay.addWidget(self.live)
        grid = QGridLayout()
        self.control_buttons: list[QPushButton] = []
        for k, (key, text) in enumerate(CONTROLS):
            b = self._big_button(f"{text}   [{key.upper()}]")
            b.setAccessibleName(text)
            b.setToolTip(f"key {key.upper()}, wherever the focus is while recording")
            b.clicked.connect(lambda _=False, c=key: self.control(c))
            b.setEnabled(False)
            grid.addWidget(b, k // 2, k % 2)
            self.control_buttons.append(b)
        lay.addLayout(grid)
        run = QGridLayout()
        self.connect_button = self._big_button("Connect")
        self.connect_button.setAccessibleName("Connect")
        self.connect_button.setToolTip("open the port, set the FASTRAK up and start recording")
        self.connect_button.clicked.connect(lambda: self.start(demo=False))
        self.demo_button = self._big_button("Demo")
        self.demo_button.setAccessibleName("Demo")
        self.demo_button.setToolTip("a simulated FASTRAK replaying the bundled 3 x 3 block")
        self.demo_button.clicked.connect(lambda: self.start(demo=True))
        self.pause_button = self._big_button(f"Pause   [{PAUSE_KEY.upper()}]")
        self.pause_button.setAccessibleName("Pause")
        self.pause_button.setToolTip(f"key {PAUSE_KEY.upper()}: stop recording presses for a "
                                     "while (to move the transmitter, or rest); presses made "
                                     "while paused are said and not recorded")
        self.pause_button.clicked.connect(self.toggle_pause)
        self.pause_button.setEnabled(False)
        self.stop_button = self._big_button("Stop")
        self.stop_button.setAccessibleName("Stop")
        self.stop_button.setToolTip("end the session: every point recorded is already on disk")
        self.stop_button.clicked.connect(lambda: self.stop("stopped"))
        self.stop_button.setEnabled(False)
        for k, b in enumerate((self.connect_button, self.demo_button, self.pause_button,
                               self.stop_button)):
            run.addWidget(b, k // 2, k % 2)
        lay.addLayout(run)

        self.settings_box = QGroupBox("connection (locked while recording)")
        form = QFormLayout(self.settings_box)
        # in a narrow dock a field goes under its label rather than out of sight
        form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
        self.ports = PortPicker(str(self._settings.value("port", "/dev/ttyUSB0")))
        self.ports.searching.connect(self._searching)
        self.ports.probed.connect(lambda p: self._say(f"{'found: ' if p.found else ''}"
                                                      f"{p.message}"))
        self.ports.searched.connect(self._searched)
        form.addRow("serial port", self.ports)
        self.baud = QSpinBox(minimum=1200, maximum=115200, value=115200, singleStep=9600)
        baud = str(self._settings.value("baud", 115200))
        self.baud.setValue(int(baud) if baud.isdigit() else 115200)
        self.baud.setAccessibleName("baud")
        self.baud.setToolTip("bits per second: must match the unit's rear DIP switches "
                             "(factory setting 115200)")
        self.baud.valueChanged.connect(lambda v: setattr(self.ports, "baud", v))
        self.ports.baud = self.baud.value()
        form.addRow("baud", self.baud)
        self.cols = QSpinBox(minimum=2, maximum=15, value=5)
        self.cols.setAccessibleName("points per cross-section")
        self.cols.setToolTip("stylus presses across the leaf, margin to margin, in each "
                             "cross-section")
        form.addRow("points per cross-section", self.cols)
        out_row = QHBoxLayout()
        stamp = time.strftime("%Y%m%d-%H%M%S")
        self.out_edit = QLineEdit(str(Path.home() / f"maizeviz-session-{stamp}.csv"))
        self.out_edit.setAccessibleName("record to")
        self.out_edit.textChanged.connect(self._show_out_path)
        self._show_out_path(self.out_edit.text())
        self.browse = QToolButton()
        self.browse.setText("…")
        self.browse.setAccessibleName("choose the file to record to")
        self.browse.setToolTip("choose the file to record to")
        self.browse.clicked.connect(self._choose_out)
        out_row.addWidget(self.out_edit, 1)
        out_row.addWidget(self.browse)
        # the path on a row of its own, under its label: the dock's whole width shows it
        out_label = QLabel("record to")
        out_label.setBuddy(self.out_edit)
        form.addRow(out_label)
        form.addRow(out_row)
        self.resume = QCheckBox("continue this file (resume)")
        self.resume.setAccessibleName("continue this file (resume)")
        self.resume.setToolTip("go on where the file stopped (after a crash, a lost cable or "
                               "a flat battery)")
        form.addRow(self.resume)
        self.reference = QCheckBox("receiver 2 on the stalk (motion compensation)")
        self.reference.setAccessibleName("receiver 2 on the stalk (motion compensation)")
        self.reference.setToolTip("points are re-expressed in the frame of a receiver fixed to "
                                  "the stalk, so a swaying plant does not blur them")
        form.addRow(self.reference)
        lay.addWidget(self.settings_box)
        self.counts = QLabel("")
        self.counts.setWordWrap(True)
        lay.addWidget(self.counts)
        self.log = QListWidget()
        self.log.setAccessibleName("digitizer log")
        self.log.setToolTip("what the session did, newest last: presses, refusals, the port")
        self.log.setUniformItemSizes(True)          # scrolling 400 lines stays instant
        self.log.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        # the band shows the whole last line
        self.log.setTextElideMode(Qt.TextElideMode.ElideMiddle)
        self.log.setMinimumHeight(90)
        lay.addWidget(self.log, 1)

        self.timer = QTimer(self, interval=50)
        self.timer.timeout.connect(self._drain)

    def _show_out_path(self, path: str) -> None:
        """The tooltip names the whole path, for one too long for the field."""
        self.out_edit.setToolTip("the points file every press is appended to (on disk before "
                                 f"it is reported recorded):\n{path}")

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
    @property
    def port(self) -> str:
        """The serial port chosen or typed."""
        return self.ports.port

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
        idle = not busy and not self._closing and not self.ports.busy
        self.connect_button.setEnabled(idle)
        self.demo_button.setEnabled(idle)
        self.stop_button.setEnabled(busy)
        self.pause_button.setEnabled(running)
        for b in self.control_buttons:
            b.setEnabled(running)
        # read-only rather than disabled: the fields stay legible and can hold the focus,
        # but a key typed there changes nothing
        self.out_edit.setReadOnly(busy)
        self.ports.set_locked(busy)
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
        keys: list[tuple[str, Callable[[], None]]] = [
            (key, partial(self.control, key)) for key, _ in CONTROLS]
        keys.append((PAUSE_KEY, self.toggle_pause))
        for key, slot in keys:
            sc = QShortcut(QKeySequence(key.upper()), owner)
            sc.setContext(Qt.ShortcutContext.ApplicationShortcut)
            sc.activated.connect(slot)
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

    @property
    def paused(self) -> bool:
        return self.recorder is not None and self._paused

    def _where(self) -> str:
        session = self.session
        if session is None:
            return "not recording"
        p = session.pos
        where = f"plant {p.plant} · leaf {p.leaf} · row {p.row} · col {p.col}"
        return f"PAUSED · {where}" if self.paused else where

    def _show_counts(self) -> None:
        if self.session is not None:
            self.counts.setText(self.session.summary())

    def _show_live(self) -> None:
        """The tip's position and distance (only when a newer answer came: no repaint else)."""
        tip = self.recorder.live if self.recorder is not None else None
        if tip is None or tip is self._live_shown:
            return
        self._live_shown = tip
        x, y, z = tip.xyz
        far = "no point recorded yet" if tip.distance is None else \
            f"{tip.distance:.2f} cm from the last point"
        text = f"tip {x:.2f}  {y:.2f}  {z:.2f} cm\n{far}"
        if not tip.trustworthy:
            text += f" ({tip.note})"
        self.live.setText(text)

    # -------------------------------------------------------------------- the port list
    def _searching(self, n: int) -> None:
        self._lock(False)
        self.band.set_state("busy", f"searching {n} port{'s' if n != 1 else ''} for a FASTRAK…")

    def _searched(self, results: list) -> None:
        self._lock(self.recording, self._connecting is not None)
        hit = next((r for r in results if r.found), None)
        if hit is not None:
            self.band.set_state("ok", f"FASTRAK found on {hit.port}: press Connect")
        elif results:
            self._loud("warn", f"no FASTRAK answered on {len(results)} port"
                               f"{'s' if len(results) != 1 else ''} (see the log): is it "
                               "switched on and plugged in, at the baud rate of its switches?")
        else:
            self.band.set_state("idle", "search stopped")

    # ----------------------------------------------------------------------- session
    def start(self, demo: bool = False) -> None:
        """Open the session file, then the port (or a simulator) in a worker; recording
        begins when the unit answered (``started``)."""
        if self.recording or self._connecting is not None or self._closing or self.ports.busy:
            return
        ref = 2 if self.reference.isChecked() else None
        try:
            session = Session(self.out_edit.text(), self.cols.value(), self.resume.isChecked(),
                              ref)
        except MaizevizError as exc:
            self._say(f"error: {exc}")
            self._loud("error", f"cannot record: {exc}")
            return
        port_name = self.port
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

        def connect(job):
            try:
                return port.configure(stations)
            except BaseException:
                port.close()                    # the worker's port: closed by the worker
                raise

        self._runner.run("connect", f"connecting to {port_name}", connect,
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
            self._settings.setValue("baud", port.baud)
        recorder = Recorder(session, port)
        recorder.start(live_every=LIVE_EVERY_S)
        self.begin(recorder)
        if demo:
            self._start_replay(session.reference_station is not None)

    def _not_connected(self, port: FastrakPort, session: Session, exc: BaseException) -> None:
        if self._connecting is None or self._connecting[0] is not port:
            return
        self._connecting = None
        session.close()
        text = str(exc) if isinstance(exc, MaizevizError) else f"{type(exc).__name__}: {exc}"
        self._say(f"error: {text}")
        self._close_demo_now()
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
        self._set_paused(False)
        self._live_shown = None
        self.live.setText("tip: waiting for the unit…" if recorder.port is not None
                          else "tip: —")
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

    def toggle_pause(self) -> None:
        """Pause or resume recording (the S key, the Pause button)."""
        if self.recorder is None:
            return
        self._set_paused(not self.paused)
        self.recorder.pause(self.paused)
        self._drain()

    def _set_paused(self, on: bool) -> None:
        self._paused = on
        self.pause_button.setText(f"{'Resume' if on else 'Pause'}   [{PAUSE_KEY.upper()}]")
        self.pause_button.setAccessibleName("Resume" if on else "Pause")

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
                self.band.where.setText(self._where())
            if changed and self.session is not None:
                self.plant.update(self.session.history, self.session.pos)
                self.recorded.emit(self.session.count.points)
            self._show_live()
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
        elif kind in ("refused", "garbled", "ignored"):
            self._say(text)
            self._loud("error" if kind == "refused" else "warn", text)
        elif kind == "paused":
            self._say(text)
            self.band.set_state("warn", text)
        elif kind in ("recorded", "control", "resumed"):
            self._say(text)
            self.band.set_state("warn" if self.paused else "ok", text)
        elif text and kind != "finished":
            self._say(text)

    # ------------------------------------------------------------------------ stopping
    def stop(self, why: str = "stopped", wait: bool = False) -> None:
        """End the session (or the connection attempt); the journal is already on disk.

        The GUI thread only lets go: the reader's join, the port's close, the demo's end and
        the journal's last presses happen in a worker, and ``stopped(why)`` is emitted once
        they are done. Presses the reader had queued are recorded, not dropped. No frame is
        drawn for the stop: the plant stays as it was. With ``wait`` (the window is closing)
        it all happens here and now.
        """
        self.timer.stop()
        if wait:                                        # an earlier stop's port closed first
            self._close_pool.waitForDone(10_000)
        connecting, self._connecting = self._connecting, None
        recorder, self.recorder = self.recorder, None
        sim, self.sim = self.sim, None
        replay, self._replay = self._replay, None
        if connecting is not None:                      # the unit had not answered yet:
            connecting[0].cancel()                      # its worker gives up and closes it
            connecting[1].close()                       # the journal's lock goes at once
        self.ports.stop_search()
        if recorder is None and connecting is None and sim is None:
            self._lock(False)
            return
        self._closing += 1
        self._lock(False)
        self.band.set_state(self.band.state, where=f"stopping ({why})…")

        def close(job=None):
            if recorder is not None and recorder.port is not None:
                recorder.port.close()                   # joins the reader
            if sim is not None:
                sim.close()
            if replay is not None:
                replay.join(timeout=5)
            # presses the reader queued before it stopped: recorded, not dropped
            late = recorder.poll(limit=1_000_000) if recorder is not None else []
            if recorder is not None:
                recorder.close()
            return late

        def done(late):
            self._stopped(why, recorder, late)

        if wait:
            done(close())
            return
        job = self._closer.run("close", "closing the digitizer", close, on_done=done,
                               on_error=lambda exc: done([Update("failed", str(exc))]),
                               supersede=False)
        if job is None:                                 # the runner is shut: do it here
            done(close())

    def _stopped(self, why: str, recorder: Recorder | None, late: list[Update]) -> None:
        self._closing = max(0, self._closing - 1)
        for update in late:
            self._show_update(update)
        summary = ""
        if recorder is not None:
            summary = recorder.session.summary()
            self._say(summary)
            self.counts.setText(summary)
            # a press that arrived as the session stopped is recorded and listed, but not
            # drawn: a frame costs 50-80 ms on software OpenGL, and Stop must not freeze
        self._lock(self.recording, self._connecting is not None)
        if self.recording or self._connecting is not None:
            return                                      # a new session began meanwhile
        self._set_paused(False)
        if recorder is not None and recorder.session.history:
            # Connect again continues this file where it stopped (the journal replays it)
            self.resume.setChecked(True)
        where = f"not recording ({why})"
        if self.band.state in ("error", "warn") and why != "finished":
            self.band.set_state(self.band.state, where=where)   # keep the trouble in sight
        else:
            self.band.set_state("idle", summary or None, where)
        self.stopped.emit(why)

    def _close_demo_now(self) -> None:
        sim, self.sim = self.sim, None
        if sim is not None:
            sim.close()

    def release_view(self) -> None:
        """The view goes back to the canopy: forget the plant (a leaf still being meshed is
        never drawn over the canopy)."""
        if not self.recording:
            self.plant.clear()

    def may_close(self, parent: QWidget | None = None) -> bool:
        """Ask before the window closes while recording; True when it may close."""
        if not self.confirm_close or (not self.recording and self._connecting is None):
            return True
        session = self.session
        what = (f"A digitizing session is recording into {session.path} "
                f"({session.count.points} points, all on disk)." if session is not None
                else "The digitizer is connecting.")
        box = QMessageBox(QMessageBox.Icon.Question, "Stop recording?",
                          f"{what}\n\nStop recording and close the window?",
                          QMessageBox.StandardButton.NoButton, parent or self.window())
        stop = box.addButton("Stop and close", QMessageBox.ButtonRole.AcceptRole)
        keep = box.addButton("Keep recording", QMessageBox.ButtonRole.RejectRole)
        box.setDefaultButton(keep)
        box.setEscapeButton(keep)
        box.exec()
        return box.clickedButton() is stop
