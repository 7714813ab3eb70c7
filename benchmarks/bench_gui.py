"""How the desktop app feels: GIL stalls, renders, slider latency, start-up, event-loop gaps.

Run under a display (``xvfb-run -a -s "-screen 0 1366x768x24" python benchmarks/bench_gui.py
--json``) on the bundled example (the 3 x 3 block tiled 3 x 3, 81 plants). Prints:

- ``gil_max_block_ms``: longest gap of a pure-Python thread (sleeping 1 ms at a time) while the
  app's own jobs rebuild the canopy at K = 4 (measures included) and trace light on it (hit
  classes on, as the app asks); no Qt, no graphics. ``gil_idle_max_gap_ms`` is the same thread
  with nothing running: on a shared machine the OS alone can delay a thread that long.
- ``idle_renders_per_s``: frames the 3D view renders while nothing happens (target 0).
- ``renders_per_canopy``: frames rendered for each new canopy (target 1), per level and worst.
- ``slider_to_view_s``: {level: seconds from the slider move to the new canopy's frame}.
- ``first_window_s``: from launching the app (a new Python process) to its window on screen;
  ``first_canopy_s``: to the first canopy's frame.
- ``event_loop_max_gap_ms``: {level: longest gap of a 10 ms timer on the GUI thread from the
  slider move to the new frame}; ``light_event_loop_max_gap_ms`` during a light run at 36
  triangles. Targets: under 200 ms at 36 triangles and below, and at K = 4 (the view then
  draws the sampled tile at K = 4, the other plants coarser), on software OpenGL.
  With ``--repeat N`` every level is visited N times: the medians, and every sample in
  ``..._samples``. ``frame_event_loop_gap_ms``: of those, the longest gap from the canopy
  shown to its frame (0 when under 50 ms): what the view's budget holds; the gaps before it
  are the build's (its worker threads and the machine's load).
- ``undo_level_to_canopy_s`` and ``undo_level_event_loop_max_gap_ms``: Edit > Undo of a
  level (16 back to 36 triangles) to the canopy shown again, and the longest gap meanwhile.
- ``layout_<edit>_ms`` and ``layout_<edit>_event_loop_max_gap_ms``: the layout editor on a
  field of 30 x 30 plants (the 3D view not following): laying it out by rows x plants, moving
  one plant, undoing the move, undoing the whole field (target: an edit or an undo on 900
  plants leaves no gap over 200 ms; laying out 900 plants where there were 81 makes 819 new
  items in the top view once: 47 ms on a quiet machine, 0.24 s on a busy one).
- ``pick_ms``: a click on a leaf of the K = 4 canopy, from the release event's delivery to the
  leaf picked, highlighted and described (the event loop is held that long; target under 50
  ms), median and worst of the clicks (``pick_ms_samples``); ``pick_frame_gap_ms``: the
  longest gap of the 10 ms timer from a click through the frame that shows the highlight
  (median over the clicks, and the worst).
- ``mesh_file_event_loop_max_gap_ms``: opening the K = 4 canopy exported as a PLY (File > Open
  canopy mesh), the longest gap from the open to its first frame (target under 200 ms, as for
  built canopies); ``mesh_file_frame_gap_ms`` the gap of the frame itself (from the canopy
  shown), ``mesh_file_drawn`` the triangles the view draws of it, ``mesh_file_s`` the time to
  the frame.
- ``stop_event_loop_max_gap_ms``: longest gap of the 10 ms timer from pressing the digitizer's
  Stop to 0.3 s after the session reported stopped (its port closed, its journal closed), for a
  session on a simulated FASTRAK (a real pty) with one leaf meshed, and ``..._demo`` for the
  Demo (its replay thread sleeping between presses), each clicked with no press in flight (a
  press's own frame is the recording's). Target: under 50 ms. ``stop_idle_max_gap_ms`` is the
  same timer over the 0.4 s (0.1 s for the Demo) just before each Stop: what the machine's
  load alone does to the event loop at that moment. Stops are repeated ``max(5, N)`` times.
- ``digitizer_presses_lost``, ``digitizer_press_to_disk_worst_s`` (and ``_median_s``): the
  promise of the digitizer under load. A scripted technician in another process
  (:mod:`maizeviz.digitizer.technician`) presses a simulated FASTRAK ``--presses`` times (200),
  0.35-0.5 s apart, asking for N/P before each new leaf, into the window's digitizer (the
  recorder in its own process) while one ``while True: pass`` burner per core runs; lost is
  the presses the unit accepted that are not in the file (target 0), the latency is from the
  unit's acceptance to the journal line's time stamp (written just before its fsync).
  ``digitizer_order_ok``: every point at its plant/leaf/row/col, in order.
  ``digitizer_press_to_window_worst_s``: from the acceptance to the window's count showing
  it (the window lags under load; the file does not wait for it).
- ``view_px``: the 3D view's size in pixels (the window is 1366 x 740, docks as on a first start).
- ``anchor_s``: a fixed numpy workload timed in the same run (these machines are shared and
  noisy; compare runs through it); ``anchor_end_s`` the same after the GUI part.

    python benchmarks/bench_gui.py [--json] [--levels K4,K2,K1,standard,36,16,8,4] [--repeat N]
                                   [--presses N] [--only digitizer]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Self

from anchors import matmul_anchor

ROOT = Path(__file__).resolve().parents[1]
STOPS = "K4,K2,K1,standard,36,16,8,4"
TIMEOUT_S = 600


class GilProbe:
    """A pure-Python thread that sleeps 1 ms at a time and records the longest gap."""

    def __init__(self) -> None:
        self.worst = 0.0
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        last = time.perf_counter()
        while not self._stop:
            time.sleep(0.001)
            now = time.perf_counter()
            self.worst = max(self.worst, now - last)
            last = now

    def __enter__(self) -> Self:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop = True
        self._thread.join()


class Ticket:
    def __init__(self) -> None:
        self.cancel = threading.Event()

    def report(self, done: int, total: int, text: str = "") -> bool:
        return True


def gil_part() -> dict:
    """The app's build and light jobs at K = 4, no Qt: the longest stall of a Python thread."""
    sys.setswitchinterval(0.005)
    from maizeviz_app import jobs
    from maizeviz_app.process import CoreProcess

    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sun import Sun
    from maizeviz.resources import example_points

    cover, light = CoreProcess("cover"), CoreProcess("light")
    cover.start()
    light.start()
    with GilProbe() as idle:
        time.sleep(3.0)
    loaded = jobs.load_points(str(example_points()), (3, 3))
    import gc

    gc.freeze()                       # as the app does once started (shorter GC pauses)
    pauses: list[float] = []
    started: dict[str, float] = {}

    def gc_timer(phase: str, info: dict) -> None:
        if phase == "start":
            started["t"] = time.perf_counter()
        elif "t" in started:
            pauses.append(time.perf_counter() - started["t"])

    gc.callbacks.append(gc_timer)
    out = {"gil_idle_max_gap_ms": idle.worst * 1000}
    with GilProbe() as probe:
        t0 = time.perf_counter()
        canopy, build_s, label = jobs.build(loaded, "K4", True)
        cover.call("measure", 1, canopy, (jobs.APP_COVER_RESOLUTION_CM,), Ticket())
        t1 = time.perf_counter()
        req = LightRequest(Sun(22.34, 166.95),
                           Sampling((0, 50, 100, 150, 200, 225), 2.0, None, True, 2), classes=True)
        result = light.call("light", 1, canopy, (req,), Ticket())
        result.triangle_light(canopy)
        t2 = time.perf_counter()
    gc.callbacks.remove(gc_timer)
    cover.close()
    light.close()
    out.update({"gil_max_block_ms": probe.worst * 1000,
                "gc_max_pause_ms": max(pauses, default=0.0) * 1000, "k4_rebuild_and_measure_s": t1 - t0,
                "k4_light_s": t2 - t1, "k4_triangles": canopy.n_triangles})
    return out


