"""Colour scales of the views: the Qt-free settings and their arithmetic, the panel bound to
them both ways, the 3D view and the heatmaps following them, a project keeping them."""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from maizeviz_app.colour import (
    CMAPS,
    ColourError,
    ColourScale,
    ColourSettings,
    colour_table,
    colours_of,
    normalised,
)

finite = st.floats(-1e6, 1e6, allow_nan=False)
values_lists = st.lists(st.one_of(finite, st.just(float("nan"))), min_size=0, max_size=60)


def test_colour_settings_import_without_qt():
    code = ("import sys, maizeviz_app.colour; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvista', 'vtk')]; "
            "sys.exit(1 if bad else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


@given(values_lists)
def test_auto_range_spans_every_finite_value_whatever_their_order(values):
    scale = ColourScale()
    lo, hi = scale.limits(np.array(values))
    assert lo < hi
    v = np.array([x for x in values if np.isfinite(x)])
    if len(v) and v.max() > v.min():
        assert (lo, hi) == (v.min(), v.max())
    # order and duplicates change nothing
    shuffled = np.random.default_rng(0).permutation(np.array(values + values, dtype=float))
    assert scale.limits(shuffled) == (lo, hi)


@given(st.lists(finite, min_size=2, max_size=80), st.floats(0, 45))
def test_percentile_clip_is_numpys_percentile(values, clip):
    scale = ColourScale(range="percentile", clip=clip)
    lo, hi = scale.limits(np.array(values))
    want = np.percentile(values, [clip, 100 - clip])
    if want[1] > want[0]:
        assert (lo, hi) == pytest.approx(tuple(want))
    assert lo < hi


def test_log_range_starts_at_the_smallest_positive_value_and_typed_range_is_kept():
    assert ColourScale(log=True).limits([0.0, 0.0, 0.02, 0.5, np.nan]) == (0.02, 0.5)
    assert ColourScale(range="fixed", vmin=0.2, vmax=0.3).limits([0, 1]) == (0.2, 0.3)
    assert ColourScale().limits([]) == (0.0, 1.0)
    lo, hi = ColourScale().limits([0.7, 0.7])             # one value: in the middle
    assert lo < 0.7 < hi and 0.7 - lo == pytest.approx(hi - 0.7)


@pytest.mark.parametrize("bad, words", [
    ({"range": "fixed", "vmin": 1.0, "vmax": 1.0}, "minimum (1) must be below the maximum (1)"),
    ({"range": "fixed", "vmin": 0.0, "vmax": 1.0, "log": True}, "log scale needs a minimum"),
    ({"cmap": "jet"}, "colour map 'jet' is not one of viridis, cividis, inferno, greys"),
    ({"range": "sometimes"}, "colour range 'sometimes'"),
    ({"clip": 50.0}, "percentile clip 50 %"),
])
def test_unusable_scales_say_what_is_wrong(bad, words):
    with pytest.raises(ColourError, match=words.replace("(", r"\(").replace(")", r"\)")):
        ColourScale(**bad).check()


def test_colours_clamp_to_the_ends_and_keep_their_own_colours_for_stalks_and_untraced():
    table = colour_table("viridis")
    v = np.array([-5.0, 0.0, 0.25, 0.5, 2.0, np.nan, -1.0])
    rgb = colours_of(v, 0.0, 0.5, table, special={-1.0: (176, 135, 90)}, nan=(1, 2, 3))
    assert (rgb[0] == table[0]).all() and (rgb[1] == table[0]).all()      # clamped low
    assert (rgb[3] == table[-1]).all() and (rgb[4] == table[-1]).all()    # clamped high
    assert (rgb[2] == table[128]).all()
    assert tuple(rgb[5]) == (1, 2, 3) and tuple(rgb[6]) == (176, 135, 90)
    # log: a decade is the same step anywhere; 0 takes the lowest colour
    t = normalised(np.array([0.0, 0.01, 0.1, 1.0]), 0.01, 1.0, log=True)
    assert t.tolist() == pytest.approx([0.0, 0.0, 0.5, 1.0])
    # greys run from black (least light) to white
    assert colour_table("greys")[0].tolist() == [0, 0, 0]
    assert colour_table("greys")[-1].tolist() == [255, 255, 255]


@given(st.lists(st.floats(0, 1), min_size=2, max_size=40))
def test_colours_are_in_the_order_of_the_values(values):
    v = np.sort(np.array(values))
    t = normalised(v, 0.0, 1.0)
    assert np.all(np.diff(t) >= 0)


def test_settings_round_trip_and_older_projects_get_the_defaults():
    s = ColourSettings()
    events = []
    s.view.events.connect(lambda info: events.append(info.signal.name))
    s.update_from_doc({"view": {"range": "fixed", "vmin": 0.1, "vmax": 0.9, "cmap": "greys",
                                "log": True}, "heatmap": {"range": "percentile", "clip": 5},
                       "shared": True, "painting": "leaves", "from a newer maizeviz": 1})
    doc = s.to_doc()
    again = ColourSettings()
    again.update_from_doc(json.loads(json.dumps(doc)))
    assert again.to_doc() == doc
    assert {"range", "vmin", "vmax", "cmap", "log"} <= set(events)
    again.update_from_doc({})                              # a project saved before colours
    assert again.to_doc() == ColourSettings().to_doc()


@pytest.mark.parametrize("doc, words", [
    ({"view": {"vmin": "low"}}, "3D view colours: colour setting 'vmin' is 'low'"),
    ({"heatmap": {"log": 1}}, "heatmap colours: colour setting 'log' is 1"),
    ({"heatmap": {"range": "fixed", "vmin": 2, "vmax": 1}}, "minimum (2) must be below"),
    ({"painting": "per pixel"}, "'painting' is 'per pixel'"),
    ({"shared": "yes"}, "'shared' is 'yes'"),
])
def test_bad_stored_settings_are_named_and_change_nothing(doc, words):
    s = ColourSettings()
    s.view.cmap = "cividis"
    before = s.to_doc()
    with pytest.raises(ColourError) as err:
        s.update_from_doc(doc, "study.maizeviz")
    assert str(err.value).startswith("study.maizeviz") and words in str(err.value)
    assert s.to_doc() == before


# ---------------------------------------------------------------------------- widgets
@pytest.fixture
def panel(qtbot):
    from maizeviz_app.panels.colour import ColourPanel

    p = ColourPanel(ColourSettings())
    qtbot.addWidget(p)
    p.show()
    return p


def test_panel_follows_the_settings_and_sets_them(panel, qtbot):
    s, ed = panel.settings, panel.view_editor
    s.view.cmap = "cividis"                                # settings -> widgets
    s.view.log = True
    assert ed.cmap.currentText() == "cividis" and ed.log.isChecked()
    ed.cmap.setCurrentText("greys")                        # widgets -> settings
    assert s.view.cmap == "greys"
    panel.shared.setChecked(True)
    assert s.shared
    panel.painting.setCurrentIndex(panel.painting.findData("leaves"))
    assert s.painting == "leaves"
    s.painting = "triangles"
    assert panel.painting.currentData() == "triangles"
    # every control has a tooltip and an accessible name
    for w in (ed.range, ed.vmin, ed.vmax, ed.clip, ed.cmap, ed.log, panel.painting,
              panel.shared):
        assert w.toolTip() and w.accessibleName()


def test_a_typed_range_starts_from_the_range_in_use_and_a_bad_one_waits(panel):
    s, ed = panel.settings, panel.heatmap_editor
    ed.show_limits(0.012, 0.34)                            # what the heatmap spans now
    assert not ed.vmin.isEnabled() and ed.vmin.value() == pytest.approx(0.012)
    ed.range.setCurrentIndex(ed.range.findData("fixed"))
    assert s.heatmap.range == "fixed"
    assert (s.heatmap.vmin, s.heatmap.vmax) == pytest.approx((0.012, 0.34))
    assert ed.vmin.isEnabled()
    ed.vmax.setValue(0.5)
    assert s.heatmap.vmax == pytest.approx(0.5)
    ed.vmin.setValue(0.8)                                  # above the max: said, not taken
    assert s.heatmap.vmin == pytest.approx(0.012)
    assert "must be below the maximum" in ed.note.text()


# ---------------------------------------------------------------------------- views
def test_3d_view_paints_light_values_with_the_scale(viewport, small_canopy):
    from maizeviz_app.options import LIGHT_CLASSES, STALK

    scale = ColourScale(cmap="inferno")
    viewport.set_colour_scale(scale)
    viewport.show_canopy(small_canopy)
    n = small_canopy.n_triangles
    values = np.linspace(0.0, 1.0, n)
    values[:10] = np.nan                                   # not traced
    viewport.set_light_values(values, "diffuse light per leaf area", "")
    viewport.colour_by("light")
    assert viewport.shown_limits == pytest.approx((values[10], 1.0), rel=1e-6)
    scale.update_from_doc({"range": "fixed", "vmin": 0.25, "vmax": 0.75, "cmap": "greys"})
    rgb = np.asarray(viewport.canopy_mesh.cell_data["light_rgb"])
    table = colour_table("greys")
    low = np.flatnonzero(values < 0.25)
    high = np.flatnonzero(values > 0.75)
    assert (rgb[low[low >= 10]] == table[0]).all() and (rgb[high] == table[-1]).all()
    stalk = tuple(int(c) for c in __import__("pyvista").Color(LIGHT_CLASSES[STALK][1]).int_rgb)
    assert (rgb[n:] == stalk).all()                        # stalks are never a light colour
    assert (rgb[:10] == (200, 200, 200)).all()
    text = viewport.key.text()
    assert "≤ 0.25" in text and "≥ 0.75" in text           # the colour bar says it clips
    assert viewport.shown_limits == (0.25, 0.75)


def test_heatmaps_take_the_scale_share_it_and_tell_the_value_under_the_mouse(small_canopy):
    from maizeviz_app.panels.heatmap_view import hover_text
    from maizeviz_app.plots import Look, heatmap_image

    from maizeviz.light.report.heatmap import transmission_map
    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light

    result = trace_light(small_canopy, LightRequest(Sun(30.0, 160.0),
                                                    Sampling((0.0, 60.0), 1.0), classes=True))
    low = transmission_map(result, 0.0).transmission
    high = transmission_map(result, 60.0).transmission
    settings = ColourSettings()
    own = heatmap_image(result, 0.0, look=Look.of(settings, {"sun": result}))
    assert own.limits == (np.nanmin(low), np.nanmax(low))   # auto: the map's own range
    settings.shared = True
    shared = Look.of(settings, {"sun": result})
    both = (min(np.nanmin(low), np.nanmin(high)), max(np.nanmax(low), np.nanmax(high)))
    assert heatmap_image(result, 0.0, look=shared).limits == both
    assert heatmap_image(result, 60.0, look=shared).limits == both
    # the core's look is still 0 to 1
    assert heatmap_image(result, 0.0).limits == (0.0, 1.0)
    # the value under a pixel is the bin's: the centre of every bin, read back
    left, top, right, bottom = own.box
    xe, ye = own.x_edges, own.y_edges
    for i in range(0, len(xe) - 1, 3):
        for j in range(0, len(ye) - 1, 2):
            x, y = (xe[i] + xe[i + 1]) / 2, (ye[j] + ye[j + 1]) / 2
            px = left + (x - xe[0]) / (xe[-1] - xe[0]) * (right - left)
            py = top + (ye[-1] - y) / (ye[-1] - ye[0]) * (bottom - top)
            got = own.value_at(px, py)
            assert got is not None and got[3] == own.rays[i, j]
            assert got[2] == pytest.approx(low[i, j], nan_ok=True)
            text = hover_text(own, px, py)
            assert (f"{low[i, j]:.3f}" in text) if own.rays[i, j] else ("no ray" in text)
    assert own.value_at(left - 3, top) is None and hover_text(own, 1, 1) == ""


def test_the_heatmap_pixels_follow_the_colour_map():
    from maizeviz_app.plots import Look

    from maizeviz.light.report.heatmap import heatmap_figure
    from maizeviz.light.results.maps import TransmissionMap

    t = np.full((4, 3), 0.5)
    tmap = TransmissionMap(10.0, np.arange(5.0) * 5, np.arange(4.0) * 5, t,
                           np.ones((4, 3), np.int64), 0.5)
    look = Look(ColourScale(range="fixed", vmin=0.0, vmax=1.0, cmap="greys"))
    fig = heatmap_figure(tmap, title="t", **look.colours(tmap))
    assert fig.axes[0].collections[0].cmap.name == CMAPS["greys"]
    assert fig.axes[0].collections[0].norm.vmin == 0.0


def test_a_project_keeps_the_colours(window, qtbot, tmp_path):
    w = window()
    qtbot.waitUntil(lambda: w.model.built is not None, timeout=120_000)
    w.model.colour.update_from_doc({"view": {"range": "percentile", "clip": 5.0,
                                             "cmap": "cividis"},
                                    "heatmap": {"log": True}, "shared": True})
    # the panel shows what the settings say
    assert w.colour_panel.view_editor.cmap.currentText() == "cividis"
    assert w.colour_panel.shared.isChecked()
    path = tmp_path / "colours.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=120_000):
        w.model.save_project(path)
    with zipfile.ZipFile(path) as zf:
        names = [n for n in zf.namelist() if n.endswith(".json")]
        docs = [json.loads(zf.read(n)) for n in names]
    assert any(d.get("settings", {}).get("view", {}).get("shared") for d in docs)
    w.model.colour.update_from_doc({})
    assert w.colour_panel.view_editor.cmap.currentText() == "inferno"
    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        w.open_project(path)
    assert w.model.colour.view.range == "percentile" and w.model.colour.view.clip == 5.0
    assert w.model.colour.view.cmap == "cividis" and w.model.colour.heatmap.log
    assert w.colour_panel.view_editor.cmap.currentText() == "cividis"


def test_the_window_redraws_its_heatmaps_when_their_colours_change(window, qtbot, small_points):
    from test_light_modes import compute, shown, small_light

    from maizeviz.light.report.heatmap import result_map

    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    heat = w.plots.heatmap
    qtbot.waitUntil(lambda: heat.heatmap is not None, timeout=120_000)
    result = w.model.runs.last.result
    maps = [result_map(result, float(h), "sun").transmission for h in result.heights_cm]
    own = maps[0]
    assert heat.heatmap.limits == (np.nanmin(own), np.nanmax(own))
    # typed: redrawn with the typed range, its note saying it
    w.model.colour.heatmap.update_from_doc({"range": "fixed", "vmin": 0.1, "vmax": 0.6,
                                            "cmap": "greys"})
    qtbot.waitUntil(lambda: heat.heatmap is not None and heat.heatmap.limits == (0.1, 0.6),
                    timeout=120_000)
    assert "0.1 to 0.6" in w.colour_panel.heatmap_editor.note.text()
    # one scale for every height: the same range at each, that of all the maps
    w.model.colour.heatmap.range = "auto"
    w.model.colour.shared = True
    both = (min(np.nanmin(m) for m in maps), max(np.nanmax(m) for m in maps))
    for index in range(len(maps)):
        w.plots.height_box.setCurrentIndex(index)
        want = float(result.heights_cm[index])
        qtbot.waitUntil(lambda want=want: heat.heatmap is not None and
                        heat.heatmap.height_cm == want, timeout=120_000)
        assert heat.heatmap.limits == pytest.approx(both)
