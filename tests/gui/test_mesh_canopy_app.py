"""A canopy from elsewhere in the app: File > Open canopy mesh reads a PLY with plant and
leaf ids, light runs on it as on digitized plants; the slider and layout do not apply, and it
is not saved into a project."""

from __future__ import annotations

import numpy as np
from test_light_modes import TIMEOUT, compute, shown, small_light


def test_a_mesh_canopy_opens_and_is_traced(window, qtbot,
                                                                      small_points, tmp_path):
    from maizeviz.canopy.export import export_canopy

    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    before = np.array(w.model.runs.last.transmission)
    triangles = w.model.canopy.n_triangles
    ply = tmp_path / "exported.ply"
    export_canopy(str(ply), w.model.canopy)

    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_mesh(ply, "cm", "z")
    assert w.model.mesh_path == str(ply) and w.model.loaded is None and not w.model.runs.runs
    assert w.model.canopy.n_triangles == triangles and w.model.built.label == "mesh"
    assert not w.canopy_panel.slider.isEnabled() and "mesh file" in w.canopy_panel.level_label.text()
    assert not w.layout_panel.isEnabled() and w.windowTitle().startswith("maizeviz — exported")
    # the same sun: a transmission profile on the mesh canopy (its field: the mesh's extent)
    w.light_panel.heights.setText("0, 100, 200")
    w.light_panel.set_mode("sun")
    small_light(w.light_panel, "sun")
    w.light_panel.periodic.setChecked(False)
    compute(qtbot, w)
    after = np.array(w.model.runs.last.transmission)
    assert after.shape == before.shape and np.all((after >= 0) & (after <= 1))
    # not a project
    w.model.save_project(tmp_path / "no.maizeviz")
    assert "not saved in a project" in w.messages.toPlainText()
    assert not (tmp_path / "no.maizeviz").exists()
    # points again: slider and layout come back
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_points(small_points)
    assert w.canopy_panel.slider.isEnabled() and w.layout_panel.isEnabled() and w.model.mesh_path is None


def test_a_mesh_without_ids_is_one_line(window, qtbot, tmp_path):
    bad = tmp_path / "noids.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 1\n"
                   "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                   "3 0 1 2\n")
    w = shown(qtbot, window())
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as sig:
        w.open_mesh(bad)
    assert "noids.ply" in sig.args[0] and "\n" not in sig.args[0]
    assert "internal" not in sig.args[0] and w.model.canopy is not None    # the canopy shown stays


def test_a_mesh_canopy_takes_the_field_given(window, qtbot, small_points, tmp_path):
    """The field (ground plot) of a mesh canopy: the one typed, else the mesh's extent; a bad
    one is one line naming the field, and the canopy shown stays."""
    from maizeviz.canopy.export import export_canopy

    w = shown(qtbot, window(small_points, tile=1))
    ply = tmp_path / "exported.ply"
    export_canopy(str(ply), w.model.canopy)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_mesh(ply, "cm", "z")
    extent = tuple(w.model.canopy.layout.bounds)
    wider = (extent[0] - 30.0, extent[1] - 20.0, extent[2] + 30.0, extent[3] + 20.0)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_mesh(ply, "cm", "z", field=", ".join(f"{v:.6f}" for v in wider))
    assert np.allclose(w.model.canopy.layout.bounds, wider, atol=1e-6)
    assert "the field is given" in w.messages.toPlainText()
    for bad, says in (("0, 0, 100", "4 numbers"), ("0, 0, ten, 100", "4 numbers"),
                      ("100, 0, 0, 100", "x1 > x0"), ("-0,-0,1e-300,1e-300", "1 cm across"),
                      ("1000, 1000, 1100, 1100", "none of the"),
                      ("-1e5, -1e5, 1e5, 1e5", "2000 x 2000 m plot")):    # refused, not measured
        with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as sig:
            w.open_mesh(ply, "cm", "z", field=bad)
        assert says in sig.args[0] and "\n" not in sig.args[0]
        assert np.allclose(w.model.canopy.layout.bounds, wider, atol=1e-6)    # the canopy stays


