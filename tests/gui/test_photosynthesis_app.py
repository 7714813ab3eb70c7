"""Photosynthesis in the app: a leaf model chosen in the Light panel (bound to the study's
settings, undoable) turns a sun's absorbed PAR into gross CO2 assimilation, computed in the
light process; the canopy is painted with it (View > Colour by > CO2 assimilation), the plants
table and the results table gain it, picking a leaf says it, and a project keeps the choice
and gives back the same numbers."""

from __future__ import annotations

import numpy as np
import pytest
from maizeviz_app.runs import ASSIMILATION_ROW
from maizeviz_app.selection import describe
from maizeviz_app.settings import MODEL_PARAMS, PhotosynthesisSettings, StudySettings
from test_light_modes import TIMEOUT, compute, headers, shown, small_light

from maizeviz.light.results.assimilation import assimilate
from maizeviz.photosynthesis.c4 import C4Leaf
from maizeviz.photosynthesis.split import leaf_model
from maizeviz.photosynthesis.wofost import WofostLeaf


def _rows(table):
    return [[table.item(r, c).text() if table.item(r, c) else ""
             for c in range(table.columnCount())] for r in range(table.rowCount())]


def _with_c4(qtbot, window, small_points, vmax=45.0):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    p.photo_model.setCurrentIndex(p.photo_model.findData("c4"))
    p.c4_vmax.setValue(vmax)
    return w, p


def test_settings_defaults_are_the_core_models():
    """The panel's defaults are the leaf models' own (the app is not a second source)."""
    s = PhotosynthesisSettings()
    c4, wofost = C4Leaf(), WofostLeaf()
    assert (s.vmax, s.alpha, s.co2_ppm) == (c4.vmax, c4.alpha, c4.co2_ppm)
    assert (s.amax, s.eff) == (wofost.amax, wofost.eff)
    for model, names in MODEL_PARAMS.items():              # the core's names of the fields
        core = {"c4": c4, "wofost": wofost}[model]
        assert all(getattr(s, k) == getattr(core, k) for k in names)
    study = StudySettings()
    study.optics.enabled = True
    assert study.optics_spec().leaf_model() is None              # none: absorbed light only
    study.photosynthesis.model = "wofost"
    study.photosynthesis.amax = 60.0
    spec = study.optics_spec()
    assert spec.leaf_model() == WofostLeaf(amax=60.0)            # only what differs is passed
    assert spec.photosynthesis_params == (("amax", 60.0),)
    # the project document carries the choice, and a project without it keeps the defaults
    doc = study.light_doc()
    assert doc["photosynthesis"] == "wofost" and doc["wofost_amax"] == 60.0
    again = StudySettings()
    again.apply_light_doc(doc)
    assert again.snapshot("photosynthesis") == study.snapshot("photosynthesis")
    old = StudySettings()
    old.apply_light_doc({k: v for k, v in doc.items() if k not in
                         ("photosynthesis", "wofost_amax")})
    assert old.photosynthesis.model == "none" and old.photosynthesis.amax == 70.0
    # the C4 temperature response: the paper's by default, kept in the project, and a project
    # saved before it was a choice reads as CLM 4.5's, what it computed
    assert s.c4_temperature == C4Leaf().temperature_response == "collatz"
    study.photosynthesis.model = "c4"
    study.photosynthesis.c4_temperature = "clm45"
    assert study.optics_spec().leaf_model().temperature_response == "clm45"
    doc = study.light_doc()
    assert doc["c4_temperature"] == "clm45"
    study.photosynthesis.c4_temperature = "collatz"
    saved_then = {k: v for k, v in study.light_doc().items() if k != "c4_temperature"}
    older = StudySettings()
    older.apply_light_doc(saved_then)
    assert older.photosynthesis.c4_temperature == "clm45"
    assert older.optics_spec().leaf_model() == C4Leaf(temperature_response="clm45")