# ---------------------------------------------------------------------------- GUI parts
def _app():
    os.environ.setdefault("QT_API", "pyside6")
    from maizeviz_app.main import gl_format
    from PySide6.QtWidgets import QApplication

    gl_format()
    return QApplication.instance() or QApplication([sys.argv[0]])


def _window():
    """A child process's QApplication and window: the app on the bundled example at a
    laptop's size, shown (hold the application while the window lives)."""
    os.environ["XDG_CONFIG_HOME"] = os.environ.get("BENCH_CONFIG", "/tmp/maizeviz-bench-cfg")
    app = _app()
    from maizeviz_app.main_window import MainWindow

    from maizeviz.resources import example_points

    window = MainWindow(str(example_points()), 3)
    window.confirm_unsaved = False          # the benchmark closes with results unsaved
    window.resize(1366, 740)
    window.show()
    return app, window


def _spin(seconds: float, until=None) -> bool:
    """Run the event loop for up to ``seconds``; True once ``until()`` is (or, without it,
    when the time is up)."""
    from PySide6.QtCore import QCoreApplication

    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        QCoreApplication.processEvents()
        if until is not None and until():
            return True
        time.sleep(0.002)
    return until is None


def startup_child() -> None:
    """Launched as a new process: print when the window is exposed and when the first canopy
    is on screen (the parent times from the launch)."""
    from PySide6.QtCore import QTimer

    app, window = _window()
    said = {"window": False}

    def poll() -> None:
        handle = window.windowHandle()
        if not said["window"] and handle is not None and handle.isExposed():
            said["window"] = True
            print("window", flush=True)

    timer = QTimer(interval=5)
    timer.timeout.connect(poll)
    timer.start()

    def canopy(_label: str) -> None:
        window.viewport.rendered.connect(lambda _n: (print("canopy", flush=True),
                                                     window.close(), app.quit()))

    window.canopy_shown.connect(canopy)
    QTimer.singleShot(TIMEOUT_S * 1000, app.quit)
    app.exec()


