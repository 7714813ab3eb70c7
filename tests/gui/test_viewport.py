"""The 3D view alone, on two plants: renders only on change, one mesh, light colouring."""

import numpy as np
import pytest


def renders_during(qtbot, viewport, ms, action=None):
    """Frames rendered while ``action`` runs and events are processed for ``ms``."""
    qtbot.wait(50)
    before = viewport.render_count
    if action is not None:
        action()
    qtbot.wait(ms)
    return viewport.render_count - before


def test_no_idle_renders(qtbot, viewport, small_canopy):
    viewport.show_canopy(small_canopy)
    qtbot.waitUntil(lambda: viewport.render_count > 0, timeout=10_000)
    qtbot.wait(300)
    assert renders_during(qtbot, viewport, 2000) == 0         # pyvistaqt renders 5/s idle


def test_one_render_per_canopy_and_per_colouring(qtbot, viewport, small_canopy):
    viewport.show_canopy(small_canopy)
    qtbot.wait(500)
    assert renders_during(qtbot, viewport, 700, lambda: viewport.show_canopy(small_canopy)) == 1
    assert renders_during(qtbot, viewport, 700, lambda: viewport.colour_by("plant")) == 1
    assert renders_during(qtbot, viewport, 700,
                          lambda: viewport.camera_preset("top")) == 1
    # several changes in one go still make one frame
    def burst():
        viewport.colour_by("leaf")
        viewport.camera_preset("along")
        viewport.show_canopy(small_canopy)
    assert renders_during(qtbot, viewport, 700, burst) == 1


def test_canopy_is_one_mesh_with_ids(viewport, small_canopy):
    viewport.show_canopy(small_canopy)
    mesh = viewport.canopy_mesh
    n_stalk = len(small_canopy.stalk_faces)
    assert mesh.n_cells == small_canopy.n_triangles + n_stalk
    for name in ("plant", "instance", "leaf", "light"):
        assert len(mesh.cell_data[name]) == mesh.n_cells
    assert set(np.unique(mesh.cell_data["plant"])) == {p.plant for p in
                                                        small_canopy.layout.placements}
    assert np.all(mesh.cell_data["leaf"][small_canopy.n_triangles:] == 0)      # stalks
    # one actor for all leaves and stalks: nothing per plant or per leaf (and the selection's,
    # hidden until a click)
    assert set(viewport.actors) == {"canopy", "ground", "selection"}
    assert not viewport.actors["selection"].GetVisibility()


def test_light_colouring(qtbot, viewport, small_canopy):
    viewport.show_canopy(small_canopy)
    assert not viewport.colour_by("light")                     # nothing traced yet
    assert viewport.colouring == "leaf"
    classes = np.zeros(small_canopy.n_triangles, np.int8)
    classes[::3] = 2
    classes[1::3] = 1
    viewport.set_light(classes)
    assert viewport.colour_by("light")
    mapper = viewport.actors["canopy"].mapper
    assert mapper.GetArrayName() == "light"
    assert "direct" in viewport.key.text() and viewport.key.isVisible()
    light = viewport.canopy_mesh.cell_data["light"]
    np.testing.assert_array_equal(light[:small_canopy.n_triangles], classes)
    assert np.all(light[small_canopy.n_triangles:] == -2)                  # stalks
    with pytest.raises(ValueError, match="light classes for"):
        viewport.set_light(classes[:-1])
    # a new canopy has no light of its own: the view falls back to leaf rank
    viewport.show_canopy(small_canopy)
    assert viewport.colouring == "leaf" and not viewport.has_light()


