"""The light panel's leaves-only switch (issue 37): whether the stalks take light is a light
setting of the study (``settings.light.stalks``), traced by the window's light process as
``maizeviz light`` traces it (``--leaves-only`` off), an undoable named step, kept in
projects (an old project's stalks took light), and each result says whether its stalks
were traced (the energy balance's stalks row only then)."""

from __future__ import annotations

import json
import zipfile

import pytest
from test_light_modes import TIMEOUT, compute, shown, small_light

SUN = (40.0, 150.0)


def _cli(capsys, points, *extra):
    from maizeviz.cli import main

    code = main(["light", str(points), "--tile", "1x1", "--triangles", "36", "--periodic",
                 "--sun-zenith", f"{SUN[0]:g}", "--sun-azimuth", f"{SUN[1]:g}",
                 "--density", "0.5", "--heights", "0,100,200", "--json", *extra])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)


def _sun(w, p):
    small_light(p, "sun")
    p.periodic.setChecked(True)
    w.model.settings.sun.zenith_deg, w.model.settings.sun.azimuth_deg = SUN


def test_leaves_only_in_the_window_is_the_command_lines(window, qtbot, small_points, capsys):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    _sun(w, p)
    assert p.stalks.isChecked() and w.model.settings.light.stalks      # the CLI's default
    compute(qtbot, w)
    with_stalks = w.model.runs.last
    assert with_stalks.stalks and "stalks" in p.info.text()
    p.stalks.click()                                        # off: the leaves alone
    assert w.model.settings.light.stalks is False
    assert w.menu_actions["undo"].text().replace("&", "") == "Undo stalks take light off"
    compute(qtbot, w)
    run = w.model.runs.last
    assert not run.stalks and "leaves only" in p.info.text()
    assert len(w.model.runs.runs) == 1                      # a new comparison
    cli = _cli(capsys, small_points, "--leaves-only")
    assert cli["stalks"]["traced"] is False and cli["triangles"] == w.model.canopy.n_triangles
    # the same rays through the same leaves: the same numbers (to float rounding)
    assert run.result.transmission.tolist() == pytest.approx(cli["transmission"], abs=1e-12)
    assert run.result.sunlit_intercepted_fraction == pytest.approx(
        cli["sunlit_intercepted_fraction"], abs=1e-12)
    shown_numbers = [p.table.item(r, 1).text() for r in range(3)]
    assert shown_numbers == [f"{t:.3f}" for t in cli["transmission"]]
    # and with the stalks, the command line's default, as the first run
    on = _cli(capsys, small_points)
    assert on["stalks"]["traced"] is True
    assert with_stalks.result.transmission.tolist() == pytest.approx(on["transmission"],
                                                                    abs=1e-12)
    assert with_stalks.result.stalk_intercepted_fraction == pytest.approx(
        on["stalks"]["sun_intercepted_fraction"], abs=1e-12)
    # undo: the stalks take light again, the box follows
    w.model.history.undo()
    assert w.model.settings.light.stalks is True and p.stalks.isChecked()
    w.model.history.redo()
    assert w.model.settings.light.stalks is False and not p.stalks.isChecked()


def test_the_stalks_row_of_the_balance_only_where_they_were_traced(window, qtbot,
                                                                   small_points):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    _sun(w, p)
    p.optics_box.setChecked(True)
    compute(qtbot, w)
    rows = {p.table.item(r, 0).text(): p.table.item(r, 1).text()
            for r in range(p.table.rowCount())}
    b = w.model.runs.last.balance
    assert b.absorbed_stalks > 0
    assert float(rows["absorbed by stalks W/m²"]) == round(b.absorbed_stalks, 1)
    w.model.settings.light.stalks = False
    compute(qtbot, w)
    rows = [p.table.item(r, 0).text() for r in range(p.table.rowCount())]
    assert "absorbed by leaves W/m²" in rows and "absorbed by stalks W/m²" not in rows
    assert w.model.runs.last.balance.absorbed_stalks == 0.0


def test_leaves_only_is_kept_in_a_project_and_an_old_one_traced_stalks(window, qtbot,
                                                                       small_points, tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    _sun(w, p)
    p.stalks.setChecked(False)
    compute(qtbot, w)
    path = tmp_path / "leaves.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    with zipfile.ZipFile(path) as zf:
        doc = json.loads(zf.read("project.json"))
    assert doc["settings"]["light"]["stalks"] is False
    w2 = window(path)
    qtbot.waitUntil(lambda: w2.model.runs.last is not None, timeout=TIMEOUT)
    assert w2.model.settings.light.stalks is False and not w2.light_panel.stalks.isChecked()
    assert w2.model.runs.last.stalks is False
    # a project saved before the switch: its settings lack it, its stalks took light
    old = tmp_path / "old.maizeviz"
    del doc["settings"]["light"]["stalks"]
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(old, "w") as dst:
        for item in src.infolist():
            dst.writestr(item, json.dumps(doc) if item.filename == "project.json"
                         else src.read(item.filename))
    w2.model.open_project(old)
    qtbot.waitUntil(lambda: w2.model.settings.light.stalks is True, timeout=TIMEOUT)
    assert w2.light_panel.stalks.isChecked()
