"""Panels as widgets over their models (no main window): canopy, light, figures, messages."""

import numpy as np
import pytest
from maizeviz_app.messages import user_message
from maizeviz_app.panels.canopy import CanopyPanel
from maizeviz_app.panels.light import (
    InputProblem,
    LightPanel,
    LightPlots,
    LightRuns,
    Run,
    parse_heights,
)

from maizeviz.errors import LeafError, MaizevizError, PointsFileError


def test_slider_asks_once_and_the_label_follows_the_view(qtbot):
    panel = CanopyPanel()
    qtbot.addWidget(panel)
    assert panel.level == "36" == panel.settings.canopy.level
    asked = []
    panel.settings.canopy.events.level.connect(lambda new, old: asked.append(new))
    for v in (0, 1, 2, 7):                                # moves within the debounce interval
        panel.slider.setValue(v)
    qtbot.waitUntil(lambda: bool(asked), timeout=2000)
    qtbot.wait(400)
    assert asked == ["4"] and panel.settings.canopy.level == "4"
    panel.settings.canopy.level = "K2"                    # set elsewhere: the slider follows
    assert panel.level == "K2" and asked == ["4", "K2"]
    qtbot.wait(400)
    assert asked == ["4", "K2"]                           # and does not ask again
    # the label names the level shown, not the one asked, until the canopy arrives
    assert panel.level_label.text() == "no canopy yet"
    assert "asked" in panel.asked_label.text()
    columns = [("level", "level"), ("triangles", "triangles")]
    panel.show_built("4", columns, {"level": "4 triangles", "triangles": "4,000"})
    assert panel.level_label.text() == "showing: at most 4 triangles per leaf"
    assert panel.asked_label.text() == ""
    assert panel.table.rowCount() == 1 and panel.table.item(0, 0).text() == "4 triangles"
    panel.show_built("K4", columns, {"level": "K=4", "triangles": "2,678,400"})
    panel.show_built("4", columns, {"level": "4 triangles", "triangles": "4,000"})
    assert panel.table.rowCount() == 2                    # one row per level, updated in place


def test_heights_are_read_or_named():
    assert parse_heights("0, 50,100 ; 150cm") == (0.0, 50.0, 100.0, 150.0)
    with pytest.raises(InputProblem, match="'fifty' is not a number of centimetres") as err:
        parse_heights("0, fifty")
    assert err.value.quantity == "heights"
    with pytest.raises(InputProblem, match="0 cm or more"):
        parse_heights("-5")
    with pytest.raises(InputProblem, match="at least one height"):
        parse_heights(" , ")


@pytest.mark.parametrize("typed", ["0,,50", "0, 50,", ",0", "0;;50", "0,,"])
def test_an_empty_height_is_refused_in_the_command_lines_words(typed):
    """The app decides as ``maizeviz light --heights`` does: an empty item is a slip, named."""
    from maizeviz.cli.common import floats

    with pytest.raises(InputProblem, match="is empty in") as app:
        parse_heights(typed)
    assert app.value.quantity == "heights"
    if ";" not in typed:                          # the command line takes commas only
        with pytest.raises(MaizevizError) as cli:
            floats(typed, "heights", "heights")
        assert str(app.value) == str(cli.value)


def test_light_panel_request_and_problem_marking(qtbot):
    panel = LightPanel()
    qtbot.addWidget(panel)
    req = panel.settings.sun_request()
    assert req.classes and req.heights_cm == (0, 50, 100, 150, 200, 225)
    tip = panel.heights.toolTip()
    panel.heights.setText("0, abc")
    assert panel.settings.sampling.heights == "0, abc"    # the field is the setting
    with pytest.raises(InputProblem) as err:
        panel.settings.sun_request()
    assert panel.point_at(err.value.quantity, str(err.value))
    assert "d0342c" in panel.heights.styleSheet()
    assert "abc" in panel.heights.toolTip()
    qtbot.keyClicks(panel.heights, "1")                   # editing clears the mark
    assert panel.heights.styleSheet() == "" and panel.heights.toolTip() == tip
    assert not panel.point_at("no such field", "x")
    # settings read back into other panels' settings show in their fields
    panel.zenith.setValue(41.5)
    panel.mode_buttons["day"].click()
    panel.band.setCurrentIndex(1)                         # NIR: its optics follow
    assert panel.settings.optics.band == "nir" and panel.reflectance.value() > 0.3
    doc = panel.settings.light_doc()
    other = LightPanel()
    qtbot.addWidget(other)
    other.settings.apply_light_doc(doc)
    assert other.settings.light_doc() == doc
    assert other.zenith.value() == 41.5 and other.mode == "day"
    assert other.pages.currentIndex() == 1 and other.reflectance.value() == \
        panel.reflectance.value()