def startup_part() -> dict:
    env = dict(os.environ, BENCH_CONFIG=f"/tmp/maizeviz-bench-{os.getpid()}")
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, __file__, "--child", "startup"],
                            stdout=subprocess.PIPE, text=True, env=env)
    times = {}
    assert proc.stdout is not None
    for line in proc.stdout:
        times[line.strip()] = time.perf_counter() - t0
    proc.wait(TIMEOUT_S)
    return {"first_window_s": times.get("window"), "first_canopy_s": times.get("canopy")}


class GapTimer:
    """A 10 ms QTimer on the GUI thread: the longest gap between its ticks."""

    def __init__(self) -> None:
        from PySide6.QtCore import QTimer

        self.worst = 0.0
        self._last = time.perf_counter()
        self.spans: list[tuple[float, float]] = []     # (start, end) of gaps over 50 ms
        self.timer = QTimer(interval=10)
        self.timer.timeout.connect(self._tick)

    def _tick(self) -> None:
        now = time.perf_counter()
        self.worst = max(self.worst, now - self._last)
        if now - self._last > 0.05:
            self.spans.append((self._last, now))
        self._last = now

    def start(self) -> None:
        self.worst = 0.0
        self.spans = []
        self._last = time.perf_counter()
        self.timer.start()

    def worst_after(self, t: float) -> float:
        """The longest gap (ms) that ended after ``t`` (perf_counter seconds)."""
        return 1000 * max((b - a for a, b in self.spans if b > t), default=0.0)

    def stop(self) -> float:
        self._tick()
        self.timer.stop()
        return self.worst * 1000


