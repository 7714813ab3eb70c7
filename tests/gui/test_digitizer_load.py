"""The promise of a digitizing tool, under load (issue 35, item 1): every press the FASTRAK
accepted is on disk, in order, at its plant/leaf/row/col, whatever the window is doing.

A scripted technician (:mod:`maizeviz.digitizer.technician`) in another process presses a
simulated FASTRAK (a real pty) 200 times, 0.35-0.5 s apart, and asks for N or P before each
new leaf or plant, waiting (as a technician watches the band) until the window shows it; the
window's digitizer records through its recorder process while one CPU burner per core keeps
every core busy and the window grows the plant in its 3D view. Before the recorder had a
process of its own, 54 of 60 presses reached the file under two burners, with no word.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from maizeviz.digitizer.technician import Technician, plan
from maizeviz.io.points import read_points

TIMEOUT = 120_000
PRESSES = 200


@pytest.fixture
def burners():
    """One busy Python process per core, killed in teardown."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
             for _ in range(os.cpu_count() or 1)]
    yield procs
    for p in procs:
        p.kill()
        p.wait()


def test_every_press_is_on_disk_in_order_under_cpu_load(window, two_plants, qtbot, tmp_path,
                                                       burners):
    w = window(two_plants, tile=1)
    panel = w.digitizer
    panel.confirm_close = False
    w.workspaces.show("digitize")
    tech = Technician(PRESSES, (0.35, 0.5), seed=1)
    try:
        out = tmp_path / "load.csv"
        panel.ports.set_port(tech.wait_port())
        panel.out_edit.setText(str(out))
        panel.cols.setValue(5)
        with qtbot.waitSignal(panel.started, timeout=TIMEOUT):
            panel.connect_button.click()
        d = panel.digitizing
        tech.follow(panel.control, lambda: (d.pos.plant, d.pos.leaf),
                    lambda: d.count.points, lambda s: qtbot.wait(int(s * 1000)),
                    timeout=PRESSES * 2.0)
        assert tech.done and len(tech.pressed) == PRESSES    # the unit accepted every press
        with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
            panel.stop_button.click()
        assert stopped.args == ["stopped"]
    finally:
        tech.close()
    pts = read_points(out)                                # the file, as any reader sees it
    assert len(pts) == PRESSES, f"{PRESSES - len(pts)} presses lost"
    np.testing.assert_array_equal(pts.ids, tech.ids)      # in order, at their place
    np.testing.assert_allclose(pts.xyz, tech.xyz, atol=0.0015)
    # the window showed what is on disk: every press confirmed, no trouble said
    assert panel.press_beeps == PRESSES and panel.press_count.text() == f"{PRESSES} points"
    assert panel.digitizing.count.refused == 0 and panel.digitizing.warnings == []
    assert panel.beeps == 0


def test_the_demo_loses_no_press_under_cpu_load(window, two_plants, qtbot, tmp_path, burners):
    """The Demo's simulated FASTRAK lives in the window's process (its replay presses from a
    thread there): 75 presses over 3 leaves, all on disk at their place."""
    from maizeviz.io.points import write_points
    from maizeviz.leaf.grid import LeafGrid

    ids, xyz = plan(75)
    src = tmp_path / "demo_plan.csv"           # (ids, xyz: the technician's plan)
    write_points(src, [LeafGrid(int(ids[k, 0]), int(ids[k, 1]), xyz[k:k + 25].reshape(5, 5, 3)) for k in range(0, 75, 25)])
    assert len(read_points(src)) == 75
    w = window(two_plants, tile=1)
    panel = w.digitizer
    panel.confirm_close = False
    panel.demo_file, panel.demo_pace = src, 0.35
    panel.cols.setValue(5)
    out = tmp_path / "demo.csv"
    panel.out_edit.setText(str(out))
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT + 75 * 2_000) as stopped:
        panel.demo_button.click()
    assert stopped.args == ["finished"]
    pts = read_points(out)
    assert len(pts) == 75, f"{75 - len(pts)} presses lost"
    np.testing.assert_array_equal(pts.ids, ids)
    # the Demo's unit adds its 0.08 cm RMS noise per axis: 6 sigma, which 225 draws exceed
    # with a probability of 4e-7
    np.testing.assert_allclose(pts.xyz, xyz, atol=6 * 0.08)
    assert panel.press_beeps == 75
