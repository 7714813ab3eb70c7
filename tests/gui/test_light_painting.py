"""The view paints a sun's light honestly: at K = 4 (triangles smaller than the ray spacing)
each leaf with its sunlit share, so no leaf in the sun shows as unlit, and it says so; at 36
triangles a leaf, each triangle with its class; either on request."""

from __future__ import annotations

import numpy as np
from test_light_modes import TIMEOUT, compute, shown, small_light

from maizeviz.mesh.levels import COMPLEXITY_STOPS


def test_k4_sun_paints_each_leaf_with_its_sunlit_share(window, qtbot, small_points, tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("K4"))
    small_light(w.light_panel, "sun", density=2.0)
    compute(qtbot, w)
    run, view, c = w.model.runs.last, w.viewport, w.model.canopy
    assert run.painting.per == "leaves" and run.painting.rays_per_triangle < 1
    assert view.colouring == "light" and view.light_variant == "values"
    n = c.n_triangles
    painted = np.asarray(view.canopy_mesh.cell_data["light_value"])[:n]
    # every triangle of a leaf the sun reaches is painted as lit; those the table says took
    # no sun, as 0
    rows = run.result.leaf_rows(c)
    for r in rows:
        mine = (c.face_instance == int(r["instance"]) - 1) & (c.face_leaf == int(r["leaf"]))
        want = min(r["sunlit_area_cm2"] / r["leaf_area_cm2"], 1.0)
        np.testing.assert_allclose(painted[mine], want, rtol=1e-5)
    lit = np.zeros(n, bool)
    for r in rows:
        if r["sunlit_area_cm2"] > 0:
            lit |= (c.face_instance == int(r["instance"]) - 1) & (c.face_leaf == int(r["leaf"]))
    assert lit.mean() > 0.5 and np.all(painted[lit] > 0)
    # the classes would have shown most of those triangles unlit
    assert (run.classes[lit] == 0).mean() > 0.5
    # said: the colour bar, the Colour panel and Messages
    assert "sunlit share of each leaf" in view.key.text()
    assert "too few to class each triangle" in w.colour_panel.painting_note.text()
    assert "too few to class each triangle" in w.messages.toPlainText()
    # asked for per triangle: the classes, with the warning
    w.colour_panel.painting.setCurrentIndex(w.colour_panel.painting.findData("triangles"))
    assert view.light_variant == "classes"
    light = np.asarray(view.canopy_mesh.cell_data["light"])[:n]
    np.testing.assert_array_equal(light, run.classes)
    assert "many sunlit triangles get no ray" in w.colour_panel.painting_note.text()
    w.model.colour.painting = "auto"
    assert view.light_variant == "values"
    # the exported canopy carries the leaves' share beside the classes
    import pyvista as pv

    out = tmp_path / "k4.vtu"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.export("canopy", out)
    mesh = pv.read(out)
    np.testing.assert_array_equal(np.asarray(mesh.cell_data["sun_class"])[:n], run.classes)
    np.testing.assert_allclose(np.asarray(mesh.cell_data["sunlit_share"])[:n],
                               run.painting.share, equal_nan=True)


def test_36_triangles_a_leaf_are_painted_one_by_one(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun", density=2.0)
    compute(qtbot, w)
    assert w.model.runs.last.painting.per == "triangles"
    assert w.viewport.light_variant == "classes"
    np.testing.assert_array_equal(
        np.asarray(w.viewport.canopy_mesh.cell_data["light"])[:w.model.canopy.n_triangles],
        w.model.runs.last.classes)
    assert "light class" in w.colour_panel.painting_note.text()