def gui_child(levels: list[str], repeat: int = 1) -> None:
    """In a display: idle renders, renders per canopy, slider latency and gaps per level."""
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    spin = _spin
    app, window = _window()
    shown: list[str] = []
    window.canopy_shown.connect(shown.append)
    assert spin(TIMEOUT_S, lambda: bool(shown)), "no first canopy"
    view = window.viewport
    spin(1.0)
    n0 = view.render_count
    spin(5.0)
    out: dict = {"idle_renders_per_s": (view.render_count - n0) / 5.0,
                 "view_px": [view.width(), view.height()]}
    samples: dict = {"slider_to_view_s": {}, "event_loop_max_gap_ms": {},
                     "frame_event_loop_gap_ms": {}, "renders_per_level": {}}
    gaps = GapTimer()
    shown_at: list[float] = []
    window.canopy_shown.connect(lambda _label: shown_at.append(time.perf_counter()))
    current = window.model.settings.canopy.level
    for level in levels * repeat:
        if level == current:
            window.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("4" if level != "4" else "8"))
            assert spin(TIMEOUT_S, lambda: bool(shown) and window.runner.current("build") is None
                        and not window.canopy_panel.asked_label.text())
            spin(1.0)
        before = len(shown)
        frames_before = view.render_count
        gaps.start()
        t0 = time.perf_counter()
        window.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index(level))
        assert spin(TIMEOUT_S, lambda before=before: len(shown) > before), f"no canopy at {level}"
        framed = view.render_count
        spin(TIMEOUT_S, lambda framed=framed: view.render_count > framed)
        samples["slider_to_view_s"].setdefault(level, []).append(time.perf_counter() - t0)
        samples["event_loop_max_gap_ms"].setdefault(level, []).append(gaps.stop())
        samples["frame_event_loop_gap_ms"].setdefault(level, []).append(
            gaps.worst_after(shown_at[-1]))
        spin(1.0)
        samples["renders_per_level"].setdefault(level, []).append(view.render_count - frames_before)
        current = level
    for name, per_level in samples.items():
        out[name] = {lv: statistics.median(v) for lv, v in per_level.items()}
        if repeat > 1 and name != "renders_per_level":
            out[name + "_samples"] = per_level
    out["renders_per_level"] = {lv: max(v) for lv, v in samples["renders_per_level"].items()}
    out["renders_per_canopy"] = max(out["renders_per_level"].values(), default=None)
    # a light run at 36 triangles: the event loop while the child traces
    if "36" in levels:
        window.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("36"))
        spin(TIMEOUT_S, lambda: shown[-1] == "36 triangles" and
             window.runner.current("build") is None)
        spin(1.0)
        lit: list = []
        window.light_shown.connect(lambda: lit.append(1))
        gaps.start()
        t0 = time.perf_counter()
        window.model.compute_light()
        spin(TIMEOUT_S, lambda: bool(lit))
        out["light_36_s"] = time.perf_counter() - t0
        out["light_event_loop_max_gap_ms"] = gaps.stop()
    out.update(edit_part(window, spin, gaps, shown))
    out.update(stop_gaps(window, gaps, spin, repeat))
    if "K4" in levels:
        out.update(rotation_part(window, spin, shown))
        out.update(pick_and_mesh_file(window, spin, gaps, shown))
    window.close()
    print(json.dumps(out), flush=True)


def edit_part(window, spin, gaps, shown: list) -> dict:
    """Undo and the layout editor on the GUI thread: an undone level (the canopy rebuilt, as
    the edit did), and on a regular field of 30 x 30 plants (900, the 3D view not following)
    laying it out, moving one plant, undoing the move and undoing the whole field; each as
    the time the GUI thread takes and the longest gap of the 10 ms timer until it is drawn
    (overlaps included)."""
    out: dict = {}
    undo = window.menu_actions["undo"]
    before = len(shown)
    window.model.settings.canopy.level = "16"
    spin(TIMEOUT_S, lambda: len(shown) > before and window.runner.current("build") is None)
    spin(1.0)
    before = len(shown)
    gaps.start()
    t0 = time.perf_counter()
    undo.trigger()
    spin(TIMEOUT_S, lambda: len(shown) > before)
    out["undo_level_to_canopy_s"] = time.perf_counter() - t0
    out["undo_level_event_loop_max_gap_ms"] = gaps.stop()
    panel = window.layout_panel
    window.docks["layout"].raise_()
    panel.follow.setChecked(False)
    panel.rows_box.setValue(30)
    panel.per_row_box.setValue(30)
    spin(0.5)
    draft = panel.draft

    def timed(name: str, action) -> None:
        gaps.start()
        t0 = time.perf_counter()
        action()
        out[f"layout_{name}_ms"] = (time.perf_counter() - t0) * 1000
        spin(0.3)                                # the overlaps (debounced 60 ms) and a paint
        out[f"layout_{name}_event_loop_max_gap_ms"] = gaps.stop()

    timed("lay_out_900", panel.lay_out)
    p = draft.placements[450]
    timed("move_one_of_900", lambda: draft.move(450, p.x + 40.0, p.y + 10.0))
    timed("undo_move_of_900", undo.trigger)
    timed("undo_lay_out_900", undo.trigger)
    return out


