"""The live digitizer panel, made for a technician in the field with gloves on.

The panel shows a :class:`~maizeviz_app.digitizing.DigitizingSession` and decides nothing: the
recorder runs in a process of its own (``maizeviz record``, as on the command line), which
reads the port and writes every press to the journal (fsync) whatever this window is doing;
a 50 ms GUI timer asks the session what is new on disk and what the recorder said, and the
panel says it: a beep and the running count for each point on disk, a colour band and a beep
on trouble (a refused press, a garbled record, a lost port, a press far from the point before
it, a cross-section ended early), ``alert`` for the window's status bar. :class:`GrowingPlant`
re-meshes the leaf whose cross-section just finished, in a worker.

While recording, N, P, R, U and S (next leaf, next plant, end row, undo, pause) are
application-wide shortcuts: they act wherever the focus is, and the connection fields are
locked, so a letter can never end up typed into the file name. While paused a press is not
recorded, and each one is said (amber band, beep). The stylus tip's live position, and its
distance from the last point, show under the band (the reader polls the unit ten times a
second; see :mod:`maizeviz.digitizer.live`).

The port is chosen from the system's list (:class:`PortPicker`, with *Find FASTRAK*); what goes
wrong is said in the recorder's words (:mod:`maizeviz.digitizer.port_problems`), the same line
``maizeviz record`` prints. Connecting and stopping happen in the recorder's process, so the
window stays live: Stop returns at once (the recorder journals what it holds, then ends), and
the plant just digitized stays in the view. The session being recorded is remembered
(QSettings); if the app ended without stopping it (a crash), the next start offers that file
with *resume* ticked.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

from PySide6.QtCore import QEvent, QObject, QSettings, Qt, QTimer, Signal
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

from maizeviz.digitizer.recorder import PAUSE_KEY, LiveTip, Recorder, Update
from maizeviz.errors import MaizevizError
from maizeviz.resources import example_points
from maizeviz_app.digitizing import STOP_REASONS, DigitizingSession
from maizeviz_app.panels.growing_plant import GrowingPlant
from maizeviz_app.panels.port_picker import PortPicker

#: The technician's controls: key, button text.
CONTROLS = (("n", "Next leaf"), ("p", "Next plant"), ("r", "End row"), ("u", "Undo"))
#: QSettings keys: the session last recorded, and whether it is still open (not stopped).
LAST_SESSION, SESSION_OPEN = "digitizer/last_session", "digitizer/session_open"
#: Band colours (background, text) per state.
BAND = {"idle": ("#dcdcdc", "#202020"), "busy": ("#90caf9", "#102030"),
        "ok": ("#2e7d32", "#ffffff"), "warn": ("#f9a825", "#000000"),
        "error": ("#c62828", "#ffffff")}
BIG_BUTTON_PX = 56


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

    Parameters
    ----------
    viewport : the 3D view the plant grows in, or None
    session : the :class:`DigitizingSession` to show (the window's is the study model's);
        a new one if None

    Signals
    -------
    started : recording began (the recorder's process configured the unit and reads it)
    recorded(int) : points on disk so far (emitted when the window sees them)
    alert(str) : something went wrong (refused point, garbled record, lost port, write
        failure, no connection, a press while paused, a jump, a short section); for the
        window's status bar
    stopped(str) : the session ended (the recorder's process has exited, its journal
        closed), and why
    """

    started = Signal()
    recorded = Signal(int)
    alert = Signal(str)
    stopped = Signal(str)
    #: Ask before the window closes while recording (tests and benchmarks turn it off).
    confirm_close = True

    def __init__(self, viewport=None, parent=None, session: DigitizingSession | None = None):
        super().__init__(parent)
        self._viewport = viewport
        #: The session this panel shows (Qt-free: the recorder's process, what is on disk);
        #: the window's is the study model's (``StudyModel.digitizing``).
        self.digitizing = session if session is not None else DigitizingSession()
        if self.digitizing.demo_file is None:
            self.digitizing.demo_file = example_points()
        self.beeps = 0                             # trouble said with a beep
        self.press_beeps = 0                       # points confirmed with a beep
        self._why: str | None = None               # why the technician stopped
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
        self.press_count = QLabel("0 points")
        self.press_count.setAccessibleName("points on disk")
        self.press_count.setToolTip("points of this session on disk (each press confirmed with "
                                    "a beep once it is written)")
        font = self.press_count.font()
        font.setPointSize(max(font.pointSize(), 9) + 9)
        font.setBold(True)
        self.press_count.setFont(font)
        lay.addWidget(self.press_count)
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
        self._offer_resume()

    @property
    def demo_file(self):
        """The points file the Demo replays."""
        return self.digitizing.demo_file

    @demo_file.setter
    def demo_file(self, path) -> None:
        self.digitizing.demo_file = path

    @property
    def demo_pace(self) -> float:
        """Seconds between the Demo's presses."""
        return self.digitizing.demo_pace

    @demo_pace.setter
    def demo_pace(self, pace: float) -> None:
        self.digitizing.demo_pace = pace

    def _offer_resume(self) -> None:
        """A session the app did not stop (it crashed): offer its file, resume ticked."""
        last = str(self._settings.value(LAST_SESSION, "") or "")
        still_open = str(self._settings.value(SESSION_OPEN, "false")).lower() == "true"
        if not (last and still_open and Path(last).is_file()):
            return
        self.out_edit.setText(last)
        self.resume.setChecked(True)
        self.band.set_state("warn", f"the last session did not end cleanly: Connect continues "
                                    f"{last} where it stopped (resume is ticked)")
        self._say(f"last session not stopped (the app ended): {last}; resume is ticked")

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

    def _confirm(self) -> None:
        """A point is on disk: a beep and the running count (the technician's eyes are on the
        leaf, not the screen)."""
        QApplication.beep()
        self.press_beeps += 1

    def _loud(self, state: str, text: str) -> None:
        """Trouble the technician must notice without looking: band colour, beep, status bar."""
        self.band.set_state(state, text)
        self._beep()
        self.alert.emit(text)

    def _lock(self, running: bool, connecting: bool = False) -> None:
        busy = running or connecting
        idle = not busy and not self.digitizing.active and not self.ports.busy
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
    def session(self) -> DigitizingSession | None:
        """The session being recorded (its points, position and counts), or None."""
        d = self.digitizing
        return d if d.state in ("recording", "stopping") and d.path is not None else None

    @property
    def recording(self) -> bool:
        return self.digitizing.recording

    @property
    def paused(self) -> bool:
        return self.recording and self._paused

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
            n = self.session.count.points
            self.press_count.setText(f"{n} point{'s' if n != 1 else ''}")

    def _show_live(self) -> None:
        """The tip's position and distance (only when a newer answer came: no repaint else)."""
        tip = self.digitizing.live if self.recording else None
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
        self._lock(self.recording, self.digitizing.state == "connecting")
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
        """Start the recorder's process on the port (or on the Demo's simulated FASTRAK);
        recording begins when the unit answered (``started``)."""
        d = self.digitizing
        if d.active or self.ports.busy:
            return
        ref = 2 if self.reference.isChecked() else None
        port = self.port
        try:
            d.start(port, self.out_edit.text(), self.cols.value(), self.resume.isChecked(), ref,
                    self.baud.value(), demo=demo)
        except MaizevizError as exc:
            self._say(f"error: {exc}")
            self._loud("error", f"cannot record: {exc}")
            return
        self._why = None
        shown = d.port_name
        self.band.set_state("busy", f"connecting to {shown} at {self.baud.value()} baud…",
                            "connecting")
        self._lock(False, connecting=True)
        self.timer.start()

    def begin(self, recorder: Recorder) -> None:
        """Show an in-process ``recorder`` (scripts and tests driving the controls)."""
        self.digitizing.attach(recorder)
        self._why = None
        self._began()
        self.timer.start()

    def _began(self) -> None:
        """Recording began (the recorder answered ready)."""
        d = self.digitizing
        if d.sim is None and d.port_name:
            self._settings.setValue("port", d.port_name)
            self._settings.setValue("baud", self.baud.value())
        self._settings.setValue(LAST_SESSION, str(d.path))
        self._settings.setValue(SESSION_OPEN, "true")
        if self.viewport is not None:
            self.viewport.hide_canopy()
        self.plant.clear()
        self._set_paused(False)
        self._live_shown = None
        self.live.setText("tip: waiting for the unit…" if d.port_name else "tip: —")
        self._lock(True)
        self._say(f"recording to {d.path}")
        self.band.set_state("ok", "recording: press the stylus on the next point",
                            self._where())
        self._show_counts()
        if d.history:
            self.plant.update(d.history, d.pos)
        self.started.emit()

    def control(self, key: str) -> None:
        """A technician's control (n, p, r, u, q), handled at once."""
        if self.recording:
            self.digitizing.control(key)
            self._drain()

    def toggle_pause(self) -> None:
        """Pause or resume recording (the S key, the Pause button)."""
        if not self.recording:
            return
        self.digitizing.pause(not self._paused)
        self._drain()

    def _set_paused(self, on: bool) -> None:
        self._paused = on
        self.pause_button.setText(f"{'Resume' if on else 'Pause'}   [{PAUSE_KEY.upper()}]")
        self.pause_button.setAccessibleName("Resume" if on else "Pause")

    def _drain(self) -> None:
        """Show what the session has new: on disk, and said by the recorder (GUI thread).

        A slot: nothing may escape it (the journal is the recorder's, in its own process,
        whatever happens here).
        """
        d = self.digitizing
        if not d.active:
            return
        try:
            updates = d.poll()
            changed = False
            for update in updates:
                self._show_update(update)
                changed = changed or update.kind in ("recorded", "control", "moved")
            if updates:
                self._show_counts()
                self.band.where.setText(self._where())
            if changed and self.session is not None:
                self.plant.update(d.history, d.pos)
                self.recorded.emit(d.count.points)
            self._show_live()
        except Exception as exc:  # noqa: BLE001 - see the docstring
            self._say(f"error: {type(exc).__name__}: {exc}")
            self._loud("error", f"unexpected error in the window ({exc}); the recorder goes on "
                                "recording: Stop, then Connect with resume")
            return
        if d.final is not None:
            self._finish(d.final)

    def _show_update(self, update: Update) -> None:
        kind, text = update.kind, update.message
        if kind == "started":
            self._began()
        elif kind == "unconnected":
            self._say(f"error: {text}")
            if self._why is None:                     # not given up by the technician
                self._loud("error", f"not connected: {text}")
        elif kind in ("lost", "failed"):
            self._say(f"error: {text}")
            self._loud("error", text)
        elif kind in ("refused", "garbled", "ignored", "jump", "short"):
            self._say(text)
            self._loud("error" if kind == "refused" else "warn", text)
        elif kind == "paused":
            self._set_paused(True)
            self._say(text)
            self.band.set_state("warn", text)
        elif kind == "recorded":
            self._confirm()
            self._say(text)
            self.band.set_state("warn" if self.paused else "ok", text)
        elif kind in ("control", "resumed"):
            if kind == "resumed":
                self._set_paused(False)
            self._say(text)
            self.band.set_state("warn" if self.paused else "ok", text)
        elif text and kind not in ("finished", "moved"):
            self._say(text)

    # ------------------------------------------------------------------------ stopping
    def stop(self, why: str = "stopped", wait: bool = False) -> None:
        """End the session (or the connection attempt); every point shown is on disk.

        The recorder is asked to finish (it journals the presses it holds, then ends) and
        ``stopped(why)`` is emitted once it has. No frame is drawn for the stop: the plant
        stays as it was. With ``wait`` (the window is closing) it all happens here and now:
        the recorder's process, the reader threads and the Demo's simulator end before this
        returns.
        """
        d = self.digitizing
        self.ports.stop_search()
        if not d.active:
            self._lock(False)
            return
        if self._why is None:
            self._why = why
        if wait:
            self.timer.stop()
            for update in d.close():
                self._show_update(update)
            self._finish(d.final or Update("finished", "finished"))
            return
        d.stop()
        self._lock(False)
        self.band.set_state(self.band.state, where=f"stopping ({why})…")

    def _finish(self, final: Update) -> None:
        """The recorder has ended: let go of it, say how, and offer the file for resume."""
        d = self.digitizing
        why = self._why or STOP_REASONS.get(final.kind, final.kind)
        self._why = None
        self.timer.stop()
        recorded = final.kind != "unconnected"
        d.release()
        summary = ""
        if recorded:
            summary = d.summary()
            self._say(summary)
            self.counts.setText(summary)
            for warning in d.warnings[-3:]:
                self._say(f"(during the session) {warning}")
        self._settings.setValue(SESSION_OPEN, "false")
        self._set_paused(False)
        if recorded and d.history:
            # Connect again continues this file where it stopped (the journal replays it)
            self.resume.setChecked(True)
        self._lock(False)
        where = f"not recording ({why})"
        if self.band.state in ("error", "warn") and why != "finished":
            self.band.set_state(self.band.state, where=where)   # keep the trouble in sight
        else:
            self.band.set_state("idle", summary or None, where)
        self.stopped.emit(why)

    def release_view(self) -> None:
        """The view goes back to the canopy: forget the plant (a leaf still being meshed is
        never drawn over the canopy)."""
        if not self.recording:
            self.plant.clear()

    def may_close(self, parent: QWidget | None = None) -> bool:
        """Ask before the window closes while recording; True when it may close."""
        if not self.confirm_close or not self.digitizing.active:
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