def test_digitizing_hides_and_restores_the_canopy(qtbot, viewport, small_canopy):
    from maizeviz.leaf.fit import fit_leaves
    from maizeviz.leaf.grid import LeafGrid
    from maizeviz.leaf.synth import example_leaf
    from maizeviz.mesh.levels import Level, mesh_leaves

    viewport.show_canopy(small_canopy)
    viewport.hide_canopy()
    assert "canopy" not in viewport.actors and "ground" not in viewport.actors
    leaves, _ = fit_leaves([LeafGrid(1, 1, example_leaf(seed=1), True)])
    meshes = mesh_leaves(leaves, Level(interp=1))
    viewport.show_leaf_surfaces(meshes, leaves[0].grid.points.reshape(-1, 3))
    assert "leafsurf" in viewport.actors and "digitized" in viewport.actors
    assert viewport.actors["digitized"].prop.opacity < 1           # points do not hide leaves
    viewport.restore_canopy()
    assert viewport.actors["canopy"].GetVisibility() and "ground" in viewport.actors
    assert "leafsurf" not in viewport.actors and "digitized" not in viewport.actors


def test_plant_and_leaf_colour_per_vertex_as_per_triangle(viewport, small_canopy):
    """Plant and leaf colour the mesh per vertex (cheaper to draw than per triangle), with the
    colour of every triangle the vertex belongs to; light stays per triangle."""
    viewport.show_canopy(small_canopy)
    mesh = viewport.canopy_mesh
    faces = mesh.regular_faces
    mapper = viewport.actors["canopy"].mapper
    for what in ("plant", "leaf"):
        cells = np.asarray(mesh.cell_data[what])
        np.testing.assert_array_equal(np.asarray(mesh.point_data[what])[faces],
                                      np.repeat(cells[:, None], 3, axis=1))
        viewport.colour_by(what)
        assert mapper.GetScalarModeAsString() == "UsePointFieldData"
        assert mapper.GetArrayName() == what and not mapper.GetInterpolateScalarsBeforeMapping()
        per_vertex = np.asarray(mapper.MapScalars(1.0)).copy()       # what OpenGL receives
        mapper.SetScalarModeToUseCellFieldData()                     # as it was: per triangle
        per_triangle = np.asarray(mapper.MapScalars(1.0)).copy()
        mapper.SetScalarModeToUsePointFieldData()
        assert per_vertex.shape == (mesh.n_points, 4) and per_triangle.shape == (len(faces), 4)
        assert len(np.unique(per_triangle, axis=0)) >= 2                # plants, leaves, stalks
        np.testing.assert_array_equal(per_vertex[faces],
                                      np.repeat(per_triangle[:, None], 3, axis=1))
    viewport.set_light(np.full(small_canopy.n_triangles, 2, np.int8))
    assert viewport.colour_by("light")
    assert mapper.GetScalarModeAsString() == "UseCellFieldData"


def test_a_vertex_shared_by_two_leaves_is_split(small_canopy):
    """An imported mesh may share a vertex between leaves: the view splits it, so that colours
    per vertex are those of each triangle."""
    from maizeviz_app.viewport import canopy_polydata

    from maizeviz.canopy.build import Canopy

    square = np.array([[0, 0, 10], [10, 0, 10], [10, 10, 12], [0, 10, 12]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])                  # sharing the edge 0-2
    canopy = Canopy.from_triangles(square, faces, small_canopy.layout,
                                   face_leaf=np.array([1, 2]))
    mesh = canopy_polydata(canopy)
    assert mesh.n_points == 6 and mesh.n_cells == 2
    np.testing.assert_array_equal(np.asarray(mesh.point_data["leaf"])[mesh.regular_faces],
                                  [[1, 1, 1], [2, 2, 2]])
    np.testing.assert_allclose(np.asarray(mesh.points)[mesh.regular_faces], square[faces])


def test_stalks_of_different_sizes(small_canopy):
    """A canopy read from a mesh gives each stalk triangle its plant (stalks of their own
    sizes): the view's mesh takes them (it assumed equal shares and failed)."""
    from dataclasses import replace

    from maizeviz_app.viewport import canopy_polydata

    n = len(small_canopy.stalk_faces)
    per = n // small_canopy.n_plants
    inst = np.repeat(np.arange(small_canopy.n_plants, dtype=np.int32), per)[3:]
    canopy = replace(small_canopy, stalk_faces=small_canopy.stalk_faces[3:], stalk_instance=inst)
    mesh = canopy_polydata(canopy)
    stalks = slice(canopy.n_triangles, None)
    assert mesh.n_cells == canopy.n_triangles + n - 3
    np.testing.assert_array_equal(np.asarray(mesh.cell_data["instance"])[stalks], inst + 1)
    plants = np.array([p.plant for p in canopy.layout.placements])
    np.testing.assert_array_equal(np.asarray(mesh.cell_data["plant"])[stalks], plants[inst])
    assert np.all(np.asarray(mesh.cell_data["leaf"])[stalks] == 0)