def stop_gaps(window, gaps: GapTimer, spin, repeat: int = 1) -> dict:
    """The event loop while the digitizer stops: a session on a simulated unit (a leaf's worth
    of presses, its surface meshed) and a Demo, ``max(5, repeat)`` times each."""
    import tempfile

    from maizeviz.digitizer.simulator import FastrakSimulator

    panel = window.digitizer
    folder = Path(tempfile.mkdtemp(prefix="maizeviz-bench-stop-"))
    samples: dict[str, list[float]] = {"stop_event_loop_max_gap_ms": [],
                                       "stop_event_loop_max_gap_ms_demo": [],
                                       "stop_idle_max_gap_ms": [],
                                       "stop_idle_max_gap_ms_demo": []}
    for k in range(max(5, repeat)):
        for demo in (False, True):
            stopped: list[str] = []
            panel.stopped.connect(stopped.append)
            panel.out_edit.setText(str(folder / f"s{k}{'d' * demo}.csv"))
            panel.cols.setValue(3)
            sim = None
            if demo:
                panel.demo_pace = 0.5
                panel.start(demo=True)
                assert spin(TIMEOUT_S, lambda: panel.session is not None
                            and panel.session.count.points >= 4), "the demo did not record"
                # Stop between two presses (the demo presses every 0.5 s): a press's own
                # frame and leaf meshing are the recording's, not the Stop's
                n = panel.session.count.points
                assert spin(10, lambda n=n: panel.session.count.points > n)
                panel.plant.wait()
                gaps.start()                         # the same loop idle, just before
                spin(0.1)
            else:
                sim = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
                panel.ports.set_port(sim.path)
                panel.start()
                assert spin(TIMEOUT_S, lambda: panel.recording), "no connection"
                for i in range(7):                   # two cross-sections and one point
                    n = panel.session.count.points
                    sim.press((2.0 * (i % 3), 0.5 * (i // 3), 10.0 + 8.0 * (i // 3)))
                    assert spin(10, lambda n=n: panel.session.count.points > n)
                panel.plant.wait()
                spin(0.1)
                gaps.start()
                spin(0.4)
            idle = gaps.stop()
            gaps.start()
            panel.stop_button.click()
            assert spin(TIMEOUT_S, lambda stopped=stopped: bool(stopped)), "no stop"
            spin(0.3)
            suffix = "_demo" if demo else ""
            samples["stop_event_loop_max_gap_ms" + suffix].append(gaps.stop())
            samples["stop_idle_max_gap_ms" + suffix].append(idle)
            panel.stopped.disconnect(stopped.append)
            if sim is not None:
                sim.close()
            window.workspaces.show("analyse")        # the canopy back, for the next session
            spin(1.0)
    out: dict = {name: statistics.median(v) for name, v in samples.items()}
    out.update({name + "_samples": v for name, v in samples.items()})
    return out


def _leaf_pixels(view, n: int):
    """Widget points over ``n`` leaf triangles of the view's mesh that a click picks."""
    import numpy as np

    mesh = view.canopy_mesh
    nf = int(mesh.field_data["leaf_triangles"][0])
    faces, points = mesh.regular_faces[:nf], np.asarray(mesh.points)
    out = []
    for cell in np.random.default_rng(7).permutation(nf):
        x, y = view.display_point(points[faces[cell]].mean(axis=0))
        if 10 < x < view.width() - 10 and 10 < y < view.height() - 10:
            p = view.pick_at(round(x), round(y))
            if p is not None and p.leaf > 0:
                out.append((round(x), round(y)))
        if len(out) == n:
            return out
    return out


def rotation_part(window, spin, shown, frames: int = 40) -> dict:
    """Turning the camera at K = 4, as a drag does (4 deg a frame): each frame's time drawn
    whole, and with the lighter drawing a moving camera gets (every k-th triangle; the whole
    canopy again once it stops); the frames over 200 ms are the stalls."""
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    window.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("K4"))
    spin(TIMEOUT_S, lambda: shown[-1].startswith("K=4") and window.runner.current("build") is None)
    spin(1.0)
    view = window.viewport

    def turn() -> list[float]:
        out = []
        for _ in range(frames):
            t0 = time.perf_counter()
            view.camera.azimuth += 4.0
            view.render()
            spin(0.001)
            out.append(1000 * (time.perf_counter() - t0))
        return out

    whole = turn()
    moving = view.start_moving()
    light = turn()
    t0 = time.perf_counter()
    view.stop_moving()
    back_ms = 1000 * (time.perf_counter() - t0)
    return {"rotation_triangles": view.canopy_mesh.n_cells,
            "rotation_frame_ms_whole": {"median": statistics.median(whole), "max": max(whole),
                                        "over_200": sum(t > 200 for t in whole)},
            "rotation_frame_ms_moving": {"median": statistics.median(light), "max": max(light),
                                         "over_200": sum(t > 200 for t in light),
                                         "lighter": moving},
            "rotation_stop_to_whole_ms": back_ms}


def pick_and_mesh_file(window, spin, gaps, shown, clicks: int = 15) -> dict:
    """Clicks on leaves of the K = 4 canopy, then the K = 4 canopy opened from a PLY."""
    import tempfile

    from PySide6.QtCore import QPoint, Qt
    from PySide6.QtTest import QTest

    from maizeviz.canopy.export import export_canopy
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    out: dict = {}
    view = window.viewport
    if window.model.settings.canopy.level != "K4":
        before = len(shown)
        window.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("K4"))
        spin(TIMEOUT_S, lambda: len(shown) > before and window.runner.current("build") is None)
    spin(1.0)
    picks, frame_gaps = [], []
    for x, y in _leaf_pixels(view, clicks):
        frames = view.render_count
        gaps.start()
        QTest.mouseClick(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier,
                         QPoint(x, y))
        picks.append(view.last_pick_ms)
        spin(5.0, lambda frames=frames: view.render_count > frames)
        frame_gaps.append(gaps.stop())
        spin(0.3)
    if picks:
        out.update({"pick_ms": statistics.median(picks), "pick_max_ms": max(picks),
                    "pick_ms_samples": [round(p, 1) for p in picks],
                    "pick_frame_gap_ms": statistics.median(frame_gaps),
                    "pick_frame_gap_max_ms": max(frame_gaps),
                    "pick_drawn": view.canopy_mesh.n_cells})
    folder = tempfile.mkdtemp(prefix="maizeviz-bench-mesh-")
    ply = str(Path(folder) / "k4.ply")
    export_canopy(ply, window.model.canopy)
    spin(1.0)
    before = len(shown)
    when: dict = {}
    window.canopy_shown.connect(lambda _l: when.setdefault("shown", time.perf_counter()))
    gaps.start()
    t0 = time.perf_counter()
    window.open_mesh(ply, "cm", "z")
    spin(TIMEOUT_S, lambda: len(shown) > before)
    spin(3.0)                                   # its frame, and what follows it
    worst = gaps.stop()
    out.update({"mesh_file_s": time.perf_counter() - t0,
                "mesh_file_event_loop_max_gap_ms": worst,
                "mesh_file_frame_gap_ms": gaps.worst_after(when.get("shown", t0)),
                "mesh_file_drawn": view.canopy_mesh.n_cells,
                "mesh_file_triangles": window.model.canopy.n_triangles})
    import shutil

    shutil.rmtree(folder, ignore_errors=True)
    return out


def digitizer_child(presses: int) -> None:
    """In a display: the window's digitizer under CPU burners (see ``digitizer_...``)."""
    import csv
    import tempfile

    import numpy as np

    from maizeviz.digitizer.technician import Technician
    from maizeviz.io.points import read_points

    spin = _spin
    app, window = _window()
    assert spin(TIMEOUT_S, lambda: window.digitizer is not None), "no digitizer"
    panel = window.digitizer
    panel.confirm_close = False
    window.workspaces.show("digitize")
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
               for _ in range(os.cpu_count() or 1)]
    tech = Technician(presses, (0.35, 0.5), seed=1)
    shown: dict[int, float] = {}
    out = Path(tempfile.mkdtemp(prefix="maizeviz-bench-load-")) / "load.csv"
    try:
        panel.ports.set_port(tech.wait_port())
        panel.out_edit.setText(str(out))
        panel.cols.setValue(5)
        panel.start()
        assert spin(TIMEOUT_S, lambda: panel.recording), "no connection"
        d = panel.digitizing
        panel.recorded.connect(lambda n: shown.setdefault(n - 1, time.time()))
        tech.follow(panel.control, lambda: (d.pos.plant, d.pos.leaf), lambda: d.count.points,
                    lambda s: spin(s), timeout=presses * 2.0)
        stopped: list[str] = []
        panel.stopped.connect(stopped.append)
        panel.stop_button.click()
        assert spin(TIMEOUT_S, lambda: bool(stopped)), "no stop"
    finally:
        tech.close()
        for b in burners:
            b.kill()
            b.wait()
    pts = read_points(out)
    with open(out, newline="") as fh:
        stamps = [float(r["time"]) for r in csv.DictReader(fh) if r["status"] == "recorded"]
    pressed = [tech.pressed[k] for k in sorted(tech.pressed)]
    n = min(len(stamps), len(pressed))
    lat = [stamps[k] - pressed[k] for k in range(n)]
    to_window = [shown[k] - tech.pressed[k] for k in shown if k in tech.pressed]
    order = len(pts) == len(tech.ids) and bool(np.array_equal(pts.ids, tech.ids))
    window.close()
    print(json.dumps({"digitizer_presses": len(pressed),
                      "digitizer_presses_lost": len(pressed) - len(pts),
                      "digitizer_order_ok": order,
                      "digitizer_press_to_disk_worst_s": max(lat, default=None),
                      "digitizer_press_to_disk_median_s": statistics.median(lat) if lat else None,
                      "digitizer_press_to_window_worst_s": max(to_window, default=None),
                      "digitizer_burners": len(burners)}), flush=True)


