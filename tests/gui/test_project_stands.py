"""A project whose layout was edited reopens with each plant's light on that plant."""

import numpy as np

TIMEOUT = 120_000


def per_stand(w):
    """Stand (plant, x, y, azimuth) -> the light value shown on its leaves."""
    values = w.viewport.canopy_mesh.cell_data["light_value"][:w.model.canopy.n_triangles]
    out = {}
    for i, p in enumerate(w.model.canopy.layout.placements):
        mine = values[w.model.canopy.face_instance == i]
        out[(p.plant, round(p.x, 6), round(p.y, 6), round(p.azimuth_deg, 6))] = \
            np.sort(mine)
    return out


def test_an_edited_layouts_sky_light_stays_on_its_plants(window, qtbot, small_points,
                                                         tmp_path):
    from dataclasses import replace

    from maizeviz.canopy.layout import layout_for

    w = window(small_points, tile=1)
    if w.model.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    # the layout edited: a 3 x 3 tiling, one plant turned, stands in the tiling's order
    tiled = layout_for(w.model.loaded.leaves, (3, 3))
    turned = tuple(replace(p, azimuth_deg=90.0) if i == 4 else p
                   for i, p in enumerate(tiled.placements))
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.model.apply_layout(replace(tiled, placements=turned))
    panel = w.light_panel
    panel.set_mode("sky")
    panel.heights.setText("0, 100, 200")
    panel.density.setValue(0.3)
    panel.sky_split.setCurrentIndex(panel.sky_split.findData(16))
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        panel.compute_button.click()
    before = per_stand(w)
    # plants take different light (else the check below could not fail)
    assert len({round(float(v.sum()), 6) for v in before.values()}) > 1
    path = tmp_path / "edited.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)

    w2 = window(path)
    with qtbot.waitSignal(w2.light_shown, timeout=TIMEOUT):
        pass
    assert w2.model.loaded.layout.placements == w.model.loaded.layout.placements   # order and tiles
    assert w2.viewport.colouring == "light"
    after = per_stand(w2)
    assert after.keys() == before.keys()
    for stand, values in before.items():    # the same light on the same plant, to rounding
        np.testing.assert_allclose(after[stand], values, rtol=1e-5, err_msg=str(stand))


def test_results_of_other_stands_are_left_out_with_one_line(window, qtbot, small_points,
                                                            tmp_path):
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.io.archive import save_project
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.light.scene.request import Sampling
    from maizeviz.light.sources.sky import make_sky
    from maizeviz.light.trace.directions import trace_sky
    from maizeviz.mesh.levels import parse_level
    from maizeviz.project.study import make_project

    leaves = read_leaves(small_points).leaves
    level = parse_level("36")
    other = layout_for(leaves, (3, 3))               # traced on a 3 x 3 tiling...
    sky = trace_sky(build_canopy(leaves, other, level), make_sky("soc", 16),
                    Sampling((0.0, 100.0), 0.3, None, True, 1))
    path = tmp_path / "stale.maizeviz"                # ...saved with the 1 x 1 tiling
    save_project(path, make_project(str(small_points), small_points.read_bytes(), None, other,
                                    {"tile": 1, "level": "36", "preserve_area": True}, {},
                                    [(level.label, sky)]))
    w = window(path)
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    text = w.messages.toPlainText()
    assert (f"note: the sky result on {level.label} was traced on other stands (18 plants) "
            "than the project's layout (2); left out (compute it again)") in text
    assert not w.model.runs.runs and w.viewport.colouring != "light"