def test_a_moving_camera_draws_a_lighter_canopy_and_the_whole_one_when_it_stops(
        window, qtbot, small_points):
    """Rotation without stalls at K = 4 (issue 37): while the camera moves (a drag, a wheel
    turn) the view draws every k-th triangle, coloured as the canopy; once it stops, the
    whole canopy again. Shown here with the threshold lowered to this small canopy's size."""
    from PySide6.QtCore import QPoint, QPointF, Qt
    from PySide6.QtGui import QWheelEvent
    from test_light_modes import shown

    w = shown(qtbot, window(small_points, tile=1))
    view = w.viewport
    n = view.canopy_mesh.n_cells
    view.MOVING_TRIANGLES = n // 4
    canopy = view.actors["canopy"]
    assert view.start_moving()
    lod = view.actors["canopy_moving"]
    assert lod.GetVisibility() and not canopy.GetVisibility()
    k = int(np.ceil(n / view.MOVING_TRIANGLES))
    assert lod.mapper.dataset.n_cells == len(range(0, n, k))
    assert lod.GetMapper().GetArrayName() == canopy.GetMapper().GetArrayName()
    assert lod.GetMapper().GetLookupTable() is canopy.GetMapper().GetLookupTable()
    view.stop_moving()
    assert canopy.GetVisibility() and not lod.GetVisibility()
    # a wheel turn: lighter at once, whole again once the wheel rests
    wheel = QWheelEvent(QPointF(50, 50), QPointF(view.mapToGlobal(QPoint(50, 50))),
                        QPoint(0, 0), QPoint(0, 120), Qt.MouseButton.NoButton,
                        Qt.KeyboardModifier.NoModifier, Qt.ScrollPhase.NoScrollPhase, False)
    view.wheelEvent(wheel)
    assert lod.GetVisibility() and not canopy.GetVisibility()
    qtbot.waitUntil(lambda: canopy.GetVisibility() and not lod.GetVisibility(), timeout=5000)


@pytest.mark.parametrize("field, rs, ps", [((-180, -90, 360, 180), 60, 30),   # 3x3 tiled
                                           ((0, 0, 180, 90), 60, 30),        # the block
                                           ((0, 0, 5400, 2700), 60, 30)])    # a field
def test_the_grounds_labels_do_not_overlap_and_y_reads_upright(field, rs, ps):
    """The first y label sat on the first x label at the corner ('-90' over '-180'), and the
    y axis's name read upside down from the usual views (turned -90 degrees)."""
    from maizeviz_app.viewport import _ticks, ground_labels

    x0, y0, x1, y1 = field
    margin = max(25.0, 0.09 * max(x1 - x0, y1 - y0))
    labels = ground_labels(field, margin, _ticks(x0, x1, rs), _ticks(y0, y1, ps))
    char_h = 0.42 * margin                      # the font's pixel size, in cm of ground
    boxes = []
    for text, x, y, _wide, angle in labels:
        w, h = 0.6 * char_h * len(text), char_h     # DejaVu Sans: under 0.6 em a character
        if angle % 180:
            w, h = h, w
        boxes.append((text, x - w / 2, y - h / 2, x + w / 2, y + h / 2))
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            apart = a[3] <= b[1] or b[3] <= a[1] or a[4] <= b[2] or b[4] <= a[2]
            assert apart, f"'{a[0]}' and '{b[0]}' overlap"
    assert [angle for text, *_, angle in labels if text.startswith("y (")] == [90.0]