def digitizer_part(presses: int) -> dict:
    env = dict(os.environ, BENCH_CONFIG=f"/tmp/maizeviz-bench-{os.getpid()}-digitizer")
    proc = subprocess.run([sys.executable, __file__, "--child", "digitizer", "--presses",
                           str(presses)], stdout=subprocess.PIPE, text=True, env=env,
                          timeout=TIMEOUT_S + presses * 2)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        raise SystemExit(f"the digitizer run failed (exit {proc.returncode})")
    return json.loads(lines[-1])


def gui_part(levels: list[str], repeat: int = 1) -> dict:
    env = dict(os.environ, BENCH_CONFIG=f"/tmp/maizeviz-bench-{os.getpid()}-gui")
    proc = subprocess.run([sys.executable, __file__, "--child", "gui", "--levels",
                           ",".join(levels), "--repeat", str(repeat)], stdout=subprocess.PIPE,
                          text=True, env=env, timeout=TIMEOUT_S * 3 * repeat)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        raise SystemExit(f"the GUI run failed (exit {proc.returncode})")
    return json.loads(lines[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--levels", default=STOPS)
    ap.add_argument("--repeat", type=int, default=1, help="visit the levels this many times")
    ap.add_argument("--presses", type=int, default=200,
                    help="stylus presses of the digitizer's load run (default 200)")
    ap.add_argument("--only", choices=("digitizer",), help="run only this part")
    ap.add_argument("--child", choices=("startup", "gui", "digitizer"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    levels = [lv for lv in args.levels.split(",") if lv]
    if args.child == "startup":
        return startup_child()
    if args.child == "gui":
        return gui_child(levels, args.repeat)
    if args.child == "digitizer":
        return digitizer_child(args.presses)
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise SystemExit("needs a display: xvfb-run -a -s \"-screen 0 1366x768x24\" python "
                         "benchmarks/bench_gui.py")
    out = {"anchor_s": min(matmul_anchor() for _ in range(3))}
    if args.only != "digitizer":
        out.update(gil_part())
        out.update(startup_part())
        out.update(gui_part(levels, args.repeat))
    out.update(digitizer_part(args.presses))
    out["anchor_end_s"] = min(matmul_anchor() for _ in range(3))     # the load may have changed
    out["targets"] = {"gil_max_block_ms": 100, "idle_renders_per_s": 0, "renders_per_canopy": 1,
                      "event_loop_max_gap_ms_at_36_and_below": 200,
                      "event_loop_max_gap_ms_at_K4": 200, "first_window_s": 3,
                      "layout_edit_event_loop_max_gap_ms_900_plants": 200,
                      "pick_ms": 50, "mesh_file_event_loop_max_gap_ms": 200,
                      "stop_event_loop_max_gap_ms": 50, "stop_event_loop_max_gap_ms_demo": 50,
                      "digitizer_presses_lost": 0, "rotation_frame_ms_moving_over_200": 0}
    if args.json:
        print(json.dumps(out, indent=1))
        return None
    for k, v in out.items():
        print(f"{k}: {v}")
    return None


if __name__ == "__main__":
    main()
