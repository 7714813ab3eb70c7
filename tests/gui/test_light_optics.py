"""Leaf optics in the light panel: a sun traced with scattering shows the leaves' absorbed
light painted on the plants, the energy balance in the results table and each plant's
absorbed light; the settings travel with a project."""

from __future__ import annotations

import numpy as np
from test_light_modes import TIMEOUT, compute, headers, shown, small_light


def _rows(table):
    return [[table.item(r, c).text() if table.item(r, c) else ""
             for c in range(table.columnCount())] for r in range(table.rowCount())]


def test_sun_with_leaf_optics_paints_absorbed_light_and_balances(window, qtbot, small_points,
                                                                 tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    assert p.band.currentData() == "par" and p.reflectance.value() == 0.10
    assert p.direct_w.value() == 480.0                      # PAR share of 1000 W/m2
    compute(qtbot, w)
    run = w.model.runs.last
    a = run.extra.light
    b = a.balance
    assert a.band == "par" and b.incident == 480.0
    assert abs(b.closure) < 0.01 and 0 < b.absorbed_leaves < b.incident
    # the balance rows of the results table are the result's numbers
    rows = {r[0]: r[1:] for r in _rows(p.table)}
    assert rows["PAR incident W/m²"] == ["480.0"]
    assert float(rows["absorbed by leaves W/m²"][0]) == round(b.absorbed_leaves, 1)
    assert float(rows["reflected out of the top W/m²"][0]) == round(b.reflected_top, 1)
    assert "leaves absorb" in p.info.text() and "closes within" in p.info.text()
    # each plant's absorbed W: they add up to what the leaves absorb over the sample ground
    plants = _rows(p.plants)
    assert headers(p.plants)[3] == "PAR absorbed W" and len(plants) == 2
    total_w = sum(float(r[3]) for r in plants)
    area_m2 = (a.rect[2] - a.rect[0]) * (a.rect[3] - a.rect[1]) * 1e-4
    assert abs(total_w - b.absorbed_leaves * area_m2) < 0.01 * len(plants) + 1e-6
    # painted: W per m2 of leaf on each leaf triangle, the colour bar says so
    values = w.viewport.canopy_mesh.cell_data["light_value"][:w.model.canopy.n_triangles]
    np.testing.assert_allclose(values, run.extra.leaf_value, rtol=1e-6)
    assert w.viewport.colouring == "light" and values.max() > 0
    # the settings and the absorbed light go into the project and come back as computed
    path = tmp_path / "optics.maizeviz"
    table = _rows(p.table)
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    w2 = window(path)
    qtbot.waitUntil(lambda: w2.model.runs.last is not None and w2.model.runs.last.extra is not None
                    and w2.model.runs.last.extra.leaf_value is not None, timeout=TIMEOUT)
    p2 = w2.light_panel
    assert p2.optics_box.isChecked() and p2.reflectance.value() == 0.10
    run2 = w2.model.runs.last
    assert run2.balance == b and _rows(p2.table) == table
    np.testing.assert_array_equal(run2.extra.light.triangle_absorbed_w, a.triangle_absorbed_w)
    np.testing.assert_array_equal(run2.extra.leaf_value, run.extra.leaf_value)
    qtbot.waitUntil(lambda: w2.viewport.colouring == "light", timeout=TIMEOUT)
    np.testing.assert_allclose(
        w2.viewport.canopy_mesh.cell_data["light_value"][:w2.model.canopy.n_triangles],
        run.extra.leaf_value, rtol=1e-6)
    assert _rows(p2.plants) == plants
    # the same sun and optics again: the comparison goes on (same settings)
    compute(qtbot, w2)
    assert "starts again" not in w2.messages.toPlainText()


def test_black_leaves_absorb_what_they_intercept(window, qtbot, small_points):
    """Leaf and soil optics all 0: the leaves absorb the share of the beam the sun's rays
    intercept, nothing is reflected."""
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    for box in (p.reflectance, p.transmittance, p.ground_reflectance):
        box.setValue(0.0)
    compute(qtbot, w)
    run = w.model.runs.last
    b = run.extra.light.balance
    assert b.reflected_top == 0 and b.absorbed_ground > 0
    assert abs(b.absorbed_leaves / b.incident - run.result.sunlit_intercepted_fraction) < 1e-9


def test_optics_out_of_range_is_one_line_on_the_field(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "sun")
    p.optics_box.setChecked(True)
    p.reflectance.setValue(0.7)
    p.transmittance.setValue(0.6)
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as sig:
        p.compute_button.click()
    assert "1" in sig.args[0] and "internal" not in sig.args[0]
    assert "border" in p.transmittance.styleSheet() or "border" in p.reflectance.styleSheet()


def test_a_day_with_perez_diffuse_light(window, qtbot, small_points, tmp_path):
    """Day mode with Perez's anisotropic diffuse light: the same directions traced, the
    circumsolar share said, the choice saved in the project."""
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "day")
    p.day_diffuse.setCurrentIndex(p.day_diffuse.findData("perez"))
    assert not p.sky_kind.isEnabled() and "uniform sky" in p.sky_kind.toolTip()
    compute(qtbot, w)
    day = w.model.runs.last.result
    assert day.diffuse is not None and day.diffuse.model == "perez"
    assert "Perez anisotropic" in p.info.text() and "circumsolar" in p.info.text()
    total = day.par_diffuse_mol_m2
    assert abs(float(day.step_diffuse_mol_m2.sum()) - total) < 1e-9 * max(total, 1)
    path = tmp_path / "perez.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    w2 = window(path)
    qtbot.waitUntil(lambda: w2.model.runs.last is not None, timeout=TIMEOUT)
    assert w2.light_panel.day_diffuse.currentData() == "perez"
    w2.light_panel.set_mode("sky")
    assert w2.light_panel.sky_kind.isEnabled()          # a sky alone has its own shape
    assert w2.model.runs.last.result.diffuse is not None
