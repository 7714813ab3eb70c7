"""Picking and linked selection: a click on a leaf selects the triangle a ray through the pixel
meets first (checked against a brute-force ray cast over every drawn triangle), highlights its
leaf and tells plant, leaf, level, area and light; a row of the plants table selects and frames
its plant; a click beside the canopy clears; a drag turns the camera and picks nothing; the
heatmap tells the value under the mouse."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtTest import QTest
from test_light_modes import TIMEOUT, compute, shown, small_light

from maizeviz.mesh.tessellate import triangle_areas_normals


def first_hit(points: np.ndarray, faces: np.ndarray, origin: np.ndarray, direction: np.ndarray):
    """Index of the triangle the ray meets first (Moller-Trumbore over all of them), or -1."""
    a, b, c = (points[faces[:, k]].astype(np.float64) for k in range(3))
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    t_vec = origin - a
    u = np.einsum("ij,ij->i", t_vec, p) * inv
    q = np.cross(t_vec, e1)
    v = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if not hit.any():
        return -1
    return int(np.flatnonzero(hit)[np.argmin(t[hit])])


def click(view, x: float, y: float) -> None:
    QTest.mouseClick(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier,
                     QPoint(round(x), round(y)))


def leaf_pixels(view, n: int, seed: int = 0):
    """Widget points over ``n`` drawn leaf triangles (their centroids), inside the view."""
    mesh = view.canopy_mesh
    nf = int(mesh.field_data["leaf_triangles"][0])
    faces = mesh.regular_faces[:nf]
    rng = np.random.default_rng(seed)
    out = []
    for cell in rng.permutation(nf):
        x, y = view.display_point(np.asarray(mesh.points)[faces[cell]].mean(axis=0))
        if 5 < x < view.width() - 5 and 5 < y < view.height() - 5:
            out.append((x, y))
        if len(out) == n:
            break
    return out


def test_a_click_picks_the_first_triangle_under_the_mouse_and_tells_its_leaf(
        window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    view, model = w.viewport, w.model
    w.camera("top")
    qtbot.wait(200)
    mesh = view.canopy_mesh
    points, faces = np.asarray(mesh.points), mesh.regular_faces
    checked = 0
    for x, y in leaf_pixels(view, 12):
        with qtbot.waitSignal(view.picked, timeout=5000) as sig:
            click(view, x, y)
        p = sig.args[0]
        # the oracle: a brute-force ray through the same pixel, over every drawn triangle
        ratio = view.devicePixelRatioF()
        from maizeviz_app.picking import ray_through

        p0, p1 = ray_through(view.renderer, round(x) * ratio,
                             (view.height() - round(y) - 1) * ratio)
        want = first_hit(points, faces, p0, (p1 - p0) / np.linalg.norm(p1 - p0))
        assert p is not None and p.cell == want
        assert (model.selection.placement, model.selection.leaf) == (p.instance, p.leaf)
        if p.leaf > 0:
            c = w.model.canopy
            mine = (c.face_instance == p.instance) & (c.face_leaf == p.leaf)
            area, _ = triangle_areas_normals(c.vertices, c.faces[mine])
            text = view.info.text()
            assert f"plant {p.plant}, leaf {p.leaf}" in text
            assert f"leaf area {area.sum():,.1f} cm²" in text and "level 36 triangles" in text
            drawn = (np.asarray(mesh.cell_data["instance"]) == p.instance + 1) & \
                (np.asarray(mesh.cell_data["leaf"]) == p.leaf)
            assert view.actors["selection"].mapper.dataset.n_cells == drawn.sum()
            checked += 1
        assert view.last_pick_ms is not None
    assert checked >= 5
    # beside the canopy (the sky above the horizon in a side view): nothing selected
    w.camera("along")
    qtbot.wait(100)
    with qtbot.waitSignal(view.picked, timeout=5000) as sig:
        click(view, 8, 8)
    assert sig.args[0] is None and model.selection.empty
    assert not view.info.isVisible() and not view.actors["selection"].GetVisibility()
    # a drag turns the camera and picks nothing
    w.camera("top")
    x, y = leaf_pixels(view, 1)[0]
    model.selection.select(0, 1)
    seen = []
    view.picked.connect(seen.append)
    before = np.array(view.camera.position)
    QTest.mousePress(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier,
                     QPoint(round(x), round(y)))
    QTest.mouseMove(view, QPoint(round(x) + 40, round(y) + 25))
    QTest.mouseRelease(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier,
                       QPoint(round(x) + 40, round(y) + 25))
    assert not seen and (model.selection.placement, model.selection.leaf) == (0, 1)
    assert not np.allclose(np.array(view.camera.position), before)      # the camera turned


def test_plants_table_and_view_select_each_other_with_the_light_of_the_selection(
        window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=3))
    view, model, table = w.viewport, w.model, w.light_panel.plants
    small_light(w.light_panel, "sky")
    compute(qtbot, w)
    assert table.isVisible() and table.rowCount() >= 2
    focal = np.array(view.camera.focal_point)
    row = 1
    stand = int(table.item(row, 0).text())
    table.selectRow(row)
    assert (model.selection.placement, model.selection.leaf) == (stand - 1, -1)
    c = w.model.canopy
    mine = c.face_instance == stand - 1
    drawn = np.asarray(view.canopy_mesh.cell_data["instance"]) == stand
    assert view.actors["selection"].mapper.dataset.n_cells == drawn.sum()
    # framed: the camera looks at the plant
    lo, hi = c.vertices[c.faces[mine]].reshape(-1, 3).min(0), \
        c.vertices[c.faces[mine]].reshape(-1, 3).max(0)
    now = np.array(view.camera.focal_point)
    assert not np.allclose(now, focal) and np.all(now >= lo - 1) and np.all(now <= hi + 1)
    # the card: the plant's sky light, the area-weighted mean of its leaves' values
    area, _ = triangle_areas_normals(c.vertices, c.faces[mine])
    value = w.model.runs.last.extra.leaf_value[mine]
    ok = np.isfinite(value)
    mean = np.sum(value[ok] * area[ok]) / area[ok].sum()
    assert f"sky: {mean:.3f} of the open sky's diffuse light per leaf area" in view.info.text()
    # a click on a leaf of another plant selects that plant's row
    w.camera("top")
    qtbot.wait(100)
    rows = {int(table.item(r, 0).text()) for r in range(table.rowCount())}
    for x, y in leaf_pixels(view, 400, seed=3):
        p = view.pick_at(round(x), round(y))
        if p is not None and p.leaf > 0 and p.instance + 1 in rows - {stand}:
            break
    else:
        raise AssertionError("no leaf of another plant of the table in sight")
    click(view, x, y)
    assert model.selection.placement == p.instance
    selected = {i.row() for i in table.selectedIndexes()}
    assert [int(table.item(r, 0).text()) for r in selected] == [p.instance + 1]
    # another level keeps the selection, drawn on the new mesh
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("16"))
    qtbot.waitUntil(lambda: "level 16 triangles" in view.info.text(), timeout=5000)
    drawn = (np.asarray(view.canopy_mesh.cell_data["instance"]) == p.instance + 1) & \
        (np.asarray(view.canopy_mesh.cell_data["leaf"]) == p.leaf)
    assert view.actors["selection"].mapper.dataset.n_cells == drawn.sum()
    # new points clear it
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_points(small_points)
    assert model.selection.empty and not view.info.isVisible()


def test_hovering_the_heatmap_tells_the_bin_under_the_mouse(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    heat = w.plots.heatmap
    qtbot.waitUntil(lambda: heat.heatmap is not None, timeout=TIMEOUT)
    m = heat.heatmap
    image = heat.image()
    scale = min(heat.width() / image.width(), heat.height() / image.height())
    dx = (heat.width() - image.width() * scale) / 2
    dy = (heat.height() - image.height() * scale) / 2
    left, top, right, bottom = m.box
    i, j = len(m.x_edges) // 3, len(m.y_edges) // 2
    x = (m.x_edges[i] + m.x_edges[i + 1]) / 2
    y = (m.y_edges[j] + m.y_edges[j + 1]) / 2
    px = left + (x - m.x_edges[0]) / (m.x_edges[-1] - m.x_edges[0]) * (right - left)
    py = top + (m.y_edges[-1] - y) / (m.y_edges[-1] - m.y_edges[0]) * (bottom - top)
    pos = QPoint(round(dx + px * scale), round(dy + py * scale))
    QTest.mouseMove(heat, pos)
    qtbot.waitUntil(lambda: "cm" in w.plots.hover.text(), timeout=5000)
    found = m.value_at(*heat.image_point(QPointF(pos)))
    assert found is not None
    text = w.plots.hover.text()
    if found[3]:
        assert f"{found[2]:.3f}" in text and f"({found[3]:,} rays)" in text
    else:
        assert "no ray" in text


def test_selection_changes_once_and_describes_a_leaf_with_the_tables_numbers(small_canopy):
    from maizeviz_app.runs import Run
    from maizeviz_app.selection import Selection, describe

    from maizeviz.light.results.painting import sun_painting
    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light

    sel = Selection()
    seen = []
    sel.changed.connect(lambda *a: seen.append(a))
    sel.select(1, 4)
    sel.select(1, 4)                                   # no change, no signal
    sel.select(-5, 3)                                  # nothing selected: the leaf goes too
    assert seen == [(1, 4), (-1, -1)] and sel.empty
    c = small_canopy
    result = trace_light(c, LightRequest(Sun(25.0, 170.0), Sampling((0.0,), 1.0, None, True),
                                         classes=True))
    painting = sun_painting(c, result)
    run = Run("36 triangles", (1, "36 triangles"), result, painting.classes, painting=painting)
    for row in result.leaf_rows(c)[:6]:
        lines = describe(c, "36 triangles", [run], int(row["instance"]) - 1, int(row["leaf"]))
        assert lines[0].startswith(f"plant {row['plant']}, leaf {row['leaf']} (stand "
                                   f"{row['instance']}")
        assert f"leaf area {row['leaf_area_cm2']:,.1f} cm²" in lines[1]
        share = min(row["sunlit_area_cm2"] / row["leaf_area_cm2"], 1.0)
        assert f"sunlit share {share:.2f}" in lines[2]
    assert describe(c, "36 triangles", [run], len(c.layout.placements), 1) == []
    assert "stalk" in describe(c, "36 triangles", [run], 0, 0)[0]


def test_a_selected_plant_seen_through_the_others_or_alone(window, qtbot, small_points):
    """Issue 37's conventions: while a plant is selected, the others drawn as the study's
    view state says (View > Selection): shown, faded (the selection seen through them) or
    hidden (the selection alone); without a selection the canopy is drawn whole again."""
    from maizeviz_app.view_state import FADED_OPACITY

    w = shown(qtbot, window(small_points, tile=1))
    view, model = w.viewport, w.model
    canopy = view.actors["canopy"]
    model.selection.select(0, -1)
    assert view.actors["selection"].GetVisibility()
    assert canopy.GetVisibility() and canopy.GetProperty().GetOpacity() == 1.0
    w.menu_actions["others_faded"].trigger()
    assert model.view.others == "faded"
    assert canopy.GetProperty().GetOpacity() == FADED_OPACITY and canopy.GetVisibility()
    model.view.others = "hidden"                     # a script, as the menu does
    assert not canopy.GetVisibility() and w.menu_actions["others_hidden"].isChecked()
    assert view.actors["selection"].GetVisibility()
    model.selection.select(-1, -1)                   # nothing selected: the canopy whole
    assert canopy.GetVisibility() and canopy.GetProperty().GetOpacity() == 1.0
    model.selection.select(1, -1)                    # the mode holds for the next selection
    assert not canopy.GetVisibility()
    model.view.others = "shown"
    assert canopy.GetVisibility() and canopy.GetProperty().GetOpacity() == 1.0


def test_view_measure_takes_the_clicks_and_says_the_distance(window, qtbot, small_points):
    """View > Measure distance: the clicks on the canopy go to the probe (not the selection),
    its points and line are drawn, the distance is said; the same entry again stops it."""
    from maizeviz_app.picking import Pick

    w = shown(qtbot, window(small_points, tile=1))
    view, model = w.viewport, w.model
    said: list[str] = []
    w.model.said.connect(lambda text, *_: said.append(text))
    w.statusBar().messageChanged.connect(said.append)
    w.menu_actions["measure_distance"].trigger()
    assert model.probe.kind == "distance" and w.menu_actions["measure_distance"].isChecked()
    view.picked.emit(Pick(0, 0, 1, 1, (10.0, 0.0, 50.0)))
    view.picked.emit(Pick(1, 0, 1, 2, (10.0, 30.0, 90.0)))
    assert model.selection.empty                        # the clicks measured, not selected
    assert "probe_line" in view.actors and "probe_points" in view.actors
    assert any(t.startswith("distance 50.0 cm") for t in said), said
    w.menu_actions["measure_distance"].trigger()
    assert not model.probe.on and "probe_line" not in view.actors
    view.picked.emit(Pick(1, 0, 1, 2, (10.0, 30.0, 90.0)))
    assert not model.selection.empty                    # selecting again
