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
    # one actor for all leaves and stalks: nothing per plant or per leaf
    assert set(viewport.actors) == {"canopy", "ground"}


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