class FakeResult:
    """What LightRuns reads from a light result."""

    def __init__(self, t, heights=(0.0, 50.0, 100.0, 150.0, 200.0, 225.0, 240.0, 250.0)):
        self.heights_cm = np.array(heights)
        self.transmission = np.array(t)


def test_results_table_shows_every_height_without_scrolling(qtbot):
    panel = LightPanel()
    qtbot.addWidget(panel)
    panel.resize(380, 900)
    panel.show()
    runs = LightRuns()
    t = np.linspace(0.05, 1, 8)
    assert not runs.add(Run("36 triangles", (1, "36 triangles"), FakeResult(t)), ("a",))
    assert not runs.add(Run("K=4", (1, "K=4"), FakeResult(t * 0.99)), ("a",))
    panel.show_runs(runs, "info")
    qtbot.wait(50)
    table = panel.table
    assert table.rowCount() == 8 and table.columnCount() == 3
    # levels fine to coarse, whatever order they were traced in
    assert [table.horizontalHeaderItem(c).text() for c in range(3)] == \
        ["height cm", "K=4", "36 triangles"]
    view = table.viewport().rect()
    for r in range(8):
        assert view.contains(table.visualItemRect(table.item(r, 1))), f"row {r} hidden"
    assert not table.verticalScrollBar().isVisible()
    # other settings start a new comparison
    assert runs.add(Run("4 triangles", (1, "4 triangles"), FakeResult(t)), ("b",))
    assert list(runs.runs) == ["4 triangles"]


def test_plots_switch_heights(qtbot):
    plots = LightPlots()
    qtbot.addWidget(plots)
    images = [(h, np.full((40, 60, 4), v, np.uint8)) for h, v in ((0.0, 10), (50.0, 200))]
    plots.set_heatmaps(images)
    assert plots.height_box.count() == 2 and plots.shown_height == 0.0
    assert plots.heatmap.image().pixel(5, 5) & 0xFF == 10
    plots.height_box.setCurrentIndex(1)
    assert plots.shown_height == 50.0 and plots.heatmap.image().pixel(5, 5) & 0xFF == 200
    plots.set_transmission(np.zeros((30, 30, 4), np.uint8))
    assert plots.transmission.image() is not None


def test_figures_are_the_core_heatmap_and_a_level_comparison(small_canopy):
    from maizeviz_app.plots import Curve, heatmap_images, rgba, transmission_figure

    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light

    result = trace_light(small_canopy, LightRequest(Sun(22.3, 167.0), Sampling((0.0, 100.0), 0.5),
                                                    classes=True))
    maps = heatmap_images(result, all_heights=True)
    assert heatmap_images(result, first=1)[0][1] is None      # drawn when asked for
    assert [h for h, _ in maps] == [0.0, 100.0]
    assert all(m.rgba.ndim == 3 and m.rgba.shape[2] == 4 and m.rgba.shape[1] > 300
               for _, m in maps)
    fig = transmission_figure([Curve("K=4", (0.0, 100.0), (0.1, 0.5)),
                               Curve("36 triangles", (0.0, 100.0), (0.11, 0.5))])
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == \
        ["K=4", "36 triangles"]
    assert rgba(fig).shape[2] == 4


@pytest.mark.parametrize("exc, doing, must, must_not", [
    (PointsFileError("/data/b.csv: missing column(s) x, y"), "open points",
     "missing column(s) x, y. Choose a points CSV", "PointsFileError"),
    (ValueError("could not convert string to float: 'abc'"), "light",
     "light failed because of an internal error", "ValueError"),
    (MaizevizError("the ray density must be > 0 rays per cm2", quantity="density"), "light",
     "the ray density must be > 0", "MaizevizError"),
    (LeafError(1, 2, "row 3 has 4 points"), "build", "plant 1, leaf 2: row 3", "LeafError"),
    (FileNotFoundError(2, "No such file", "/x/y.csv"), "open points", "/x/y.csv: no such file",
     "FileNotFoundError"),
    (MemoryError(), "light", "not enough memory", "MemoryError"),
])
def test_messages_are_for_people(exc, doing, must, must_not):
    text = user_message(exc, doing)
    assert must in text and must_not not in text and "\n" not in text
    assert "maizeviz.errors" not in text and "Traceback" not in text
