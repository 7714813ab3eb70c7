"""The window reads a project's per-triangle light through the core's exact check (the one
``read_study`` applies): an array one value short, one long or of the wrong type is refused in
one line naming the array, and the window keeps its canopy and its light."""

from dataclasses import replace

import numpy as np
import pytest

TIMEOUT = 120_000


@pytest.fixture
def lit_window(window, qtbot, small_points):
    """A window on two plants with a sun traced."""
    w = window(small_points, tile=1)
    if w.model.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    w.light_panel.density.setValue(0.5)
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        w.model.compute_light()
    return w


def _damaged(path, out, name, damage):
    """The project at ``path`` with its sun's array ``name`` damaged, written to ``out``."""
    from maizeviz.io.archive import load_project, save_project

    project = load_project(path)
    rec = project.results[0]
    a = np.asarray(rec.arrays[name])
    changed = {"one short": a[:-1], "one long": np.append(a, a[-1:]),
               "wrong dtype": a.astype(np.float64) + 0.5}[damage]
    arrays = {**rec.arrays, name: changed}
    if name == "first_hits" and damage != "wrong dtype":          # both hit arrays alike
        arrays["second_hits"] = np.resize(np.asarray(rec.arrays["second_hits"]), len(changed))
    save_project(out, replace(project, results=(replace(rec, arrays=arrays),
                                                *project.results[1:])))
    return out


@pytest.mark.parametrize("damage", ["one short", "one long", "wrong dtype"])
def test_a_projects_damaged_light_array_is_refused_and_the_window_keeps_its_own(
        lit_window, qtbot, tmp_path, damage):
    w = lit_window
    saved = tmp_path / "ok.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(saved)
    bad = _damaged(saved, tmp_path / "bad.maizeviz", "first_hits", damage)
    canopy, label = w.model.canopy, w.canopy_panel.file_label.text()
    runs = list(w.model.runs.in_order())
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
        w.open_project(bad)
    msg = err.args[0]
    assert "'first_hits'" in msg and "\n" not in msg and "ProjectError" not in msg, msg
    assert "bad.maizeviz" in msg, msg
    assert w.model.canopy is canopy and w.canopy_panel.file_label.text() == label
    assert list(w.model.runs.in_order()) == runs and len(runs) == 1