def test_a_leaf_model_paints_assimilation_and_a_project_keeps_it(window, qtbot, small_points,
                                                                   tmp_path):
    w, p = _with_c4(qtbot, window, small_points)
    ph = w.model.settings.photosynthesis
    assert ph.model == "c4" and ph.vmax == 45.0                  # bound to the model
    assert p.c4_vmax.isVisibleTo(p) and not p.wofost_amax.isVisibleTo(p)
    compute(qtbot, w)
    run = w.model.runs.last
    g = run.extra.assimilation
    canopy = w.model.canopy
    # the light process's figure is the core's on the same absorbed light (oracle: the core
    # called here on the result the app got)
    own = assimilate(canopy, run.extra.light, leaf_model("c4", vmax=45.0), 25.0)
    assert g.model["vmax"] == 45.0
    assert g.canopy_gross_umol_m2_s == pytest.approx(own.canopy_gross_umol_m2_s, rel=1e-12)
    assert 0 < g.canopy_gross_umol_m2_s
    # the plants table gains the gross assimilation; the plants add up to the canopy's
    head = headers(p.plants)
    assert "CO₂ gross µmol/s" in head and "± se" in head
    plants = _rows(p.plants)
    total = sum(float(r[head.index("CO₂ gross µmol/s")]) for r in plants)
    assert total == pytest.approx(g.canopy_gross_umol_m2_s * g.ground_m2,
                                  abs=0.005 * len(plants) + 1e-9)
    assert "C4 leaf, Vmax 45" in p.plants_title.text()
    assert "temperature response Collatz et al. 1992" in p.plants_title.text()
    assert p.c4_temperature.isVisibleTo(p) and p.c4_temperature.currentData() == "collatz"
    # the results table says the canopy's figure beside the energy balance
    rows = {r[0]: r[1:] for r in _rows(p.table)}
    assert rows[ASSIMILATION_ROW][0].startswith(f"{g.canopy_gross_umol_m2_s:.2f} ± ")
    assert "gross CO₂ assimilation" in p.info.text() and "kg CO₂/ha/h" in p.info.text()
    # painted: colour by assimilation shows each leaf's umol per m2 of leaf, with its unit
    w.colour_by("assimilation")
    v = w.viewport
    assert v.colouring == "assimilation"
    assert w.menu_actions["colour_assimilation"].isChecked()
    nf = canopy.n_triangles
    np.testing.assert_allclose(v.canopy_mesh.cell_data["assimilation_value"][:nf],
                               run.extra.gross_value, rtol=1e-6)
    assert "µmol/m² leaf/s" in v.key.text() and "C4" in v.key.text()
    lit = run.extra.gross_value[run.extra.gross_value > 0]
    assert len(lit) and v.shown_limits[1] == pytest.approx(float(lit.max()), rel=1e-5)
    # picking a leaf says its assimilation: per m2 of leaf as painted
    leaf_tri = int(np.argmax(run.extra.gross_value))
    inst, leaf = int(canopy.face_instance[leaf_tri]), int(canopy.face_leaf[leaf_tri])
    lines = describe(canopy, run.label, [run], inst, leaf)
    said = [line for line in lines if "gross CO₂ assimilation" in line]
    assert said and f"{float(run.extra.gross_value[leaf_tri]):.3g} µmol/m² of leaf/s" in said[0]
    # the exported canopy carries it per triangle, beside the absorbed light
    import pyvista as pv

    out = tmp_path / "carbon.vtu"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.export("canopy", out)
    mesh = pv.read(out)
    np.testing.assert_allclose(np.asarray(mesh.cell_data["gross_umol_co2_per_m2_leaf_s"])[:nf],
                               run.extra.gross_value, rtol=1e-6)
    # a project keeps the model and gives the same assimilation back, painted
    path = tmp_path / "carbon.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    w2 = window(path)
    qtbot.waitUntil(lambda: w2.model.runs.last is not None and w2.model.runs.last.extra is not None
                    and w2.model.runs.last.extra.leaf_value is not None, timeout=TIMEOUT)
    p2 = w2.light_panel
    assert p2.photo_model.currentData() == "c4" and p2.c4_vmax.value() == 45.0
    run2 = w2.model.runs.last
    assert run2.extra.assimilation.canopy_gross_umol_m2_s == g.canopy_gross_umol_m2_s
    np.testing.assert_array_equal(run2.extra.gross_value, run.extra.gross_value)
    assert _rows(p2.plants) == plants
    w2.colour_by("assimilation")
    assert w2.viewport.colouring == "assimilation"
    # a sun without a leaf model: nothing to colour by, the view goes back to the light
    p.photo_model.setCurrentIndex(p.photo_model.findData("none"))
    compute(qtbot, w)
    assert w.model.runs.last.extra.assimilation is None
    assert v.colouring == "light" and not v.has_assimilation()
    assert "CO₂ gross µmol/s" not in headers(p.plants)