def test_a_large_mesh_file_is_drawn_within_the_budget(window, qtbot, small_points, tmp_path,
                                                      monkeypatch):
    """A mesh file over the view's budget: the plants nearest the centre drawn with the
    file's triangles, the others simplified per leaf, each drawn triangle keeping its leaf;
    a sun's light per leaf paints them all."""
    import maizeviz_app.mesh_file_view as mesh_file_view
    import maizeviz_app.viewport as viewport_mod

    from maizeviz.canopy.export import export_canopy
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    w = shown(qtbot, window(small_points, tile=3))
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.canopy_panel.slider.setValue(COMPLEXITY_STOPS.index("standard"))
    ply = tmp_path / "field.ply"
    export_canopy(str(ply), w.model.canopy)
    monkeypatch.setattr(viewport_mod, "VIEW_BUDGET", 20_000)
    monkeypatch.setattr(mesh_file_view, "DRAWN", 12_000)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_mesh(ply, "cm", "z")
    c, mesh = w.model.canopy, w.viewport.canopy_mesh
    n_leaf = int(mesh.field_data["leaf_triangles"][0])
    assert c.n_triangles > 20_000 and n_leaf + len(c.stalk_faces) <= 1.1 * 12_000
    assert "simplified" in w.messages.toPlainText()
    source = np.asarray(mesh.field_data["source"])
    inst = np.asarray(mesh.cell_data["instance"])[:n_leaf] - 1
    leaf = np.asarray(mesh.cell_data["leaf"])[:n_leaf]
    fine = np.unique(inst[source >= 0])
    assert 0 < len(fine) < len(c.layout.placements)
    # the fine plants are the file's own triangles, all of them
    np.testing.assert_array_equal(np.sort(source[source >= 0]),
                                  np.flatnonzero(np.isin(c.face_instance, fine)))
    # every leaf of the other plants is drawn, simplified, with its own ids
    keys = set(zip(c.face_instance.tolist(), c.face_leaf.tolist()))
    drawn = set(zip(inst.tolist(), leaf.tolist()))
    assert drawn == keys
    # a sun per leaf: each drawn triangle takes its leaf's share
    small_light(w.light_panel, "sun", density=0.5)
    w.model.colour.painting = "leaves"
    compute(qtbot, w)
    share = w.model.runs.last.painting.share
    values = np.asarray(mesh.cell_data["light_value"])[:n_leaf]
    for k in np.flatnonzero(source < 0)[::53]:
        mine = (c.face_instance == inst[k]) & (c.face_leaf == leaf[k])
        np.testing.assert_allclose(values[k], share[mine][0], equal_nan=True)


def test_an_exported_canopy_opens_with_its_plot_and_period(window, qtbot, small_points,
                                                           tmp_path):
    """File > Open canopy mesh with the field left empty: a canopy the app exported comes
    back on its own plot, with its tiling's period, and a periodic sun gives the same
    transmission as the canopy it came from (issue 27)."""
    from maizeviz.canopy.export import export_canopy

    w = shown(qtbot, window(small_points, tile=3))
    layout = w.model.canopy.layout
    w.light_panel.set_mode("sun")
    small_light(w.light_panel, "sun")
    w.light_panel.periodic.setChecked(True)
    compute(qtbot, w)
    before = list(w.model.runs.last.transmission)
    ply = tmp_path / "exported.ply"
    export_canopy(str(ply), w.model.canopy)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_mesh(ply, "cm", "z")
    assert w.model.canopy.layout.bounds == layout.bounds
    assert w.model.canopy.layout.period == layout.centre_bounds == w.model.canopy.layout.centre_bounds
    assert "the field is the file's" in w.messages.toPlainText()
    small_light(w.light_panel, "sun")
    w.light_panel.periodic.setChecked(True)
    compute(qtbot, w)
    assert list(w.model.runs.last.transmission) == before
