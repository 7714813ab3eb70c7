"""A project whose layout was edited reopens with each plant's light on that plant."""

import numpy as np


TIMEOUT = 120_000


def per_stand(w):
    """Stand (plant, x, y, azimuth) -> the light value shown on its leaves."""
    values = w.viewport.canopy_mesh.cell_data["light_value"][:w.canopy.n_triangles]
    out = {}
    for i, p in enumerate(w.canopy.layout.placements):
        mine = values[w.canopy.face_instance == i]
        out[(p.plant, round(p.x, 6), round(p.y, 6), round(p.azimuth_deg, 6))] = \
            np.sort(mine)
    return out


def test_an_edited_layouts_sky_light_stays_on_its_plants(window, qtbot, small_points,
                                                         tmp_path):
    from dataclasses import replace

    from maizeviz.canopy.layout import layout_for

    w = window(small_points, tile=1)
    if w.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    # the layout edited: a 3 x 3 tiling, one plant turned, stands in the tiling's order
    tiled = layout_for(w.loaded.leaves, (3, 3))
    turned = tuple(replace(p, azimuth_deg=90.0) if i == 4 else p
                   for i, p in enumerate(tiled.placements))
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.layout_panel.applied.emit(replace(tiled, placements=turned))
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
        w.save_project(path)

    w2 = window(path)
    with qtbot.waitSignal(w2.light_shown, timeout=TIMEOUT):
        pass
    assert w2.loaded.layout.placements == w.loaded.layout.placements   # order and tiles
    assert w2.viewport.colouring == "light"
    after = per_stand(w2)
    assert after.keys() == before.keys()
    for stand, values in before.items():    # the same light on the same plant, to rounding
        np.testing.assert_allclose(after[stand], values, rtol=1e-5, err_msg=str(stand))