def test_the_model_choice_is_undoable_and_wofost_shows_its_parameters(window, qtbot,
                                                                      small_points):
    w, p = _with_c4(qtbot, window, small_points)
    stack = w.undo.stack
    p.photo_model.setCurrentIndex(p.photo_model.findData("wofost"))
    assert w.model.settings.photosynthesis.model == "wofost"
    assert stack.undoText() == "photosynthesis wofost"
    assert p.wofost_amax.isVisibleTo(p) and p.wofost_eff.isVisibleTo(p)
    assert not p.c4_vmax.isVisibleTo(p)
    stack.undo()
    assert w.model.settings.photosynthesis.model == "c4"
    assert p.photo_model.currentData() == "c4" and p.c4_vmax.isVisibleTo(p)
    stack.undo()                                                   # the Vmax typed
    assert w.model.settings.photosynthesis.vmax == 39.0 and p.c4_vmax.value() == 39.0
    assert stack.undoText() == "photosynthesis c4"
    stack.undo()
    assert p.photo_model.currentData() == "none" and not p.c4_vmax.isVisibleTo(p)
    assert not p.leaf_temp.isEnabled()


def test_photosynthesis_from_nir_is_one_line_on_the_band(window, qtbot, small_points):
    w, p = _with_c4(qtbot, window, small_points)
    p.band.setCurrentIndex(p.band.findData("nir"))
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as sig:
        p.compute_button.click()
    assert "PAR" in sig.args[0] and "internal" not in sig.args[0] and "\n" not in sig.args[0]
    assert "border" in p.band.styleSheet()
    assert w.model.runs.last is None                               # nothing traced


def test_a_suns_light_and_carbon_per_plant_and_per_leaf_are_exported(window, qtbot,
                                                                     small_points, tmp_path):
    """Issue 37, item 1: after a sun with leaf optics and C4, the panel's Leaves... and
    Plants... and File's light per leaf / plant write the absorbed light and the gross CO2 of
    each leaf and plant (they were greyed, and File's said 'no sky or day computed yet')."""
    import csv

    w, p = _with_c4(qtbot, window, small_points)
    assert not p.export_buttons["plants"].isEnabled()
    compute(qtbot, w)
    g = w.model.runs.last.extra.assimilation
    assert p.export_buttons["plants"].isEnabled() and p.export_buttons["leaves"].isEnabled()
    plants_csv, leaves_csv = tmp_path / "plants.csv", tmp_path / "leaves.csv"
    for what, path in (("plants", plants_csv), ("leaves", leaves_csv)):
        with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
            assert w.model.export(what, path)
    plants = list(csv.DictReader(plants_csv.open()))
    leaves = list(csv.DictReader(leaves_csv.open()))
    shown_rows = _rows(p.plants)
    head = headers(p.plants)
    assert len(plants) == len(shown_rows)
    for row, seen in zip(plants, shown_rows):
        assert f"{float(row['gross_umol_s']):.2f}" == seen[head.index("CO₂ gross µmol/s")]
        assert float(row["absorbed_w"]) > 0
    total = sum(float(r["gross_umol_s"]) for r in leaves)
    assert total == pytest.approx(g.canopy_gross_umol_m2_s * g.ground_m2, rel=1e-6)
    assert sum(float(r["gross_umol_s"]) for r in plants) == pytest.approx(total, rel=1e-6)
    assert {r["level"] for r in leaves} == {w.model.runs.last.label}
