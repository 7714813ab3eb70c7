"""The live digitizer panel: a FASTRAK (or the simulator in demo mode) feeding a session.

The serial reader is one long-lived thread (``FastrakPort.start_reader``) that parses records
into a queue; a GUI timer drains the queue in batches, so the window never blocks on the port.
Every point goes through :class:`~maizeviz.digitizer.session.Session`, which puts it on disk
(fsync) before the panel shows it. The current leaf's points are drawn in the 3D view as they
arrive.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings, QTimer, Signal
from PySide6.QtWidgets import (QCheckBox, QFileDialog, QFormLayout, QHBoxLayout, QLabel,
                               QLineEdit, QListWidget, QPushButton, QSpinBox, QVBoxLayout,
                               QWidget)

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session
from maizeviz.errors import MaizevizError
from maizeviz.resources import example_points


class DigitizerPanel(QWidget):
    """Connect to a FASTRAK (or a simulated one), record presses, show the leaf growing."""

    recorded = Signal(int)              # points recorded so far
    stopped = Signal(str)               # why the session ended

    def __init__(self, viewport=None, parent=None):
        super().__init__(parent)
        self.viewport = viewport
        self.recorder: Recorder | None = None
        self.sim = None
        self._replay: threading.Thread | None = None
        self._settings = QSettings("maizeviz", "maizeviz")
        self.demo_file = example_points()
        self.demo_pace = 0.5

        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.port_edit = QLineEdit(str(self._settings.value("port", "/dev/ttyUSB0")))
        form.addRow("serial port", self.port_edit)
        self.baud = QSpinBox(minimum=1200, maximum=115200, value=115200, singleStep=9600)
        form.addRow("baud", self.baud)
        self.cols = QSpinBox(minimum=2, maximum=15, value=5)
        form.addRow("points per cross-section", self.cols)
        out_row = QHBoxLayout()
        stamp = time.strftime("%Y%m%d-%H%M%S")
        self.out_edit = QLineEdit(str(Path.home() / f"maizeviz-session-{stamp}.csv"))
        browse = QPushButton("…")
        browse.clicked.connect(self._choose_out)
        out_row.addWidget(self.out_edit, 1)
        out_row.addWidget(browse)
        form.addRow("record to", out_row)
        self.resume = QCheckBox("continue this file (resume)")
        form.addRow(self.resume)
        self.reference = QCheckBox("receiver 2 on the stalk (motion compensation)")
        form.addRow(self.reference)
        lay.addLayout(form)
        buttons = QHBoxLayout()
        self.connect_button = QPushButton("Connect")
        self.connect_button.clicked.connect(lambda: self.start(demo=False))
        self.demo_button = QPushButton("Demo (simulated FASTRAK)")
        self.demo_button.clicked.connect(lambda: self.start(demo=True))
        self.stop_button = QPushButton("Stop")
        self.stop_button.clicked.connect(lambda: self.stop("stopped"))
        self.stop_button.setEnabled(False)
        for b in (self.connect_button, self.demo_button, self.stop_button):
            buttons.addWidget(b)
        lay.addLayout(buttons)
        controls = QHBoxLayout()
        self.control_buttons = []
        for key, text in (("n", "Next leaf"), ("p", "Next plant"), ("r", "End row"),
                          ("u", "Undo")):
            b = QPushButton(text)
            b.setShortcut(key.upper())
            b.setToolTip(f"shortcut {key.upper()}")
            b.clicked.connect(lambda _=False, k=key: self.control(k))
            b.setEnabled(False)
            controls.addWidget(b)
            self.control_buttons.append(b)
        lay.addLayout(controls)
        self.where = QLabel("not recording")
        self.counts = QLabel("")
        lay.addWidget(self.where)
        lay.addWidget(self.counts)
        self.log = QListWidget()
        lay.addWidget(self.log, 1)
        self.timer = QTimer(self, interval=50)
        self.timer.timeout.connect(self._drain)

    # -------------------------------------------------------------------------- ui
    def _choose_out(self):
        path, _ = QFileDialog.getSaveFileName(self, "Record to", self.out_edit.text(),
                                              "Points CSV (*.csv)")
        if path:
            self.out_edit.setText(path)

    def _say(self, text: str) -> None:
        self.log.addItem(text)
        self.log.scrollToBottom()
        while self.log.count() > 400:
            self.log.takeItem(0)

    def _set_running(self, running: bool) -> None:
        self.connect_button.setEnabled(not running)
        self.demo_button.setEnabled(not running)
        self.stop_button.setEnabled(running)
        for b in self.control_buttons:
            b.setEnabled(running)

    @property
    def session(self) -> Session | None:
        return self.recorder.session if self.recorder is not None else None

    def _show_state(self) -> None:
        if self.session is None:
            return
        p = self.session.pos
        self.where.setText(f"next point: plant {p.plant}, leaf {p.leaf}, row {p.row}, col {p.col}")
        self.counts.setText(self.session.summary())

    # ----------------------------------------------------------------------- session
    def start(self, demo: bool = False) -> None:
        """Open the session file, then the port (or a simulator), then start reading."""
        ref = 2 if self.reference.isChecked() else None
        try:
            session = Session(self.out_edit.text(), self.cols.value(), self.resume.isChecked(),
                              ref)
        except MaizevizError as exc:
            self._say(f"error: {exc}")
            return
        port_name = self.port_edit.text()
        if demo:
            from maizeviz.digitizer.simulator import FastrakSimulator

            self.sim = FastrakSimulator(stations=(1, 2) if ref else (1,))
            port_name = self.sim.path
            self._say(f"demo: simulated FASTRAK on {port_name}")
        port = FastrakPort(port_name, self.baud.value(), answer_timeout=1.0)
        self.recorder = Recorder(session, port)
        try:
            cfg = port.configure((1,) if ref is None else (1, ref))
        except MaizevizError as exc:
            self._say(f"error: {exc}")
            self.stop("could not connect")
            return
        for w in cfg.warnings:
            self._say(f"warning: {w}")
        if not demo:
            self._settings.setValue("port", port_name)
        self.recorder.start()
        if self.viewport is not None:
            self.viewport.hide_canopy()
        self.timer.start()
        self._set_running(True)
        self._say(f"recording to {session.path}")
        self._show_state()
        if demo:
            self._start_replay(ref is not None)

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
        """A technician's control (n, p, r, u, q), handled at the next drain."""
        if self.recorder is not None:
            self.recorder.control(key)
            self._drain()

    def _drain(self) -> None:
        """Handle what the reader and the controls queued since the last tick (GUI thread)."""
        if self.recorder is None:
            return
        changed = False
        for update in self.recorder.poll(limit=2000):
            if update.message and update.kind != "finished":
                self._say(("error: " if update.kind in ("lost", "failed") else "")
                          + update.message)
            changed = changed or update.kind in ("recorded", "control")
        if changed:
            self._show_state()
            self._draw_leaf()
            if self.session is not None:
                self.recorded.emit(self.session.count.points)
        final = self.recorder.final
        if final is not None:
            self.stop({"finished": "finished", "lost": "port lost",
                       "failed": "cannot write"}.get(final.kind, final.kind))

    def _draw_leaf(self) -> None:
        """The plant being digitized: its points, and a surface through each leaf's complete
        cross-sections (the standard mesh refined twice), so the technician sees the leaf grow."""
        if self.viewport is None or self.session is None or not self.session.history:
            return
        from maizeviz.errors import LeafError
        from maizeviz.leaf.grid import grid_from_rows
        from maizeviz.leaf.fit import Leaf
        from maizeviz.mesh.levels import Level, mesh_leaf
        from maizeviz.leaf.nurbs import fit_surface

        plant = self.session.history[-1][0].plant
        mine = [(p, xyz) for p, xyz in self.session.history if p.plant == plant]
        leaves: dict = {}
        for p, xyz in mine:
            leaves.setdefault(p.leaf, {}).setdefault(p.row, []).append(xyz)
        meshes = []
        cols = self.session.cols
        for leaf, rows in leaves.items():
            full = {r: np.array(v) for r, v in rows.items() if len(v) == cols or len(v) == 1}
            keep = {}
            for r in range(len(full)):                    # consecutive complete rows from 0
                if r not in full:
                    break
                keep[r] = full[r]
            if len(keep) < 2:
                continue
            try:
                grid = grid_from_rows(plant, leaf, keep)
                surf = fit_surface(grid.points, plant=plant, leaf=leaf)
                meshes.append(mesh_leaf(Leaf(grid, surf), Level(interp=2)))
            except (LeafError, ValueError, np.linalg.LinAlgError):
                continue
        self.viewport.show_leaf_surfaces(meshes, np.array([xyz for _, xyz in mine]))

    def stop(self, why: str = "stopped") -> None:
        self.timer.stop()
        recorder, self.recorder = self.recorder, None
        if recorder is not None and recorder.port is not None:
            recorder.port.close()
        if self.sim is not None:
            self.sim.close()
            self.sim = None
        if self._replay is not None:
            self._replay.join(timeout=5)
            self._replay = None
        if recorder is not None:
            summary = recorder.session.summary()
            self._say(summary)
            self.counts.setText(summary)
            recorder.close()
        self.where.setText(f"not recording ({why})")
        self._set_running(False)
        self.stopped.emit(why)
