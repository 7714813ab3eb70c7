"""A canopy above the view's triangle budget: the plants of the sampled tile nearest its centre
(within FINE_BUDGET) are drawn at the level asked, the others at the display level, and light given per triangle of the canopy
colours the drawn triangles exactly where they are the canopy's and per leaf elsewhere."""

from __future__ import annotations

import maizeviz_app.viewport as viewport_mod
import numpy as np
from test_light_modes import compute, shown, small_light


def test_a_large_canopy_is_drawn_within_the_budget_and_coloured_by_its_light(
        window, qtbot, small_points, monkeypatch):
    monkeypatch.setattr(viewport_mod, "VIEW_BUDGET", 500)
    w = shown(qtbot, window(small_points, tile=3))
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        w.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("standard"))     # finer than 36 a leaf
    mesh = w.viewport.canopy_mesh
    c = w.model.canopy
    assert "source" in mesh.field_data and c.n_triangles > 500
    assert "draws the 2 plants of the sampled tile at this level" in w.messages.toPlainText()
    source = np.asarray(mesh.field_data["source"])
    x0, y0, x1, y1 = c.layout.centre_bounds
    sampled = [i for i, p in enumerate(c.layout.placements) if x0 <= p.x <= x1 and y0 <= p.y <= y1]
    own = source[source >= 0]
    np.testing.assert_array_equal(np.sort(own),
                                  np.flatnonzero(np.isin(c.face_instance, sampled)))
    n_leaf = int(mesh.field_data["leaf_triangles"][0])
    assert n_leaf < c.n_triangles                       # fewer triangles drawn
    # only the vertices of the triangles drawn, the sampled plants' where the canopy has them
    faces = mesh.regular_faces
    np.testing.assert_array_equal(np.unique(faces), np.arange(mesh.n_points))
    mine = np.flatnonzero(source >= 0)
    np.testing.assert_allclose(np.asarray(mesh.points)[faces[mine]],
                               c.vertices[c.faces[source[mine]]], rtol=1e-6)
    small_light(w.light_panel, "sun")
    w.model.colour.painting = "triangles"               # each triangle's class, asked for
    compute(qtbot, w)
    classes = w.model.runs.last.classes
    light = np.asarray(mesh.cell_data["light"])[:n_leaf]
    np.testing.assert_array_equal(light[source >= 0], classes[source[source >= 0]])
    # elsewhere: the most common class of the leaf (instance, rank) among the canopy's
    inst = np.asarray(mesh.cell_data["instance"])[:n_leaf] - 1
    leaf = np.asarray(mesh.cell_data["leaf"])[:n_leaf]
    for k in np.flatnonzero(source < 0)[::37]:
        mine = (c.face_instance == inst[k]) & (c.face_leaf == leaf[k])
        counts = np.bincount(classes[mine].astype(int) + 1, minlength=4)
        assert light[k] == counts.argmax() - 1
    assert w.viewport.colouring == "light"
    qtbot.wait(100)
    # a sky's light per leaf: the same value on every drawn triangle of a leaf
    small_light(w.light_panel, "sky")
    compute(qtbot, w)
    values = np.asarray(mesh.cell_data["light_value"])[:n_leaf]
    leaf_value = w.model.runs.last.extra.leaf_value
    np.testing.assert_array_equal(values[source >= 0], leaf_value[source[source >= 0]])
    k = int(np.flatnonzero(source < 0)[0])
    mine = (c.face_instance == inst[k]) & (c.face_leaf == leaf[k])
    np.testing.assert_allclose(values[k], leaf_value[mine][0], equal_nan=True)



def test_a_dense_tile_draws_the_plants_nearest_its_centre_within_the_fine_budget(small_points):
    """Above the budget the view draws at the level asked only the sample tile's plants
    nearest its centre whose triangles fit FINE_BUDGET (at least the central one), the
    others coarse: a K = 4 frame costs what its triangles cost, not the whole tile's."""
    from maizeviz_app.building import DISPLAY_LEVEL
    from maizeviz_app.viewport import display_polydata, sample_plants

    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import parse_level

    leaves = read_leaves(small_points).leaves
    layout = layout_for(leaves, (3, 3))
    canopy = build_canopy(leaves, layout, parse_level("standard"))
    coarse = build_canopy(leaves, layout, parse_level(DISPLAY_LEVEL))
    tile = sample_plants(canopy, None)
    per_plant = np.bincount(canopy.face_instance, minlength=len(tile))
    assert tile.sum() == 2
    x0, y0, x1, y1 = canopy.layout.centre_bounds
    xy = np.array([(p.x, p.y) for p in canopy.layout.placements])
    near = np.flatnonzero(tile)[np.argmin(np.hypot(*(xy[tile] - [(x0 + x1) / 2,
                                                                   (y0 + y1) / 2]).T))]
    for budget, drawn in ((10 ** 9, set(np.flatnonzero(tile))),
                          (int(per_plant[tile].max()) + int(per_plant[tile].min()) - 1, {near}),
                          (1, {near})):
        assert set(np.flatnonzero(sample_plants(canopy, budget))) == drawn, budget
    viewport_mod.FINE_BUDGET, old = 1, viewport_mod.FINE_BUDGET
    try:
        poly = display_polydata(canopy, coarse)
    finally:
        viewport_mod.FINE_BUDGET = old
    source = np.asarray(poly.field_data["source"])
    np.testing.assert_array_equal(np.sort(source[source >= 0]),
                                  np.flatnonzero(canopy.face_instance == near))
    assert "draws 1 of the 2 plants of the sampled tile" in poly.field_data["view_note"][0]
