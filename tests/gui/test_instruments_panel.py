"""The instruments panel as a widget on the small canopy: places clicked on the top view,
each instrument read on the panel's thread, its table, figure and JSON (the command line's
record); and the panel in the main window's docks."""

from __future__ import annotations

import json

import pytest
from PySide6.QtCore import QPoint, Qt

from maizeviz.cli import main


@pytest.fixture
def panel(qtbot, small_canopy):
    from maizeviz_app.panels.instruments import InstrumentsPanel

    p = InstrumentsPanel(canopy=lambda: small_canopy)
    qtbot.addWidget(p)
    p.resize(460, 900)
    p.show()
    qtbot.waitExposed(p)
    yield p
    p.shutdown()


@pytest.mark.parametrize("kind, rows", [("ceptometer", 2), ("analyser", 6), ("hemiphoto", 5)])
def test_each_instrument_reads_into_the_table_and_saves_its_json(qtbot, panel, tmp_path,
                                                                 kind, rows):
    panel.kind.setCurrentIndex(panel.kind.findData(kind))
    panel.size_spin.setValue(48)
    qtbot.mouseClick(panel.top.viewport(), Qt.MouseButton.LeftButton,
                     pos=panel.top.viewport().rect().center())
    assert len(panel.places) == 1
    with qtbot.waitSignal(panel.read_done, timeout=120_000) as got:
        qtbot.mouseClick(panel.read_button, Qt.MouseButton.LeftButton)
    rec = got.args[0]
    assert rec["instrument"] == kind
    assert panel.table.rowCount() == rows
    assert panel.figure.image() is not None and panel.save_button.isEnabled()
    out = panel.save_json(tmp_path / "readings.json")
    assert json.loads(out.read_text())["instrument"] == kind


def test_the_panel_reads_what_the_command_line_reads(qtbot, panel, small_points, capsys):
    """The same place, settings and canopy: the panel's record is the --json one."""
    panel.kind.setCurrentIndex(panel.kind.findData("ceptometer"))
    panel.add_place(20.0, 10.0)
    with qtbot.waitSignal(panel.read_done, timeout=120_000) as got:
        panel.read()
    assert main(["instrument", "ceptometer", str(small_points), "--triangles", "36", "--at",
                 "20,10", "--sun-zenith", "30", "--sun-azimuth", "180", "--periodic",
                 "--json"]) == 0
    want = json.loads(capsys.readouterr().out)
    assert got.args[0]["tau"] == pytest.approx(want["tau"], abs=1e-12)
    assert got.args[0]["probes"][0]["par_umol_m2_s"] == want["probes"][0]["par_umol_m2_s"]


def test_without_a_canopy_the_panel_says_so(qtbot):
    from maizeviz_app.panels.instruments import InstrumentsPanel

    p = InstrumentsPanel()
    qtbot.addWidget(p)
    with qtbot.waitSignal(p.failed) as got:
        p.read()
    assert "canopy" in got.args[0]
    p.shutdown()


def test_clicks_add_places_and_clear_removes_them(qtbot, panel):
    vp = panel.top.viewport()
    for dx in (-20, 0, 20):
        qtbot.mouseClick(vp, Qt.MouseButton.LeftButton, pos=vp.rect().center() + QPoint(dx, 0))
    assert len(panel.places) == 3 and panel.places_label.text() == "3 places"
    xs = [x for x, _ in panel.places]
    assert xs == sorted(xs)                               # left to right on screen: x grows
    qtbot.mouseClick(panel.clear_button, Qt.MouseButton.LeftButton)
    assert panel.places == []
